"""A renderer's model is one object (issue 46): the adapters hold `Model`s, the protocol passes the
object, and the adapters do not dispatch on a model's name."""

import re
from pathlib import Path

import pytest

from brdfremap.core.data.scene import ProbeScene
from brdfremap.core.data.schemas import Material, ModelSpec, ParamSpec
from brdfremap.core.host.model import Model
from brdfremap.core.host.plugins import collect_adapters
from brdfremap.core.job.execute import AdapterPool, execute
from brdfremap.core.job.job import Job, Target, resolve
from brdfremap.core.data.settings import Settings
from brdfremap_example.adapter import ToyAdapter
from helpers import registry_of

ROOT = Path(__file__).resolve().parents[2]
NAME_DISPATCH = re.compile(r"""model *(==|!=|in) *[("']""")
ALLOWED = {"adapters/mitsuba/reader.py": "a blendbsdf's file nests two BSDFs, read slot by slot"}
"""The places an adapter may still compare a model's name, each with why."""


@pytest.mark.parametrize("adapter", ["mitsuba", "cycles", "threejs"])
def test_every_shipped_model_is_one_object_of_its_adapter(adapter):
    models = collect_adapters().get(adapter).models
    assert models and all(isinstance(m, Model) and m.name == name for name, m in models.items())
    assert len({type(m) for m in models.values()}) > 1 or adapter == "threejs"  # a class per kind of model


def test_no_adapter_dispatches_on_a_models_name():
    found = {str(p.relative_to(ROOT)): [n for n, line in enumerate(p.read_text().splitlines(), 1)
                                        if NAME_DISPATCH.search(line)]
             for p in (ROOT / "adapters").rglob("*.py") if "node_modules" not in p.parts}
    found = {k: v for k, v in found.items() if v}
    assert set(found) <= set(ALLOWED) and sum(map(len, found.values())) <= 5, found


class _Recording(ToyAdapter):
    seen: list = []

    def render(self, model, params, scene, lobe=None):
        self.seen.append(model)
        return super().render(model, params, scene, lobe)


def test_the_job_passes_the_model_object_to_the_adapter():
    reg = registry_of("toy", _Recording)
    src = Material(adapter="toy", model="toy", params={"diffuse": [0.6, 0.3, 0.1], "specular": 0.8, "alpha": 0.15})
    job = Job(source=src, target=Target(adapter="toy", model="toy"), scene=ProbeScene(resolution=32),
              settings=Settings(scheme="one", coarse=0, validation="none"), label="m.yaml", fit_same_model=True)
    resolved = resolve(job, reg)
    assert resolved.look is not None and resolved.look.alpha == pytest.approx(0.15)  # read once, from the model
    pool = AdapterPool(reg)
    try:
        execute(resolved, pool)
    finally:
        pool.close()
    assert _Recording.seen and all(m is resolved.target_spec for m in _Recording.seen)


def test_a_plugin_of_plain_modelspecs_is_unavailable_with_one_line_saying_why():
    class Old(ToyAdapter):
        name = "old"
        models = {"m": ModelSpec(name="m", parameters=(ParamSpec(name="a", kind="scalar", default=0.5),))}

    why = registry_of("old", Old).get("old").unavailable_reason()
    assert "'m' is a plain ModelSpec" in why and "brdfremap.core.Model" in why and "\n" not in why


def test_a_plugins_own_exception_is_one_line_naming_the_adapter():
    from brdfremap.core.data.errors import RenderError
    from brdfremap.core.job.renders import CachedRenderer

    class Broken(ToyAdapter):
        def render(self, model, params, scene, lobe=None):
            raise RuntimeError("the renderer's own failure\nand its second line")

    adapter = Broken()
    r = CachedRenderer(adapter, "broken", adapter.models["toy"], ProbeScene(resolution=16))
    with pytest.raises(RenderError) as exc:
        r(adapter.models["toy"].complete({}))
    assert "adapter 'broken'" in str(exc.value) and "RuntimeError: the renderer's own failure" in str(exc.value)
    assert "\n" not in str(exc.value)


def test_a_worker_with_other_renderers_than_the_job_was_planned_with_refuses_it(monkeypatch):
    from brdfremap.core.data.errors import RenderError
    from brdfremap.core.job import execute as ex

    class Other(ToyAdapter):
        version = "2-other-machine"

    src = Material(adapter="toy", model="toy", params={"diffuse": [0.6, 0.3, 0.1]})
    job = Job(source=src, target=Target(adapter="toy", model="toy"), scene=ProbeScene(resolution=16),
              settings=Settings(validation="none"), label="m.yaml")
    resolved = resolve(job, registry_of("toy", ToyAdapter))
    monkeypatch.setattr(ex, "_worker_adapters", lambda files: AdapterPool(registry_of("toy", Other)))
    with pytest.raises(RenderError, match="other renderers than the job was planned with"):
        ex.run_in_worker(resolved)


def test_a_library_from_a_plugin_of_plain_modelspecs_fails_its_materials_in_one_line():
    from brdfremap.core.data.errors import ConfigError
    from brdfremap.core.job.job import model_of

    class Old(ToyAdapter):
        name = "old"
        models = {"m": ModelSpec(name="m", parameters=(ParamSpec(name="a", kind="scalar", default=0.5),))}

    with pytest.raises(ConfigError, match="is a plain ModelSpec"):
        model_of(registry_of("old", Old), "old", "m", "lib.xml", "wood: ")


def test_principled_from_a_reading_at_ior_1_leaves_the_level_alone():
    """An IOR of 1 (a held value a same-model remap carries, or a --fix) has no F0 to scale: no
    division by zero (the corpus's StandardSurface documents hit it)."""
    from brdfremap.adapters.cycles.models import MODELS

    p = MODELS["principled"]
    base = p.complete({"ior": 1.0})
    out = p.from_appearance(p.appearance(p.complete({"base_color": (0.5, 0.5, 0.5)})), base)
    assert "specular_ior_level" not in out and out["metallic"] == 0.0
