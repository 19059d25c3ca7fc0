"""The neutral reading of materials (the informed start): Fresnel arithmetic, each adapter's
reading and writing (pure functions, no renderer), and the session's use of it."""

import math

import numpy as np
import pytest

from brdfremap.adapters.mitsuba.model import EXT_IOR
from brdfremap.adapters.cycles.models import MODELS as CYCLES
from brdfremap.adapters.mitsuba.models import MODELS as MITSUBA
from brdfremap.core.data.appearance import (
    Appearance,
    conductor_f0,
    dielectric_f0,
    eta_k_from_reflectivity,
    ior_from_f0,
    reflectivity_edge_tint,
)
from brdfremap.core.data.scene import ProbeScene
from brdfremap.core.data.schemas import Material
from brdfremap.core.job.execute import AdapterPool, execute, fitted, informed_start
from brdfremap.core.job.job import Job, Target, resolve
from brdfremap.core.data.settings import Settings
from brdfremap_example.adapter import ToyAdapter
from helpers import registry_of

GOLD = ((0.143, 0.374, 1.442), (3.983, 2.385, 1.603))  # Mitsuba's Au preset in RGB, near enough


def test_fresnel_helpers_invert_each_other():
    assert dielectric_f0(1.5) == pytest.approx(0.04)
    assert ior_from_f0(dielectric_f0(1.3)) == pytest.approx(1.3)
    r, g = reflectivity_edge_tint(*GOLD)
    n, k = eta_k_from_reflectivity(r, g)
    assert np.allclose(n, GOLD[0]) and np.allclose(k, GOLD[1])
    assert np.allclose(conductor_f0(*GOLD), r)
    assert conductor_f0(*GOLD)[0] > conductor_f0(*GOLD)[1] > conductor_f0(*GOLD)[2]  # gold is yellow


def test_mitsuba_gold_reads_as_a_conductor_and_writes_principled_by_the_exporters_rule():
    src = MITSUBA["roughconductor"].complete({"material": "none", "eta": GOLD[0], "k": GOLD[1], "alpha": 0.1})
    look = MITSUBA["roughconductor"].appearance(src)  # eta and k given: no preset is asked of Mitsuba
    assert look.kind == "conductor" and look.alpha == 0.1 and look.distribution == "beckmann"
    assert look.specular == pytest.approx(conductor_f0(*GOLD))
    out = CYCLES["principled"].from_appearance(look, CYCLES["principled"].complete({}))
    # Its edge too: Principled's Specular Tint is a metal's F82 tint, which a complex IOR gives.
    assert out == {"roughness": pytest.approx(math.sqrt(0.1)), "base_color": look.specular, "metallic": 1.0,
                   "specular_tint": look.edge_tint()}
    # Cycles' own conductor takes the complex IOR itself, and the source's Beckmann (Principled has none:
    # the fit tries its two GGX kinds, see test_an_open_distribution_is_tried_each_way).
    assert CYCLES["metallic"].from_appearance(look, {}) == {"roughness": pytest.approx(math.sqrt(0.1)),
                                                           "ior": GOLD[0], "extinction": GOLD[1],
                                                           "distribution": "beckmann"}


def test_a_plastic_keeps_its_reflectance_through_specular_ior_level():
    """Principled's IOR is not fitted (1.5): a plastic of IOR 1.3 reaches its lower F0 through
    Specular IOR Level (0.5 is the IOR as given, F0 scales with twice the level)."""
    src = MITSUBA["roughplastic"].complete({"diffuse_reflectance": (0.6, 0.1, 0.05), "alpha": 0.2, "int_ior": 1.3})
    look = MITSUBA["roughplastic"].appearance(src)
    assert look.kind == "dielectric" and look.diffuse == (0.6, 0.1, 0.05)
    out = CYCLES["principled"].from_appearance(look, CYCLES["principled"].complete({}))
    assert out["metallic"] == 0.0 and out["base_color"] == (0.6, 0.1, 0.05)
    assert 2 * out["specular_ior_level"] * dielectric_f0(1.5) == pytest.approx(dielectric_f0(1.3 / EXT_IOR))
    # And back: Cycles' reading of that Principled BSDF is the plastic again.
    back = CYCLES["principled"].appearance(CYCLES["principled"].complete(out))
    assert back.ior == pytest.approx(1.3 / EXT_IOR) and back.alpha == pytest.approx(0.2)
    again = MITSUBA["roughplastic"].from_appearance(back, {})
    assert again["int_ior"] == pytest.approx(1.3) and again["alpha"] == pytest.approx(0.2)


