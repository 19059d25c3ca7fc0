"""Reference geometry and images for testing adapters (numpy only, no renderer).

``analytic_lambert`` is the ground truth every adapter's white diffuse sphere must match:
it is what "the same physical units" means (radiant intensity in W/sr, radiance out)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from .metrics import relative_rmse
from .scene import EnvironmentLight, PointLight, ProbeScene


@dataclass
class SphereHits:
    mask: np.ndarray  # H x W bool: the pixel centre's ray hits the sphere
    interior: np.ndarray  # H x W bool: the whole pixel footprint hits (no silhouette blending)
    position: np.ndarray  # H x W x 3
    normal: np.ndarray  # H x W x 3
    view: np.ndarray  # H x W x 3, unit vector from the surface to the camera


def _rays(scene: ProbeScene, offsets: tuple[float, float]):
    cam = scene.camera
    eye = np.array(cam.position, dtype=np.float64)
    fwd = np.array(cam.target) - eye
    fwd /= np.linalg.norm(fwd)
    right = np.cross(fwd, np.array(cam.up, dtype=np.float64))
    right /= np.linalg.norm(right)
    up = np.cross(right, fwd)
    n = scene.resolution
    half = math.tan(math.radians(cam.fov) / 2)
    idx = np.arange(n, dtype=np.float64)
    x = ((idx + offsets[0]) / n * 2 - 1) * half
    y = (1 - (idx + offsets[1]) / n * 2) * half
    xx, yy = np.meshgrid(x, y)
    d = fwd + xx[..., None] * right + yy[..., None] * up
    return eye, d / np.linalg.norm(d, axis=-1, keepdims=True)


def _hit(scene: ProbeScene, eye, d):
    c = np.array(scene.sphere.center, dtype=np.float64)
    oc = eye - c
    b = d @ oc
    disc = b * b - (oc @ oc - scene.sphere.radius**2)
    mask = disc > 0
    t = -b - np.sqrt(np.where(mask, disc, 0.0))
    return mask & (t > 0), t


def sphere_hits(scene: ProbeScene) -> SphereHits:
    eye, d = _rays(scene, (0.5, 0.5))
    mask, t = _hit(scene, eye, d)
    interior = mask.copy()
    for off in ((0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)):
        interior &= _hit(scene, *_rays(scene, off))[0]
    pos = eye + t[..., None] * d
    normal = (pos - np.array(scene.sphere.center)) / scene.sphere.radius
    return SphereHits(mask, interior, pos, normal, -d)


def point_light_irradiance(scene: ProbeScene, hits: SphereHits, light: PointLight | None = None
                           ) -> tuple[np.ndarray, np.ndarray]:
    """(E, l): irradiance I cos(theta) / r^2 (W/m^2, zero where unlit) and the unit light vector,
    of ``light`` (default: the scene's first point light)."""
    light = light or scene.point_lights[0]
    lp = np.array(light.position, dtype=np.float64)
    to_l = lp - hits.position
    dist2 = (to_l**2).sum(-1)
    l = to_l / np.sqrt(dist2)[..., None]
    cos = np.clip((hits.normal * l).sum(-1), 0.0, None)
    return np.where(hits.mask, light.intensity * cos / dist2, 0.0), l


def scene_for(spec, scene: ProbeScene, environment_ok: bool = True, params: dict | None = None) -> ProbeScene:
    """The scene a model is seen in: under the studio environment for a smooth one (`ModelSpec.is_smooth`
    with ``params``, else its defaults: a point light shows in a mirror as a point at most), where
    the adapter renders one."""
    if spec.is_smooth(params if params is not None else spec.complete({})) and environment_ok:
        return scene.model_copy(update={"lights": [EnvironmentLight(type="environment", map="studio")]})
    return scene


def environment_irradiance(radiance: np.ndarray, normals: np.ndarray, width: int = 128) -> np.ndarray:
    """Irradiance (…, 3) an unoccluded surface of these normals receives from an equirectangular
    map (H x W x 3, `core.environment`'s orientation), integrated over the map box-averaged
    down to ``width`` columns: a few tenths of a percent from the exact integral for smooth maps."""
    from .environment import pixel_directions

    h, w = radiance.shape[:2]
    f = max(1, w // width)
    small = radiance[: h // f * f, : w // f * f].reshape(h // f, f, w // f, f, 3).mean(axis=(1, 3))
    hh, ww = small.shape[:2]
    d = pixel_directions(ww, hh).reshape(-1, 3)
    theta = (np.arange(hh) + 0.5) / hh * math.pi
    solid = np.repeat(np.sin(theta) * (math.pi / hh) * (2 * math.pi / ww), ww)
    weighted = small.reshape(-1, 3) * solid[:, None]
    n = normals.reshape(-1, 3)
    out = np.zeros((n.shape[0], 3))
    for i in range(0, n.shape[0], 4096):
        cos = np.clip(n[i:i + 4096] @ d.T, 0.0, None)
        out[i:i + 4096] = cos @ weighted
    return out.reshape(*normals.shape[:-1], 3)


def analytic_lambert(scene: ProbeScene, albedo: float | tuple[float, float, float] = 0.8) -> np.ndarray:
    """Radiance image of a Lambertian sphere under the scene's lights: albedo / pi * E. Silhouette
    pixels are point-sampled here but box-filtered by renderers: compare on ``sphere_hits().interior``."""
    from .environment import radiance

    hits = sphere_hits(scene)
    e = sum(point_light_irradiance(scene, hits, light)[0] for light in scene.point_lights)
    e = np.broadcast_to(np.asarray(e, dtype=np.float64)[..., None], (*hits.mask.shape, 3))
    env = scene.environment
    if env is not None:
        e = e + np.where(hits.mask[..., None],
                         environment_irradiance(radiance(env.map, env.scale, env.rotation), hits.normal), 0.0)
    rho = np.broadcast_to(np.asarray(albedo, dtype=np.float64), (3,))
    return (e * rho / math.pi).astype(np.float32)


def _fresnel(cos_i: np.ndarray, eta: float) -> np.ndarray:
    """Unpolarised Fresnel reflectance of a smooth dielectric boundary (relative IOR ``eta``, light
    arriving from the side of index 1 at cosine ``cos_i``)."""
    sin_t2 = (1.0 - cos_i ** 2) / eta ** 2
    cos_t = np.sqrt(np.clip(1.0 - sin_t2, 0.0, None))
    rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
    return 0.5 * (rs ** 2 + rp ** 2)


def _refract(d: np.ndarray, n: np.ndarray, eta: float) -> np.ndarray:
    """Direction ``d`` refracted through a boundary of normal ``n`` (facing ``d``'s origin) into
    relative index ``eta``; no total internal reflection (none happens inside a sphere)."""
    cos_i = -(d * n).sum(-1, keepdims=True)
    k = 1.0 - (1.0 - cos_i ** 2) / eta ** 2
    return d / eta + (cos_i / eta - np.sqrt(np.clip(k, 0.0, None))) * n


def analytic_glass(scene: ProbeScene, ior: float = 1.5, supersample: int = 3, bounces: int = 8) -> np.ndarray:
    """Radiance image of a perfectly smooth, clear glass sphere (relative IOR ``ior``) under the
    scene's environment: its Fresnel reflection, and the light through it after 0 to ``bounces``
    internal reflections (in a sphere every one meets the boundary at the entry angle: the same
    Fresnel, no total internal reflection). Point lights show in it as points: they add nothing.
    Pixels are averaged over ``supersample``² rays (a renderer's box filter)."""
    from .environment import lookup, radiance

    env = scene.environment
    out = np.zeros((scene.resolution, scene.resolution, 3))
    if env is None:
        return out.astype(np.float32)
    px = radiance(env.map, env.scale, env.rotation)
    c = np.array(scene.sphere.center, dtype=np.float64)
    offsets = [(i + 0.5) / supersample for i in range(supersample)]
    for ox in offsets:
        for oy in offsets:
            eye, d = _rays(scene, (ox, oy))
            mask, t = _hit(scene, eye, d)
            # Rays that miss follow one that hits the sphere's front head-on (then masked out).
            d = np.where(mask[..., None], d, np.array([0.0, 0.0, -1.0]))
            p = np.where(mask[..., None], eye + t[..., None] * d, c + [0.0, 0.0, scene.sphere.radius])
            n = (p - c) / scene.sphere.radius
            cos_i = np.clip(-(d * n).sum(-1), 0.0, 1.0)
            f = _fresnel(cos_i, ior)[..., None]
            colour = f * lookup(px, d + 2.0 * cos_i[..., None] * n)
            inside, weight = _refract(d, n, ior), 1.0 - f
            for _ in range(bounces + 1):
                # The chord to the far side: from p along the inside direction, length -2 (inside . n_p).
                p = p - 2.0 * ((inside * (p - c)).sum(-1, keepdims=True) / scene.sphere.radius) * \
                    scene.sphere.radius * inside
                n_out = (p - c) / scene.sphere.radius
                colour += weight * (1.0 - f) * lookup(px, _refract(inside, -n_out, 1.0 / ior))
                inside = inside - 2.0 * (inside * n_out).sum(-1, keepdims=True) * n_out
                weight = weight * f
            out += np.where(mask[..., None], colour, 0.0)
    return (out / supersample ** 2).astype(np.float32)


# -- the adapter contract test kit ------------------------------------------------------

class AdapterContract:
    """Contract tests any adapter author runs against their adapter (pytest).

    Subclass it in a test module, named ``Test...``, and set the class attributes::

        from brdfremap.core.testing import AdapterContract

        class TestMyRenderer(AdapterContract):
            factory = MyAdapter                       # the registered class
            calibration = ("diffuse", {"reflectance": 0.8})   # a white Lambertian, albedo 0.8

    The checks: image shape, dtype, finiteness and black background for every model; the
    optional neutral reading (``appearance``/``from_appearance``) naming only model parameters;
    bit-identical renders for a fixed seed; lobes that sum to the full image; and the white
    diffuse sphere against the analytic radiance (same physical units as every adapter).
    """

    factory: Any = None
    calibration: tuple[str, dict] | None = None
    scene = ProbeScene(resolution=48, spp=16)
    calibration_scene = ProbeScene(resolution=64, spp=64)
    calibration_tolerance = 0.01
    lobe_tolerance = 1e-4

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

    def test_models_are_described(self):
        assert self.adapter.models, "the adapter declares no models"
        for name, spec in self.adapter.models.items():
            assert spec.name == name
            spec.complete({})  # defaults are valid

    def test_derived_quantities_are_declared(self):
        """What ``derived`` returns for a model's defaults is declared in its ``ModelSpec.derived``
        (an experiment's plot is checked against them before any render)."""
        for name, spec in self.adapter.models.items():
            got = set(self.adapter.derived(name, spec.complete({})))
            assert got <= set(spec.derived), (name, sorted(got - set(spec.derived)))

    def test_neutral_reading_names_only_the_models_parameters(self):
        """Optional: an adapter without ``appearance``/``from_appearance`` passes trivially. Each
        reading of a model's defaults is an Appearance; each conversion into a model names only
        its parameters, and they complete (validate) once clipped to their bounds."""
        from .appearance import Appearance

        looks = [Appearance(kind="conductor", alpha=0.1, specular=(0.9, 0.6, 0.3)),
                 Appearance(kind="dielectric", alpha=0.2, specular=(0.04,) * 3, diffuse=(0.6, 0.1, 0.05), ior=1.5),
                 Appearance(kind="dielectric", diffuse=(0.8, 0.8, 0.8))]
        for name, spec in self.adapter.models.items():
            look = self.adapter.appearance(name, spec.complete({}))
            assert look is None or isinstance(look, Appearance), name
            for a in looks:
                conv = self.adapter.from_appearance(name, a, spec.complete({}))
                assert set(conv) <= set(spec.names), (name, set(conv) - set(spec.names))
                spec.complete({k: spec.param(k).clip(v) for k, v in conv.items()})

    def _scene_for(self, model: str) -> ProbeScene:
        return scene_for(self.adapter.models[model], self.scene, "environment" in self.adapter.light_types)

    def test_render_shape_dtype_finite_black_background(self):
        n = self.scene.resolution
        for model in self.adapter.models:
            img = self.adapter.render(model, self._params(model), self._scene_for(model))
            assert isinstance(img, np.ndarray), f"{model}: not a numpy array"
            assert img.shape == (n, n, 3), f"{model}: shape {img.shape}, expected {(n, n, 3)}"
            assert img.dtype == np.float32, f"{model}: dtype {img.dtype}, expected float32"
            assert np.isfinite(img).all(), f"{model}: NaN or Inf pixels"
            assert img.max() > 0, f"{model}: black image"
            assert img[0, 0].max() == 0 and img[-1, -1].max() == 0, f"{model}: background is not black"

    def test_fixed_seed_is_deterministic(self):
        # A second adapter instance: an adapter may cache images, and repeatability must
        # hold across processes, not only within one.
        other = self.factory()
        try:
            for model in self.adapter.models:
                p = self._params(model)
                a = self.adapter.render(model, p, self.scene)
                c = other.render(model, p, self.scene)
                assert np.array_equal(a, c), f"{model}: two renders with one seed differ"
        finally:
            other.close()

    def test_lobes_sum_to_the_full_image(self):
        for model, spec in self.adapter.models.items():
            if not spec.has_lobes or any(lobe.empty for lobe in spec.lobes.values()):
                continue
            p = self._params(model)
            full = self.adapter.render(model, p, self.scene)
            parts = sum(self.adapter.render(model, p, self.scene, lobe) for lobe in ("diffuse", "specular"))
            err = relative_rmse(full, parts)
            assert err < self.lobe_tolerance, f"{model}: diffuse + specular differs from full by {err:.2e}"

    def test_white_diffuse_sphere_matches_the_analytic_radiance(self):
        import pytest

        if self.calibration is None:
            pytest.skip("no calibration material given")
        model, given = self.calibration
        scene = self.calibration_scene
        img = self.adapter.render(model, self._params(model, **given), scene)
        inner = sphere_hits(scene).interior
        err = relative_rmse(analytic_lambert(scene, 0.8)[inner], img[inner])
        assert err < self.calibration_tolerance, (
            f"white diffuse sphere differs from the analytic radiance by {err:.2%}: check the light's "
            "units (radiant intensity in W/sr), the camera's field of view and the sphere's size")

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

        if self.calibration is None:
            pytest.skip("no calibration material given")
        model, given = self.calibration
        for name, (scene, tolerance) in self.light_scenes.items():
            if scene.light_types() - set(self.factory.light_types):
                assert self.factory.scene_problem(scene), f"{name}: an undeclared light type is not refused"
            if self.factory.scene_problem(scene):
                continue  # refused before any render, with the reason
            img = self.adapter.render(model, self._params(model, **given), scene)
            hits = sphere_hits(scene)
            err = relative_rmse(analytic_lambert(scene, 0.8)[hits.interior], img[hits.interior])
            assert err < tolerance, f"{name}: white diffuse sphere {err:.2%} from the analytic radiance"
            assert img[0, 0].max() == 0 and img[-1, -1].max() == 0, f"{name}: background is not black"
