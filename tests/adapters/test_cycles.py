"""The Cycles adapter with real Blender renders (bpy in a worker process)."""

import ast
import os

import numpy as np
import pytest

from brdfremap.core.data.errors import RenderError
from brdfremap.core.data.metrics import relative_rmse
from brdfremap.core.data.scene import EnvironmentLight, ProbeScene
from brdfremap.core.testing import analytic_lambert, sphere_hits

SCENE = ProbeScene(resolution=64)


def _p(adapter, model, **kw):
    return adapter.models[model].complete(kw)


def test_calibration_white_diffuse_matches_mitsuba_and_the_analytic_radiance(cycles_adapter, mitsuba_adapter):
    scene = ProbeScene(spp=64)  # the default probe, 128²
    cy = cycles_adapter.render("diffuse", _p(cycles_adapter, "diffuse", color=0.8), scene)
    mi = mitsuba_adapter.render("diffuse", mitsuba_adapter.models["diffuse"].complete({"reflectance": 0.8}), scene)
    assert relative_rmse(mi, cy) < 0.01
    inner = sphere_hits(scene).interior
    assert relative_rmse(analytic_lambert(scene, 0.8)[inner], cy[inner]) < 0.005


@pytest.mark.parametrize("kw", [{}, {"metallic": 0.5, "coat_weight": 0.5, "roughness": 0.2}])
def test_principled_lobes_from_passes_sum_to_the_full_image(cycles_adapter, kw):
    p = _p(cycles_adapter, "principled", base_color=[0.2, 0.4, 0.7], **kw)
    full = cycles_adapter.render("principled", p, SCENE)
    dif = cycles_adapter.render("principled", p, SCENE, "diffuse")
    spec = cycles_adapter.render("principled", p, SCENE, "specular")
    assert relative_rmse(full, dif + spec) < 1e-6
    assert dif.max() > 0 and spec.max() > 0


def test_a_full_image_is_rendered_without_the_lobe_passes_and_a_lobes_render_serves_it(cycles_adapter):
    """The passes cost about 13 % of a render: a full image alone is rendered without them (the
    same pixels), a lobe asked for later renders again with them, and one rendered with them
    serves the full image and the other lobe free."""
    p = _p(cycles_adapter, "principled", base_color=[0.6, 0.3, 0.2], roughness=0.37, metallic=0.3)
    n = cycles_adapter.renders
    full = cycles_adapter.render("principled", p, SCENE)
    spec = cycles_adapter.render("principled", p, SCENE, "specular")
    assert cycles_adapter.renders == n + 2
    assert np.array_equal(cycles_adapter.render("principled", p, SCENE), full)  # the lobes' render kept it
    dif = cycles_adapter.render("principled", p, SCENE, "diffuse")
    assert cycles_adapter.renders == n + 2
    assert relative_rmse(full, dif + spec) < 1e-6
    q = dict(p, roughness=0.38)
    cycles_adapter.render("principled", q, SCENE, "diffuse")
    cycles_adapter.render("principled", q, SCENE)
    assert cycles_adapter.renders == n + 3


def test_what_principled_declares_inert_leaves_the_image_unchanged(cycles_adapter):
    """inert_when lets the engine skip these parameters' Jacobian columns: it must stay true."""
    spec = cycles_adapter.models["principled"]
    p = _p(cycles_adapter, "principled", base_color=[0.9, 0.6, 0.3], metallic=1.0, roughness=0.3)
    ref = cycles_adapter.render("principled", p, SCENE)
    away = {"ior": 2.4, "specular_ior_level": 0.1, "coat_roughness": 0.6, "coat_ior": 2.2, "coat_tint": (0.9, 0.5, 0.3),
            "sheen_roughness": 0.1, "sheen_tint": (1.0, 0.2, 0.2), "subsurface_radius": (0.1, 1.0, 1.0),
            "subsurface_scale": 1.0, "subsurface_ior": 2.0, "subsurface_anisotropy": 0.5, "thin_film_ior": 2.0,
            "anisotropic_rotation": 0.3, "subsurface_method": "burley"}
    inert = {q.name for q in spec.parameters if q.inert_when}
    assert inert == set(away)  # every declaration is checked here: coat, sheen, subsurface weights, film, anisotropy 0
    # At roughness 0 every distribution is the same mirror: no tries of one for a smooth source
    # (`execute.alternatives`), though a user may still name one.
    studio = ProbeScene(resolution=32, spp=8, lights=[EnvironmentLight(type="environment", map="studio")])
    mirror = {**p, "roughness": 0.0}
    assert np.array_equal(cycles_adapter.render("principled", {**mirror, "distribution": "ggx"}, studio),
                          cycles_adapter.render("principled", {**mirror, "distribution": "multi_ggx"}, studio))
    for name, value in away.items():
        assert spec.is_inert(name, p), name
        assert np.array_equal(cycles_adapter.render("principled", {**p, name: value}, SCENE), ref), name
    # Not inert below 1, and Specular Tint (the F82 edge tint) does reach a metal.
    q = {**p, "metallic": 0.9}
    assert not spec.is_inert("specular_ior_level", q)
    assert not np.array_equal(cycles_adapter.render("principled", {**q, "specular_ior_level": 0.1}, SCENE),
                              cycles_adapter.render("principled", q, SCENE))
    assert not np.array_equal(cycles_adapter.render("principled", {**p, "specular_tint": (0.5, 0.2, 0.1)}, SCENE), ref)