@pytest.mark.parametrize("model, params", [
    ("phong", {"exponent": 98.0, "specular_reflectance": (0.9, 0.6, 0.3), "diffuse_reflectance": (0, 0, 0)}),
    ("ward", {"alpha": 0.1, "specular_reflectance": (0.9, 0.6, 0.3), "diffuse_reflectance": (0.2, 0.2, 0.2)}),
])
def test_the_paper_models_carry_phongs_exponent_rule(model, params):
    """n = 2/α² − 2 both ways (α 0.1 ↔ n 198 would be wrong: n 98 ↔ α = √(2/100))."""
    look = MITSUBA[model].appearance(MITSUBA[model].complete(params))
    assert look.alpha == pytest.approx(0.1 if model == "ward" else math.sqrt(2 / 100))
    assert look.kind == ("conductor" if model == "phong" else "dielectric")
    assert MITSUBA["phong"].from_appearance(Appearance(kind="conductor", alpha=0.1), {})["exponent"] == pytest.approx(198)


def test_a_model_without_a_reading_gives_none_and_no_conversion():
    from brdfremap.core.host.model import Model
    from brdfremap.core.data.schemas import ParamSpec

    plain = Model(name="plain", parameters=(ParamSpec(name="c", kind="rgb", default=(0.5, 0.5, 0.5)),))
    assert plain.appearance(plain.complete({})) is None
    assert plain.from_appearance(Appearance(kind="conductor", alpha=0.1), {}) == {}


def _toy_registry():
    return registry_of("toy", ToyAdapter)


def _job(reg, src, scene, fix=None, **settings):
    job = Job(source=src, target=Target(adapter="toy", model="toy", fix=fix or {}), scene=scene,
              settings=Settings(**settings), label="src.yaml", fit_same_model=True)  # the optimiser under test
    return resolve(job, reg)


def test_the_session_starts_from_the_conversion_of_free_parameters_only_within_bounds(monkeypatch):
    reg = _toy_registry()
    src = Material(adapter="toy", model="toy", params={"diffuse": [0.6, 0.3, 0.1], "specular": 0.8, "alpha": 0.15})
    scene = ProbeScene(resolution=48)
    job = _job(reg, src, scene, {"specular": 0.5}, scheme="one", coarse=0)
    toy = type(job.target_spec)
    start = informed_start(job)
    assert start == {"diffuse": (0.6, 0.3, 0.1), "alpha": 0.15}  # specular is fixed: not touched
    monkeypatch.setattr(toy, "from_appearance", lambda self, a, b: {"diffuse": (1.7, -0.2, 0.5), "alpha": 9.0,
                                                                     "unused": 0.3})
    # Clipped; the held one is taken as the start gives it, and stays held.
    start = informed_start(job)
    assert start == {"diffuse": (1.0, 0.0, 0.5), "alpha": 1.0, "unused": 0.3}
    assert "unused" not in fitted(job, start)
    monkeypatch.setattr(toy, "from_appearance", lambda self, a, b: {"diffuse": 0.5, "alpha": float("nan")})
    assert informed_start(job) == {}  # a hint of the wrong shape or not finite is left out


