"""`remap check`'s transmission row judges a renderer's smooth glass against the analytic image
(`core.testing.analytic_glass`), with no renderer: a right image passes, a black interior (direct
light only, the probe's old transport) or a sphere that lets nothing through fails with its fix."""

import numpy as np
from brdfremap.core.host.check import GLASS, transmission
from brdfremap.core.data.schemas import ModelSpec, ParamSpec
from brdfremap.core.testing import analytic_glass, sphere_hits

GLASSY = {"glass": ModelSpec(name="glass", transmits=True,
                             parameters=(ParamSpec(name="ior", kind="scalar", lower=1.0, upper=3.0, default=1.5),))}
OPAQUE = {"paint": ModelSpec(name="paint", parameters=(ParamSpec(name="c", kind="rgb", default=(0.5, 0.5, 0.5)),))}


def _noisy(image: np.ndarray):
    def render(model, params, scene, lobe=None):
        rng = np.random.default_rng(scene.seed)
        return (image * rng.normal(1.0, 0.01, image.shape)).astype(np.float32)
    return render


def test_a_glass_is_judged_against_its_analytic_image():
    exact = analytic_glass(GLASS, 1.5, supersample=6)
    row = transmission(_noisy(exact), GLASSY, ("glass", {"ior": 1.5}), environment=True)
    assert row.passed, row.detail
    reflection_only = analytic_glass(GLASS, 1.5, supersample=6, bounces=-1)  # no light through it
    row = transmission(_noisy(reflection_only), GLASSY, ("glass", {"ior": 1.5}), environment=True)
    assert row.passed is False and "deep enough to enter the sphere" in row.fix
    assert float(reflection_only[sphere_hits(GLASS).interior].sum()) < 0.5 * float(exact.sum())


def test_what_it_asks_of_an_adapter():
    assert transmission(None, OPAQUE, None, environment=True).passed  # nothing lets light through
    row = transmission(None, GLASSY, None, environment=True)
    assert row.passed is False and "no clear glass is declared" in row.detail
    assert transmission(None, GLASSY, ("glass", {}), environment=False).passed is None