def test_metallic_bsdf_with_mitsuba_eta_k_matches_roughconductor(cycles_adapter, mitsuba_adapter):
    scene = ProbeScene(spp=64)
    mi = mitsuba_adapter.render("roughconductor", mitsuba_adapter.models["roughconductor"].complete(
        {"distribution": "beckmann", "material": "Cu", "alpha": 0.2}), scene)
    cy = cycles_adapter.render("metallic", _p(cycles_adapter, "metallic", distribution="beckmann",
                                              ior=[0.201005, 0.92375, 1.10222], extinction=[3.91326, 2.45305, 2.14209],
                                              roughness=0.2**0.5), scene)
    assert relative_rmse(mi, cy) < 0.01


def test_native_outputs(cycles_adapter, tmp_path):
    p = _p(cycles_adapter, "principled", base_color=[0.9, 0.6, 0.2], metallic=1.0, roughness=0.3)
    blend, snippet = cycles_adapter.write_native("principled", p, tmp_path)
    assert blend.read_bytes()[:7] == b"BLENDER"
    text = snippet.read_text()
    ast.parse(text)
    assert "ShaderNodeBsdfPrincipled" in text and "socket('Metallic').default_value = 1" in text
    assert not [f for f in os.listdir(tmp_path) if f.startswith(".")]  # no temp files left


def test_a_killed_worker_is_restarted_once(cycles_adapter):
    import signal

    p = _p(cycles_adapter, "glossy", roughness=0.41)
    cycles_adapter._passes.clear()
    os.kill(cycles_adapter.worker.proc.pid, signal.SIGKILL)
    img = cycles_adapter.render("glossy", p, SCENE)
    assert img.max() > 0
    assert cycles_adapter.worker.restarts >= 1


def test_a_failing_render_is_a_render_error_with_blenders_message(cycles_adapter):
    with pytest.raises(RenderError, match="cycles: .*"):
        cycles_adapter.worker.request({"op": "render", "model": "nope", "params": {}, "out": "/nonexistent/x.exr",
                                       "scene": {}})
    # The failed request wiped the scene half-way: the worker must rebuild it, not trip over it.
    cycles_adapter._passes.clear()
    assert cycles_adapter.render("glossy", _p(cycles_adapter, "glossy", roughness=0.43), SCENE).max() > 0


def test_a_batch_over_two_workers_equals_one_at_a_time(cycles_adapter):
    """Parallel finite differences (BRDFREMAP_CYCLES_WORKERS=2) must not change a single pixel."""
    from brdfremap.core.data.scene import ProbeScene

    spec, scene = cycles_adapter.models["principled"], ProbeScene(resolution=32)
    reqs = [("principled", spec.complete({"roughness": 0.21 + 0.03 * i, "metallic": 0.5}), scene, lobe)
            for i, lobe in enumerate((None, "specular", "diffuse", None, None))]
    saved = cycles_adapter.n_workers
    cycles_adapter.n_workers = 2
    try:
        batch = cycles_adapter.render_batch(reqs)
        assert len(cycles_adapter._extra) == 1 and cycles_adapter._extra[0].alive()
    finally:
        cycles_adapter.n_workers = saved
    cycles_adapter._passes.clear()  # render them again, one at a time, in the primary worker
    for (model, params, sc, lobe), img in zip(reqs, batch):
        assert np.array_equal(cycles_adapter.render(model, params, sc, lobe), img)
