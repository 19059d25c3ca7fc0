"""Glass judged (issue 53): a source that lets light through is fitted and judged where what is behind it
is seen through it, each point light a soft box in its direction over a dim backdrop (built-in
environment maps), never under a point light that reaches what is seen through the sphere by rare paths."""

import numpy as np
import pytest
from brdfremap.core.data.environment import BACKDROP_LEVEL, BACKDROPS, backdrop, pixel_directions, radiance
from brdfremap.core.data.scene import EnvironmentLight, ProbeScene
from brdfremap.core.host.analytic import environment_irradiance
from brdfremap.core.job.fitscene import choose
from brdfremap.core.job.validation import held_out_scenes


@pytest.mark.parametrize("name", sorted(BACKDROPS))
def test_a_backdrops_light_gives_unit_irradiance_facing_it_over_a_dim_pattern(name):
    where = np.asarray(BACKDROPS[name].direction)
    pattern = environment_irradiance(backdrop(), np.stack([where, -where]))
    e = environment_irradiance(radiance(name), np.stack([where, -where])) - pattern
    assert e[0] == pytest.approx([1.0, 1.0, 1.0], rel=0.01) and np.allclose(e[1], 0.0, atol=1e-6)
    assert 0.3 < float(pattern.mean()) < 0.7  # its hemisphere: about half the light's irradiance


def test_the_backdrop_is_a_pattern_on_every_side():
    px = backdrop()
    assert px.min() > 0 and px.mean() == pytest.approx(BACKDROP_LEVEL, rel=0.15)
    d = pixel_directions(px.shape[1], px.shape[0])
    up, down = px[d[..., 1] > 0.3].mean(), px[d[..., 1] < -0.3].mean()
    assert up > 1.5 * down  # a sky over a ground: what a glass turns upside down shows
    assert px[..., 1].std() / px[..., 1].mean() > 0.3  # bands: what refraction bends shows


def test_a_transmissive_source_is_judged_over_backdrops_and_an_opaque_one_is_not():
    scene = ProbeScene()
    glass = {c.name: a for c, a, _ in held_out_scenes(scene, transmissive=True)}
    paint = {c.name: a for c, a, _ in held_out_scenes(scene)}
    assert set(glass) == set(paint)
    for name in ("grazing", "rim", "headlight"):
        (light,) = glass[name].lights
        assert light.map == f"{name}-backdrop" and light.scale == pytest.approx(30.0 / 5.2 ** 2, rel=1e-5)
        assert glass[name].resolution == scene.resolution // 2  # an environment's: half the size, 4x the samples
        assert paint[name].point_lights
    # The scene's own light over its backdrop, held out where the fit ran under the studio, not where the fit ran there.
    studio = [EnvironmentLight(type="environment", map="studio")]
    given = [c for c, _, _ in held_out_scenes(scene, given=True, fit_lights=studio, transmissive=True) if c.given]
    assert [x.map for x in given[0].lights] == ["probe-backdrop"]
    fitted = given[0].lights
    assert not [c for c, _, _ in held_out_scenes(scene, given=True, fit_lights=fitted, transmissive=True) if c.given]


def test_a_transmissive_source_is_fitted_over_the_backdrop():
    """Its fit scene: the probe's light as its backdrop, at the samples that bring its noise to 3 %."""
    noise = {"point": 1.2, "backdrop": 0.02}

    def render(sc):
        which = "backdrop" if sc.environment is not None else "point"
        rng = np.random.default_rng(sc.seed)
        return np.ones((sc.resolution, sc.resolution, 3), np.float32) + rng.normal(0, noise[which], (sc.resolution,) * 2 + (3,)).astype(np.float32)

    found = choose(render, ProbeScene(), environment_ok=True, limit=0.1, transmissive=True)
    assert [x.map for x in found.scene.lights] == ["probe-backdrop"] and "over a backdrop" in found.why
    assert not found.scene.views  # no second view lit from behind: the backdrop lights it from every side