def test_an_informed_start_saves_renders_and_is_reported(tmp_path):
    reg = _toy_registry()
    src = Material(adapter="toy", model="toy", params={"diffuse": [0.6, 0.3, 0.1], "specular": 0.8, "alpha": 0.15})
    scene = ProbeScene(resolution=48)
    out = {}
    ads = AdapterPool(reg)
    for start in ("informed", "defaults"):
        out[start] = execute(_job(reg, src, scene, scheme="one", coarse=0, start=start), ads).report
    assert out["informed"].renders < out["defaults"].renders
    assert out["informed"].metrics.relative_rmse < 1e-3
    doc = out["informed"].document()
    assert doc["start"] == {"informed": True, "params": {"diffuse": [0.6, 0.3, 0.1], "specular": 0.8, "alpha": 0.15},
                            "rule": ""}
    assert out["defaults"].document()["start"] == {"informed": False, "params": {}, "rule": ""}


class _NoisyToy(ToyAdapter):
    """The toy with render noise: 1 % per pixel at 16 spp, falling as 1/√spp; a fixed pattern for a
    seed and sample count, as a renderer with a fixed seed (so finite differences stay smooth)."""

    def render(self, model, params, scene, lobe=None):
        img = super().render(model, params, scene, lobe)
        rng = np.random.default_rng([scene.seed, scene.spp])
        return (img * (1 + 0.04 / math.sqrt(scene.spp) * rng.standard_normal(img.shape))).astype(np.float32)


def test_a_noise_limited_fit_is_polished_at_more_samples():
    """A fit that ends within a few times the render noise is polished at 4x the samples: the
    parameters land closer to the truth than the fit at the scene's samples leaves them."""
    reg = registry_of("toy", _NoisyToy)
    truth = {"diffuse": [0.6, 0.3, 0.1], "specular": 0.8, "alpha": 0.15}
    src = Material(adapter="toy", model="toy", params=truth)
    scene = ProbeScene(resolution=48, spp=16)
    out = {}
    ads = AdapterPool(reg)
    for factor in (1, 4):
        job = _job(reg, src, scene, scheme="one", coarse=0, start="defaults", precise_spp=factor)
        out[factor] = execute(job, ads).report
    assert [s.name for s in out[4].stages][-1] == "precise@64spp"
    assert any(f.kind == "noise_polished" for f in out[4].findings)
    assert not any(f.kind == "noise_polished" for f in out[1].findings)
    # The verdict is taken after the polish, on the parameters it left.
    assert out[4].metrics.relative_rmse <= out[4].metrics.threshold and out[4].verdict == "ok"
    off = {f: abs(out[f].params["alpha"] / truth["alpha"] - 1) for f in out}
    assert off[4] < off[1]


def test_a_complex_ior_needs_an_edge_tint_where_schlick_misses_its_edge():
    from brdfremap.core.data.appearance import EDGE_COS, conductor_fresnel, schlick
    from brdfremap.core.data.schemas import Need

    eta, k = (1.66, 0.88, 0.52), (9.22, 6.27, 4.84)  # aluminium: its edge dips below Schlick's
    al = Appearance(kind="conductor", alpha=0.09, specular=conductor_f0(eta, k), eta=eta, k=k)
    assert conductor_fresnel(eta, k, 1.0) == pytest.approx(al.specular)
    assert Need.EDGE_TINT in al.needs()
    assert al.edge_tint() == pytest.approx((0.881, 0.910, 0.942), abs=2e-3)
    assert conductor_fresnel(eta, k, EDGE_COS) == pytest.approx(schlick(al.specular, EDGE_COS) * al.edge_tint())
    # Read as F0 alone (no complex IOR) a metal needs nothing: Schlick is its model.
    assert not Appearance(kind="conductor", alpha=0.09, specular=al.specular).needs()


def test_a_burley_diffuse_needs_what_no_shipped_input_renders():
    from brdfremap.adapters.cycles.models import MODELS
    from brdfremap.core.data.schemas import Need

    banana = Appearance(kind="dielectric", alpha=0.25, specular=(0.04,) * 3, diffuse=(0.66, 0.52, 0.12),
                        diffuse_model="burley")
    assert set(banana.needs()) == {Need.RETRO_DIFFUSE}
    assert not [p for m in MODELS.values() for p in m.parameters if Need.RETRO_DIFFUSE in p.fit_for]
    assert set(banana.model_copy(update={"diffuse_model": "oren-nayar"}).needs()) == {Need.ROUGH_DIFFUSE}
