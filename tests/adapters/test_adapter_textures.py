"""Textures on the probe sphere: each adapter lays an image over the sphere by the same texture
coordinates (`core.data.textures`), a constant image renders as the constant, and a texture's values
reach the BSDF as they are."""

import numpy as np
import pytest

from brdfremap.core.data.metrics import relative_rmse
from brdfremap.core.data.scene import ProbeScene
from brdfremap.core.data.textures import TextureMap
from helpers import checker

SCENE = ProbeScene().overridden(resolution=64, spp=64)


def test_mitsuba_and_cycles_lay_a_texture_the_same_way(mitsuba_adapter, cycles_adapter):
    tex = checker()
    mi = mitsuba_adapter.render_textured("diffuse", {"reflectance": (0.5,) * 3},
                                         {"reflectance": TextureMap(tex, "nearest")}, SCENE)
    cy = cycles_adapter.render_textured("diffuse", {"color": (0.5,) * 3, "roughness": 0.0},
                                        {"color": TextureMap(tex, "nearest")}, SCENE)
    same = relative_rmse(mi, cy)
    assert same < 0.02, same
    # The check can see a mistake: the same texture flipped, mirrored or turned is far off.
    for wrong in (tex[::-1], tex[:, ::-1], np.roll(tex, tex.shape[1] // 12, axis=1)):
        cy_wrong = cycles_adapter.render_textured("diffuse", {"color": (0.5,) * 3, "roughness": 0.0},
                                                  {"color": TextureMap(wrong, "nearest")}, SCENE)
        assert relative_rmse(mi, cy_wrong) > 10 * same


@pytest.mark.parametrize("side", ["mitsuba", "cycles"])
def test_a_constant_texture_renders_as_the_constant(side, mitsuba_adapter, cycles_adapter):
    if side == "mitsuba":
        adapter, model = mitsuba_adapter, "roughconductor"
        params = adapter.models[model].complete({"eta": 0, "k": 1, "alpha": 0.2, "specular_reflectance": 0.6})
        maps = {"alpha": TextureMap(np.full((4, 4), 0.2, np.float32)),
                "specular_reflectance": TextureMap(np.full((4, 4, 3), 0.6, np.float32))}
        tol = 1e-6
    else:
        adapter, model = cycles_adapter, "principled"
        params = adapter.models[model].complete({"base_color": 0.6, "metallic": 1.0, "roughness": 0.45})
        maps = {"roughness": TextureMap(np.full((4, 4), 0.45, np.float32)),
                "base_color": TextureMap(np.full((4, 4, 3), 0.6, np.float32))}
        tol = 0.01  # the mesh against the exact sphere, and its own noise
    plain = adapter.render(model, params, SCENE)
    textured = adapter.render_textured(model, params, maps, SCENE)
    assert relative_rmse(plain, textured) < tol
    rougher = adapter.render_textured(model, params, {**maps, next(iter(maps)): TextureMap(
        np.full((4, 4), 0.6, np.float32))}, SCENE)
    assert relative_rmse(plain, rougher) > 0.05  # the texture, not the parameter, is what rendered
