"""Light through a sphere, alike in both renderers: a smooth clear glass (IOR 1.5) against its
analytic image under the studio environment, black under a point light; a rough one Mitsuba
against Cycles. Each adapter's `glasses` are the materials; the full table, at more samples:
bench/transport.py, docs/transport.md.

Before paths went through transmissive spheres (Mitsuba's direct integrator, no bounces in
Cycles, and Cycles' point-cloud sphere, which a ray inside it does not hit) the smooth glass was
92 % off between the two under the studio."""

import numpy as np
import pytest
from brdfremap.core.data.metrics import beyond_noise, relative_rmse
from brdfremap.core.data.scene import EnvironmentLight, PointLight, ProbeScene
from brdfremap.core.testing import analytic_glass, sphere_hits

STUDIO = ProbeScene(lights=[EnvironmentLight(type="environment", map="studio")], resolution=64, spp=256)
PROBE = ProbeScene(lights=[PointLight()], resolution=64, spp=512)


def _pair(adapter, kind: str, scene: ProbeScene) -> tuple[np.ndarray, np.ndarray]:
    model, given = adapter.glasses[kind]
    params = adapter.models[model].complete(given)
    assert adapter.models[model].transmissive(params)
    return tuple(adapter.render(model, params, scene.with_(seed=s)).astype(np.float64) for s in (0, 1))


def _judged(a: tuple, b: tuple, view=lambda x: x) -> tuple[float, float]:
    """Beyond-noise error of the means of two render pairs, and its noise floor."""
    err = relative_rmse(view((a[0] + a[1]) / 2), view((b[0] + b[1]) / 2))
    floor = np.hypot(relative_rmse(view(a[0]), view(a[1])), relative_rmse(view(b[0]), view(b[1]))) / 2
    return beyond_noise(err, floor), floor


def _blocks(img: np.ndarray, k: int = 8) -> np.ndarray:
    n = img.shape[0] // k * k
    return img[:n, :n].reshape(n // k, k, n // k, k, 3).mean(axis=(1, 3))


@pytest.fixture(scope="module")
def adapters(mitsuba_adapter, cycles_adapter):
    return {"mitsuba": mitsuba_adapter, "cycles": cycles_adapter}


@pytest.mark.parametrize("name", ["mitsuba", "cycles"])
def test_a_smooth_glass_matches_its_analytic_image_under_the_studio(adapters, name):
    inner = sphere_hits(STUDIO).interior
    exact = analytic_glass(STUDIO, 1.5, supersample=6)[inner].astype(np.float64)
    first, second = (img[inner] for img in _pair(adapters[name], "smooth", STUDIO))
    err, floor = relative_rmse(exact, (first + second) / 2), relative_rmse(first, second) / 2
    assert beyond_noise(err, floor) < 0.025, (err, floor)
    assert ((first + second) / 2).mean() == pytest.approx(exact.mean(), rel=0.01)  # the light through it, all of it


def test_a_smooth_glass_under_a_point_light_is_black_in_both(adapters):
    for a in adapters.values():
        assert max(img.max() for img in _pair(a, "smooth", PROBE.with_(spp=16))) == 0.0


def test_a_rough_glass_looks_the_same_in_both(adapters):
    m, c = (_pair(adapters[n], "rough", STUDIO) for n in ("mitsuba", "cycles"))
    beyond, floor = _judged(m, c, _blocks)
    assert beyond < 0.03, (beyond, floor)
    # Under a point light a few paths carry the light through (72 % noise per image at 128 spp,
    # bench/transport.py): compared in blocks, and by the light that comes through in all.
    m, c = (_pair(adapters[n], "rough", PROBE) for n in ("mitsuba", "cycles"))
    beyond, floor = _judged(m, c, _blocks)
    assert beyond < 0.08, (beyond, floor)
    assert (c[0] + c[1]).mean() == pytest.approx((m[0] + m[1]).mean(), rel=0.08)


def test_a_tinted_glass_is_tinted_alike(adapters):
    """A Principled glass's Base Color tints the light through the sphere, in and out; Mitsuba's
    dielectric tints each crossing (`Appearance.transmittance`): Base Color 0.5 is a transmittance
    of √0.5. Under a constant environment a clear sphere gives back exactly its radiance."""
    scene = ProbeScene(lights=[EnvironmentLight(type="environment", map="constant")], resolution=64, spp=128)
    inner = sphere_hits(scene).interior
    m, c = adapters["mitsuba"], adapters["cycles"]
    cycles = c.render("principled", c.models["principled"].complete(
        {"transmission_weight": 1.0, "base_color": 0.5, "roughness": 0.0, "ior": 1.5}), scene)[inner].mean()
    dielectric = m.render("dielectric", m.models["dielectric"].complete(
        {"int_ior": 1.5, "specular_transmittance": 0.5 ** 0.5}), scene)[inner].mean()
    principled = m.render("principled", m.models["principled"].complete(
        {"spec_trans": 1.0, "base_color": 0.5, "roughness": 0.01}), scene)[inner].mean()
    assert cycles == pytest.approx(dielectric, rel=0.01) and cycles == pytest.approx(principled, rel=0.01)
    clear = m.render("dielectric", m.models["dielectric"].complete({"int_ior": 1.5}), scene)[inner].mean()
    assert clear == pytest.approx(1.0, rel=0.005)
