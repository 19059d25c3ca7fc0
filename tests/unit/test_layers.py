"""Coat, sheen, anisotropy and transmission carried between renderers (issue 20), without a
render: the neutral reading carries each layer, the informed start sets it, and the target fits
the layers the source has (`ParamSpec.fit_when_carried`) and holds the others."""

import numpy as np
import pytest

from brdfremap.adapters.mitsuba import appearance as mitsuba
from brdfremap.core.job.execute import fitted, informed_start
from brdfremap.core.job.fitscene import choose
from brdfremap.core.job.job import Job, Target, resolve
from brdfremap.core.host.plugins import collect_adapters
from brdfremap.core.data.scene import ProbeScene
from brdfremap.core.data.schemas import Material
from brdfremap.core.data.settings import Settings

COPPER = {"base_color": [0.955, 0.638, 0.538], "metallic": 1.0, "roughness": 0.35}


@pytest.fixture(scope="module")
def registry():
    return collect_adapters()


def _start(registry, src: Material, adapter: str, model: str, fix=None):
    job = resolve(Job(source=src, target=Target(adapter=adapter, model=model, fix=fix or {}),
                      scene=ProbeScene(), settings=Settings(), label="m.yaml"), registry)
    start = informed_start(job)
    return start, fitted(job, start)


def test_a_coat_is_carried_and_fitted_only_when_the_source_has_one(registry):
    coated = Material(adapter="cycles", model="principled",
                      params={**COPPER, "coat_weight": 0.2, "coat_roughness": 0.2, "coat_tint": [0.9, 0.7, 0.5]})
    start, free = _start(registry, coated, "mitsuba", "principled")
    assert start["clearcoat"] == pytest.approx(0.8)  # a quarter of a full coat per unit of Disney's clearcoat
    assert start["clearcoat_gloss"] == pytest.approx((0.1 - 0.04) / 0.099)
    assert {"clearcoat", "clearcoat_gloss"} <= set(free) and "sheen" not in free
    bare_start, bare_free = _start(registry, Material(adapter="cycles", model="principled", params=COPPER),
                                   "mitsuba", "principled")
    assert "clearcoat" not in bare_start and not {"clearcoat", "clearcoat_gloss"} & set(bare_free)
    # Back to Cycles: the coat is fitted, its tint (which Mitsuba has not) held at the default.
    back = Material(adapter="mitsuba", model="principled", params={"base_color": [0.9, 0.6, 0.5], "metallic": 1.0,
                                                                   "clearcoat": 1.0, "clearcoat_gloss": 0.5})
    start, free = _start(registry, back, "cycles", "principled")
    assert start["coat_weight"] == 0.25 and {"coat_weight", "coat_roughness"} <= set(free)
    assert start["coat_tint"] == (1.0, 1.0, 1.0) and "coat_tint" not in free  # held at the reading's (white)


def test_a_held_value_the_user_fixes_is_neither_started_nor_fitted(registry):
    coated = Material(adapter="cycles", model="principled", params={**COPPER, "coat_weight": 0.2})
    start, free = _start(registry, coated, "mitsuba", "principled", fix={"clearcoat": 0.0})
    assert "clearcoat" not in start and "clearcoat" not in free


def test_anisotropy_carries_its_axes_both_ways(registry):
    al = Material(adapter="mitsuba", model="roughconductor",
                  params={"distribution": "ggx", "eta": [1.66, 0.88, 0.52], "k": [9.2, 6.3, 4.8],
                          "anisotropy": "anisotropic",
                          "alpha_u": 0.05, "alpha_v": 0.3})
    start, free = _start(registry, al, "cycles", "principled")
    assert start["anisotropic"] == pytest.approx((1 - 0.05 / 0.3) / 0.9)
    assert start["anisotropic_rotation"] == 0.25  # alpha_v the larger: the tangent turned a quarter
    assert start["roughness"] ** 2 == pytest.approx((0.05 * 0.3) ** 0.5)
    assert {"anisotropic", "anisotropic_rotation"} <= set(free)
    brushed = Material(adapter="cycles", model="principled",
                       params={**COPPER, "anisotropic": 0.9, "anisotropic_rotation": 0.25})
    start, free = _start(registry, brushed, "mitsuba", "roughconductor")
    assert start["anisotropy"] == "anisotropic" and start["alpha_u"] < start["alpha_v"]
    assert {"alpha_u", "alpha_v"} <= set(free) and "alpha" not in free


def test_a_glass_keeps_its_ior_and_its_colour(registry):
    glass = Material(adapter="mitsuba", model="roughdielectric",
                     params={"alpha": 0.04, "int_ior": 1.6, "specular_transmittance": [0.9, 1.0, 0.95]})
    start, _ = _start(registry, glass, "cycles", "principled")
    assert start["transmission_weight"] == 1.0 and start["ior"] == pytest.approx(1.6 / 1.000277)
    # Base Color tints what a Principled glass transmits, in and out; Mitsuba's transmittance each crossing
    # (a constant environment through a sphere: Base Color 0.5 and a transmittance of 0.707 both give 0.539).
    assert start["base_color"] == pytest.approx((0.81, 1.0, 0.9025))
    principled = registry.get("cycles").models["principled"]
    look = principled.appearance(principled.complete(
        {"transmission_weight": 1.0, "base_color": [1, 1, 1], "metallic": 0.0}))
    assert mitsuba.model_for(look)[0] == "roughdielectric"


