"""Anisotropy's tangent frame (issue 20): both probes run their tangent along the sphere's
latitudes (the pole at the image's top), so Mitsuba's alpha_u is Cycles' roughness along the
tangent, and Cycles' rotation turns it counter-clockwise about the outward normal."""

import numpy as np
import pytest

from brdfremap.core.data.appearance import alphas_from_anisotropy, anisotropy_from_alphas
from brdfremap.core.data.metrics import relative_rmse
from brdfremap.core.data.scene import ProbeScene

SCENE = ProbeScene(resolution=48, spp=32)
ALUMINIUM = {"distribution": "ggx", "material": "Al", "anisotropy": "anisotropic"}


def _cycles_brushed(cycles_adapter, alpha_u: float, alpha_v: float, rotation: float):
    alpha, aniso, _ = anisotropy_from_alphas(max(alpha_u, alpha_v), min(alpha_u, alpha_v))
    p = cycles_adapter.models["principled"].complete({
        "distribution": "ggx", "base_color": [0.91, 0.92, 0.92], "metallic": 1.0, "roughness": alpha ** 0.5,
        "anisotropic": aniso, "anisotropic_rotation": rotation})
    return cycles_adapter.render("principled", p, SCENE)


def test_alpha_u_runs_along_the_same_tangent_in_both_renderers(cycles_adapter, mitsuba_adapter):
    """An asymmetric check: alpha_u 0.05 / alpha_v 0.3 against its swap."""
    spec = mitsuba_adapter.models["roughconductor"]
    narrow_u = mitsuba_adapter.render("roughconductor", spec.complete({**ALUMINIUM, "alpha_u": 0.05, "alpha_v": 0.3}),
                                      SCENE)
    along = _cycles_brushed(cycles_adapter, 0.3, 0.05, rotation=0.0)  # the rougher direction on the tangent
    across = _cycles_brushed(cycles_adapter, 0.3, 0.05, rotation=0.25)  # turned a quarter: across it
    assert relative_rmse(narrow_u, across) < 0.05  # F82 against aluminium's measured IOR: about 1 %
    assert relative_rmse(narrow_u, along) > 0.5


def _principal_slope(img: np.ndarray) -> float:
    """The sign of the highlight's long axis slope, image up being +y: + for '/', - for '\\'."""
    lum = img.sum(axis=2)
    w = np.where(lum > 0.5 * lum.max(), lum, 0.0)
    rows, cols = np.indices(w.shape)
    x, y = cols - np.average(cols, weights=w), -(rows - np.average(rows, weights=w))
    return float(np.sign(np.average(x * y, weights=w)))


def test_cycles_rotation_turns_the_tangent_counter_clockwise(cycles_adapter):
    """An eighth of a turn from the latitudes (horizontal at the front) is '/', minus an eighth '\\';
    the neutral reading's rotation uses this sense (core.data.appearance)."""
    assert _principal_slope(_cycles_brushed(cycles_adapter, 0.3, 0.02, rotation=0.125)) > 0
    assert _principal_slope(_cycles_brushed(cycles_adapter, 0.3, 0.02, rotation=0.875)) < 0


@pytest.mark.parametrize("au, av", [(0.05, 0.3), (0.3, 0.05), (0.2, 0.1)])
def test_alphas_and_anisotropy_convert_both_ways(au, av):
    alpha, aniso, rot = anisotropy_from_alphas(au, av)
    assert np.allclose(alphas_from_anisotropy(alpha, aniso, rot), (au, av))
