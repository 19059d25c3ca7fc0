"""The contract test kit an adapter author runs with pytest: the checks `remap check` runs
(`core.host.check`), one test each, and a few that need pytest's fixtures or a second instance. The
reference images live in `core.host.analytic` (re-exported here, where tests have always found them)."""

from __future__ import annotations

from typing import Any

import numpy as np

from . import check
from .analytic import (
    box_filtered,
    box_filtered_lambert,
    SphereHits,
    analytic_glass,
    analytic_lambert,
    analytic_mirror,
    environment_irradiance,
    point_light_irradiance,
    scene_for,
    sphere_hits,
)
from ..data.metrics import relative_rmse
from ..data.scene import LightType, ProbeScene


class AdapterContract:
    """Contract tests any adapter author runs against their adapter (pytest).

    Subclass it in a test module, named ``Test...``, and set the class attributes::

        from brdfremap.core.testing import AdapterContract

        class TestMyRenderer(AdapterContract):
            factory = MyAdapter                       # the registered class
            calibration = ("diffuse", {"reflectance": 0.8})   # a white Lambertian, albedo 0.8

    The conventions are `remap check`'s own checks (`core.host.check`), a test each: images (shape,
    float, finite, lit, black background), units (the white Lambertian against the analytic
    radiance), orientation, determinism, seeds (two seeds, two images, unless the renderer has no
    sampling noise), lobes, precision and light through a glass. Besides them,
    what needs pytest: the models and their derived quantities declared, the optional neutral
    reading naming only model parameters, one seed giving the same image in a second instance of
    the adapter, and each light type it declares against the analytic radiance.
    """

    factory: Any = None
    calibration: tuple[str, dict] | None = None
    """Default: the adapter's own (`Adapter.calibration`)."""
    scene = ProbeScene(resolution=48, spp=16)

    @classmethod
    def setup_class(cls):
        import pytest

        if cls.factory is None:
            pytest.skip("set `factory` to the adapter class")
        reason = cls.factory.unavailable_reason()
        if reason:
            pytest.skip(f"{cls.factory.name} unavailable: {reason}")
        cls.adapter = cls.factory()

    @classmethod
    def teardown_class(cls):
        adapter = getattr(cls, "adapter", None)
        if adapter is not None:
            adapter.close()

    def _params(self, model: str, **given):
        return self.adapter.models[model].complete(given)

    def _render(self, model, params, scene, lobe=None):
        """A render of a model named as the checks name it (the adapter is passed its object)."""
        return self.adapter.render(self.adapter.models[model], params, scene, lobe)

    def _white(self) -> tuple[str, dict] | None:
        given = self.calibration or getattr(self.factory, "calibration", None)
        return None if given is None else (given[0], self._params(given[0], **given[1]))

    def _glass(self) -> tuple[str, dict] | None:
        given = getattr(self.factory, "glasses", {}).get("smooth")
        return None if given is None else (given[0], self._params(given[0], **given[1]))

    @staticmethod
    def _holds(row: check.Row) -> None:
        """A check's row as a test's outcome: passed, failed with its detail and fix, or skipped."""
        import pytest

        if row.passed is None:
            pytest.skip(f"{row.name}: {row.detail}")
        if row.by_design:
            pytest.xfail(f"{row.name}: {row.detail}: {row.fix}")
        assert row.passed, f"{row.name}: {row.detail}" + (f"; fix: {row.fix}" if row.fix else "")

    def test_images(self):
        environment = LightType.ENVIRONMENT in self.factory.light_types
        for model, spec in self.adapter.models.items():  # what `render` returns, before `check` reads it
            img = self.adapter.render(spec, self._params(model), scene_for(spec, self.scene, environment))
            assert isinstance(img, np.ndarray) and img.dtype == np.float32, f"{model}: {type(img)} {img.dtype}"
        self._holds(check.images(self._render, self.adapter.models, environment))

    def test_units(self):
        self._holds(check.calibration(self._render, self._white()))

    def test_orientation(self):
        self._holds(check.orientation(self._render, self._white()))

    def test_encoding(self):
        self._holds(check.encoding(self._render, self._white()))

    def test_sampling(self):
        self._holds(check.sampling(self._render, self._white()))

    def test_environment(self):
        self._holds(check.lit_by_environment(self._render, self._white(),
                                             LightType.ENVIRONMENT in self.factory.light_types))

    def test_glossy(self):
        given = getattr(self.factory, "mirror", None)
        mirror = None if given is None else (given[0], self._params(given[0], **given[1]))
        self._holds(check.glossy(self._render, mirror, LightType.ENVIRONMENT in self.factory.light_types))

    def test_determinism(self):
        self._holds(check.determinism(self._render, self.adapter.models, self._white()))

    def test_seed(self):
        self._holds(check.seed(self._render, self._white(), LightType.ENVIRONMENT in self.factory.light_types))

    def test_lobes(self):
        self._holds(check.lobes(self._render, self.adapter.models))

    def test_precision(self):
        self._holds(check.precision(self._render, self._white()))

    def test_transmission(self):
        self._holds(check.transmission(self._render, self.adapter.models, self._glass(),
                                       LightType.ENVIRONMENT in self.factory.light_types,
                                       getattr(self.factory, "transmission_limit", "")))

    def test_models_are_described(self):
        assert self.adapter.models, "the adapter declares no models"
        for name, spec in self.adapter.models.items():
            assert spec.name == name
            spec.complete({})  # defaults are valid

    def test_derived_quantities_are_declared(self):
        """What ``Model.derive`` returns for a model's defaults is declared in its ``derived``
        (an experiment's plot is checked against them before any render)."""
        for name, spec in self.adapter.models.items():
            got = set(spec.derive(spec.complete({})))
            assert got <= set(spec.derived), (name, sorted(got - set(spec.derived)))

    def test_neutral_reading_names_only_the_models_parameters(self):
        """Optional: a model without ``appearance``/``from_appearance`` passes trivially. Each
        reading of a model's defaults is an Appearance; each conversion into a model names only
        its parameters, and they complete (validate) once clipped to their bounds."""
        from ..data.appearance import Appearance

        looks = [Appearance(kind="conductor", alpha=0.1, specular=(0.9, 0.6, 0.3)),
                 Appearance(kind="dielectric", alpha=0.2, specular=(0.04,) * 3, diffuse=(0.6, 0.1, 0.05), ior=1.5),
                 Appearance(kind="dielectric", diffuse=(0.8, 0.8, 0.8))]
        for name, spec in self.adapter.models.items():
            look = spec.appearance(spec.complete({}))
            assert look is None or isinstance(look, Appearance), name
            for a in looks:
                conv = spec.from_appearance(a, spec.complete({}))
                assert set(conv) <= set(spec.names), (name, set(conv) - set(spec.names))
                spec.complete({k: spec.param(k).clip(v) for k, v in conv.items()})

    def test_one_seed_gives_one_image_in_a_second_instance(self):
        """Repeatability across processes, not only within one (an adapter may cache images)."""
        other = self.factory()
        try:
            for model, spec in self.adapter.models.items():
                p = self._params(model)
                a = self.adapter.render(spec, p, self.scene)
                c = other.render(other.models[model], p, self.scene)
                assert np.array_equal(a, c), f"{model}: two renders with one seed differ"
        finally:
            other.close()

    light_scenes = {
        "two point lights": (ProbeScene.model_validate(
            {"lights": [{}, {"theta": 100.0, "phi": 10.0, "intensity": 15.0}], "resolution": 48, "spp": 64}), 0.01),
        "constant environment": (ProbeScene.model_validate(
            {"lights": [{"type": "environment", "map": "constant", "scale": 0.35}], "resolution": 48, "spp": 256}),
            0.01),
        "studio environment": (ProbeScene.model_validate(
            {"lights": [{"type": "environment", "map": "studio"}], "resolution": 48, "spp": 256}), 0.02),
    }
    """Scenes of each light type with the white diffuse sphere's tolerance against the analytic
    radiance: point lights add up; a constant environment gives radiance albedo x L; the
    asymmetric studio pins the map's orientation (its key light upper left in front)."""

    def test_each_light_type_matches_the_analytic_radiance(self):
        import pytest

        white = self._white()
        if white is None:
            pytest.skip("no calibration material given")
        for name, (scene, tolerance) in self.light_scenes.items():
            if scene.light_types() - set(self.factory.light_types):
                assert self.factory.scene_problem(scene), f"{name}: an undeclared light type is not refused"
            if self.factory.scene_problem(scene):
                continue  # refused before any render, with the reason
            img = self._render(*white, scene)
            hits = sphere_hits(scene)
            err = relative_rmse(analytic_lambert(scene, 0.8)[hits.interior], img[hits.interior])
            assert err < tolerance, f"{name}: white diffuse sphere {err:.2%} from the analytic radiance"
            assert img[0, 0].max() == 0 and img[-1, -1].max() == 0, f"{name}: background is not black"