def test_a_smooth_material_is_fitted_under_the_environment():
    scene = ProbeScene(resolution=16)
    renders = []

    def render(sc):
        renders.append(sc)
        return np.full((16, 16, 3), 0.5 if sc.environment is not None else 0.0, np.float32)

    got = choose(render, scene, environment_ok=True, limit=0.1, smooth=True)
    assert got.scene.environment is not None and "perfectly smooth" in got.why
    assert choose(render, scene, environment_ok=False, limit=0.1, smooth=True).scene.environment is None


def test_black_or_transmissive_sources_are_fitted_under_the_environment():
    """A source black under the point light goes where it shows; one that lets light through too, when
    the point light reaches it by too few paths to resolve (a rough glass)."""
    scene = ProbeScene(resolution=16)
    rng = np.random.default_rng(0)

    def black(sc):
        return np.full((16, 16, 3), 0.5 if sc.environment is not None else 0.0, np.float32)

    def noisy(sc):
        spread = 0.01 if sc.environment is not None else 0.8
        return (0.5 * (1 + spread * rng.standard_normal((16, 16, 3)))).astype(np.float32)

    assert "renders black" in choose(black, scene, environment_ok=True, limit=0.1).why
    assert choose(black, scene, environment_ok=False, limit=0.1).scene.environment is None  # the engine says so
    got = choose(noisy, scene, environment_ok=True, limit=0.1, transmissive=True)
    assert got.scene.environment is not None and "light through the sphere" in got.why
    assert choose(noisy, scene, environment_ok=True, limit=0.1, policy="as-given", transmissive=True).scene is scene


def test_a_full_glass_holds_its_colour_and_metalness(registry):
    """A glass's colour and metalness are carried from the source, not fitted."""
    glass = Material(adapter="cycles", model="principled",
                     params={"base_color": [1.0, 1.0, 1.0], "metallic": 0.0, "roughness": 0.2,
                             "transmission_weight": 1.0})
    for model, colour in (("principled", "base_color"),):
        start, free = _start(registry, glass, "mitsuba", model)
        assert start["spec_trans"] == 1.0 and start[colour] == (1.0, 1.0, 1.0)
        assert colour not in free and "metallic" not in free and "roughness" in free
    start, free = _start(registry, glass, "cycles", "principled")
    assert "base_color" not in free and "metallic" not in free


def test_part_transmission_is_counted_once(registry):
    half = Material(adapter="cycles", model="principled",
                    params={"base_color": [0.8, 0.2, 0.1], "metallic": 0.0, "transmission_weight": 0.5})
    for adapter in ("cycles", "mitsuba"):
        start, free = _start(registry, half, adapter, "principled")
        assert start["base_color"] == pytest.approx((0.8, 0.2, 0.1)) and "base_color" in free


def test_a_sheen_tint_comes_back_as_it_went(registry):
    cloth = Material(adapter="mitsuba", model="principled",
                     params={"base_color": [0.1, 0.15, 0.45], "sheen": 0.8, "sheen_tint": 0.5})
    start, _ = _start(registry, cloth, "mitsuba", "principled")
    assert start["sheen_tint"] == pytest.approx(0.5) and start["sheen"] == 0.8


def test_a_blend_weighted_by_a_texture_is_still_two_bsdfs(tmp_path):
    from brdfremap.core.library.formats import collect_formats, expand_inputs, read_all

    path = tmp_path / "s.xml"
    path.write_text("<scene version='3.0.0'><texture type='bitmap' id='mask'><string name='filename' value='m.png'/>"
                    "</texture><bsdf type='blendbsdf' id='mix'><ref name='weight' id='mask'/>"
                    "<bsdf type='diffuse'/><bsdf type='roughconductor'/></bsdf></scene>")
    formats = collect_formats()
    (entry,) = read_all(expand_inputs([str(path)], formats), formats)
    assert entry.material is not None and entry.textured == ["weight <- bitmap 'm.png'"]


def test_a_front_lit_fit_scene_gets_a_back_light_view_weighted_like_the_front():
    """By default a scene of point lights that resolves the source is fitted with a second view lit
    from behind (`core.job.fitscene.with_back_light`); its intensity makes the source's back view weigh
    `BACK_WEIGHT` of the first. Left out with --fit-scene one-view or as-given, and where the fit runs
    elsewhere."""
    from brdfremap.core.job.fitscene import BACK, BACK_WEIGHT
    from brdfremap.core.testing import analytic_lambert

    scene = ProbeScene(resolution=32)

    def lambert(sc):
        return np.concatenate([analytic_lambert(v) for v in sc.view_scenes()], axis=0)

    got = choose(lambert, scene, environment_ok=True, limit=0.1)
    assert len(got.scene.views) == 1 and got.scene.view_scenes()[0].cache_key() == scene.cache_key()
    back = got.scene.views[0].lights[0]
    assert abs(back.theta - BACK.theta) < 1e-6 and "lit from behind" in got.why
    front, rear = np.linalg.norm(analytic_lambert(scene)), np.linalg.norm(lambert(got.scene)[32:])
    assert abs(rear / front - BACK_WEIGHT ** 0.5) < 1e-3, (front, rear)
    for policy in ("one-view", "as-given", "samples"):
        assert not choose(lambert, scene, environment_ok=True, limit=0.1, policy=policy).scene.views, policy
    smooth = choose(lambert, scene, environment_ok=True, limit=0.1, smooth=True)
    assert smooth.scene.environment is not None and not smooth.scene.views
