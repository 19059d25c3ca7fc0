"""Sharp highlights judged (issue 43): a point light shows a near-mirror's highlight smaller than a
pixel, so such a material is fitted and judged under discs of light of finite size where the point
lights are (built-in environment maps), and a point light that cannot resolve a material gives way to
its disc instead of leaving the result unchecked."""

import numpy as np
import pytest
from brdfremap.core.data.environment import DISC_RADIUS, DISCS, radiance
from brdfremap.core.data.scene import EnvironmentLight, PointLight, ProbeScene
from brdfremap.core.host.analytic import environment_irradiance
from brdfremap.core.job.fitscene import SHARP_PX, choose
from brdfremap.core.job.validation import disc_for, held_out_scenes, validate


@pytest.mark.parametrize("name", sorted(DISCS))
def test_a_disc_gives_unit_irradiance_to_a_surface_facing_it_and_none_behind(name):
    where = np.asarray(DISCS[name].direction)
    e = environment_irradiance(radiance(name), np.stack([where, -where]))
    assert e[0] == pytest.approx([1.0, 1.0, 1.0], rel=0.01) and np.allclose(e[1], 0.0)


def test_a_disc_lies_where_its_point_light_is_and_nowhere_else():
    px = radiance("rim-disc")
    lit = px[..., 0] > 0
    from brdfremap.core.data.environment import pixel_directions

    d = pixel_directions(px.shape[1], px.shape[0])[lit]
    angle = np.degrees(np.arccos(np.clip(d @ np.asarray(DISCS["rim-disc"].direction), -1, 1)))
    assert angle.max() <= DISC_RADIUS + 1.0 + 0.5  # its edge ramp, and a pixel's pitch


def test_the_probe_light_has_its_disc_at_its_irradiance():
    scene = ProbeScene()
    disc = disc_for(scene.point_lights[0], scene)
    assert disc.map == "probe-disc" and disc.scale == pytest.approx(30.0 / 5.2**2, rel=1e-5)
    assert disc_for(PointLight(theta=33.0), scene) is None  # no disc built there: the caller keeps its lights


def test_a_sharp_source_is_judged_under_discs_where_the_point_lights_are():
    scene = ProbeScene()
    plain = {c.name: c for c, _, _ in held_out_scenes(scene)}
    sharp = {c.name: (c, a) for c, a, _ in held_out_scenes(scene, sharp=True)}
    assert all(isinstance(x, PointLight) for c in (plain["grazing"], plain["rim"], plain["headlight"]) for x in c.lights)
    for name in ("grazing", "rim", "headlight"):
        cond, a = sharp[name]
        (light,) = a.lights
        assert isinstance(light, EnvironmentLight) and light.map == f"{name}-disc" and "as a disc" in cond.label
        assert light.scale == pytest.approx(30.0 / 5.2**2, rel=1e-5) and a.resolution == scene.resolution
    assert sharp["environment"][0].lights == plain["environment"].lights  # the studio as it is


def _flat(sc):
    return np.ones((16, 16, 3), np.float32)


def test_a_point_light_that_cannot_resolve_a_material_gives_way_to_its_disc():
    """Two renders of the source under a point light differ by far more than the limit (a sub-pixel
    highlight), under a disc they agree: the disc's check is the condition's, and says so."""
    rng = np.random.default_rng(3)

    def render(sc):
        if any(isinstance(x, PointLight) for x in sc.lights):
            return (1 + 5.0 * rng.standard_normal((16, 16, 3))).astype(np.float32)
        return _flat(sc)

    got = validate(render, render, ProbeScene(resolution=16, spp=16), lambda sc: None, resolve_limit=0.10)
    checks = {c.condition: c for c in got.checks}
    assert set(checks) == {"grazing", "rim", "headlight", "environment"}
    for name in ("grazing", "rim", "headlight"):
        assert checks[name].noise_floor == 0.0 and "as a disc" in checks[name].label
        assert "the point light: " in checks[name].description
        assert got.scenes[name][0].lights[0].map == f"{name}-disc"


def test_a_disc_that_cannot_resolve_it_either_leaves_the_point_lights_outcome():
    rng = np.random.default_rng(4)
    noisy = lambda sc: (1 + 5.0 * rng.standard_normal((16, 16, 3))).astype(np.float32)  # noqa: E731
    got = validate(noisy, noisy, ProbeScene(resolution=16, spp=16), lambda sc: None, resolve_limit=0.10)
    rim = next(c for c in got.checks if c.condition == "rim")
    assert rim.label == "rim light" and rim.noise_floor > 0.10


def _noisy(sc):
    """Two seeds 2 % apart under a point light (a sharp highlight is noisy), none under a disc."""
    if any(isinstance(x, EnvironmentLight) for x in sc.lights):
        return _flat(sc)
    return np.full((16, 16, 3), 1.0 + 0.02 * (sc.seed % 2), np.float32)


def test_a_sharp_highlight_is_fitted_under_the_disc_and_a_broad_one_under_the_point_light():
    scene = ProbeScene(resolution=32, spp=16)
    sharp = choose(_noisy, scene, True, 0.10, highlight=lambda sc: SHARP_PX - 1)
    assert sharp.sharp and sharp.scene.lights[0].map == "probe-disc" and "as a disc" in sharp.why
    broad = choose(_noisy, scene, True, 0.10, highlight=lambda sc: SHARP_PX + 1)
    assert not broad.sharp and isinstance(broad.scene.lights[0], PointLight)
    no_env = choose(_noisy, scene, False, 0.10, highlight=lambda sc: 1.0)  # an adapter without environments
    assert not no_env.sharp and isinstance(no_env.scene.lights[0], PointLight)
    measured = []
    quiet = choose(_flat, scene, True, 0.10, highlight=lambda sc: measured.append(sc) or 1.0)
    assert not quiet.sharp and not measured  # noiseless: no highlight to measure, no render spent on it
