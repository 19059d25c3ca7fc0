"""The scene a fit runs on: the job's scene, unless it cannot resolve the source.

A sharp highlight under a point light covers a fraction of a pixel: a few of the scene's samples
land on it, so two renders of the source differ by tens of percent and no fit can tell a match
from a mismatch. The source's own render noise says so before any fit. Then, in order:

1. more samples, while the noise they predict (noise ∝ 1/√spp) reaches `GOAL` within
   `MAX_SPP_FACTOR` times the scene's samples;
2. else the studio environment (`core.data.environment`) instead of the scene's lights (at half the
   resolution for a smooth source: `ENV_MIN_RESOLUTION`), where both
   adapters render one: a near-mirror reflects its whole surroundings, which a point light
   reduces to one sub-pixel spot (bench/validation.py measures both);
3. else the scene as it is (the verdict then says it cannot resolve the material).

Each candidate is measured (two source renders) before it is taken. A scene of point lights that
stays (as given, or at more samples) gets a second view (`with_back_light`): the same sphere lit
from behind, 100 degrees from the view, so that the fit sees the rim and the grazing Fresnel a
front light never shows (`--fit-scene one-view` leaves it out)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..data.metrics import l2, relative_rmse
from ..data.scene import MAX_SPP, EnvironmentLight, PointLight, ProbeScene, View
from ..data.settings import FitScene as Policy
from ..data.environment import DISC_RADIUS, SOFT_RADIUS
from .validation import backdrop_for, disc_for, place_light

GOAL = 0.03
"""The source noise (relative RMSE between two seeds) a fit scene should reach."""
MAX_SPP_FACTOR = 16
SHARP_PX = 8.0
"""A source whose highlight under the scene's point light carries half its light in fewer pixels than this
is sharp (a GGX metal below about alpha 0.03: alpha 0.01 in 2 pixels, 0.05 in 18): fitted and judged with
its point lights as discs (`_discs`), which show such a highlight as the disc's image."""
SMOOTH_WHY = "a perfectly smooth material (it shows a point light as a point at most)"
SHARP_NOISE = 0.01
"""A sharp highlight is noisy: its source's two renders differ by more than this at the scene's samples
(Au GGX alpha 0.03: 1.3 % at 16 spp, 0.05: 0.7 %, a diffuse sphere 0.4 %), so the highlight's size is
measured (one render of the specular lobe) only above it."""
ENV_MIN_RESOLUTION = 32
"""A perfectly smooth (or near-mirror, opaque) source's studio fit scene is half the job's resolution, at least this: a
quarter of the cost. The samples it takes to resolve it (up to 16 times the scene's) made these
fits among the costliest of a library (a smooth plastic 150 s with `--jobs 2`, 17 s at half the
size), and judged under the held-out lights the fits at either size are the same (within 0.1-1.3
points beyond the noise on the public corpus: docs/measurements/speed.md). A rough glass's is not halved: its
light through the sphere is noisy at any samples (16-20 % at 256 spp), and a quarter of the pixels
left its fit twice as far off under the turned studio (9.4 % -> 25.9 % beyond the noise)."""


@dataclass(frozen=True)
class FitScene:
    scene: ProbeScene
    why: str = ""
    """Empty when it is the job's scene; else why the fit runs elsewhere, in words."""
    noise: float = 0.0
    """The source's noise there (relative RMSE between two seeds)."""
    scene_noise: float = 0.0
    """The source's noise on the job's scene."""
    sharp: bool = False
    """The fit runs with the scene's point light as a disc (`_discs`): its held-out point lights are
    discs too (`core.job.validation.held_out_scenes`)."""


def source_noise(render: Callable[[ProbeScene], np.ndarray], scene: ProbeScene) -> float:
    """Two renders' difference (relative RMSE); infinite when both are black (nothing resolved)."""
    first, second = render(scene), render(scene.with_(seed=scene.seed + 1))
    if not (np.any(first > 0) or np.any(second > 0)):
        return math.inf
    return relative_rmse(first, second)


def _samples_for(noise: float, spp: int) -> int:
    """The samples per pixel (a power of two) that bring this noise at ``spp`` down to GOAL."""
    need = spp * (noise / GOAL) ** 2
    return min(MAX_SPP, 2 ** math.ceil(math.log2(max(need, spp + 1))))


def choose(render: Callable[[ProbeScene], np.ndarray], scene: ProbeScene, environment_ok: bool,
           limit: float, policy: Policy = Policy.AUTO, smooth: bool = False, transmissive: bool = False,
           source_smooth: bool = False, highlight: Callable[[ProbeScene], float] | None = None) -> FitScene:
    """The fit scene (`choose_lights`; one-view chooses as auto does), with the back light's view where
    ``policy`` is auto and the chosen scene is one of point lights that resolves the source."""
    back_view = policy == Policy.AUTO
    found = choose_lights(render, scene, environment_ok, limit, Policy.AUTO if back_view else policy, smooth,
                          transmissive, source_smooth, highlight)
    if not back_view or transmissive or found.scene.views or found.scene.environment is not None \
            or not found.noise <= limit:
        return found
    return with_back_light(render, found)


BACK = PointLight(theta=100.0)
"""The back light of a fit's second view: behind the sphere's outline, 100 degrees from the view (the
held-out grazing and rim lights are at 80 and 120, `core.job.validation`), on the side opposite the
scene's first light (`with_back_light`)."""
MAX_SCALE = 1000.0
"""The back light's intensity is at most this many times the scene's light's (a source nearly black
from behind is not fitted on its amplified noise)."""


BACK_WEIGHT = 0.25
"""The back view's weight against the first's in the fit's squared relative error: the source's image
there is scaled to this fraction of the first view's (squared norm)."""


def back_light(scene: ProbeScene) -> PointLight:
    """The back light of a fit's second view (`BACK`), placed about this scene's sphere, on the side opposite
    its first point light, at that light's intensity (`with_back_light` scales it to the source)."""
    first = next(iter(scene.point_lights), None)
    return place_light(BACK.model_copy(update={"phi": (first.phi + 180.0) % 360.0}) if first else BACK, scene)


def as_given(render: Callable[[ProbeScene], np.ndarray], scene: ProbeScene,
             renders: Callable[[ProbeScene], bool], estimate: Callable[[ProbeScene], float | None]) -> FitScene:
    """The fit scene of a source that renders only the scenes it was given (images: `core.images`): the
    job's scene, with the back light's view where the source renders it (``renders(scene)``) and it
    resolves the source as `with_back_light` asks; ``estimate(scene)``: its noise where one seed was given."""
    given = estimate(scene)
    noise = source_noise(render, scene) if given is None else given
    found = FitScene(scene, noise=noise, scene_noise=noise)
    back = scene.model_copy(update={"lights": [back_light(scene)]})
    if scene.views or scene.environment is not None or not renders(back) or not noise <= GOAL:
        return found
    return with_back_light(render, found)


def with_back_light(render: Callable[[ProbeScene], np.ndarray], found: FitScene,
                    weight: float = BACK_WEIGHT) -> FitScene:
    """``found`` with a second view under `BACK`, placed as the held-out lights are (at the distance of
    the scene's first light), its intensity scaled so that the source's image there weighs ``weight``
    of the first view's in the fit's error (at one intensity a white Lambertian's back view weighs 55
    times less, its lit crescent being 7 % of the pixels, where a metal's grazing reflection can
    outweigh the front). Left out where the source is black from behind, or where its noise over
    both views exceeds `GOAL` and the first view's own (a sharp grazing highlight)."""
    scene = found.scene
    light = back_light(scene)
    back = scene.model_copy(update={"lights": [light]})
    front_norm, back_norm = (l2(render(sc)) for sc in (scene, back))
    if back_norm <= 0.0 or front_norm <= 0.0 or np.sqrt(weight) * front_norm / back_norm > MAX_SCALE:
        return found
    # Rounded: the intensity is part of every render's key, which must not depend on the last bit.
    scale = float(f"{np.sqrt(weight) * front_norm / back_norm:.6g}")
    light = light.model_copy(update={"intensity": light.intensity * scale})
    both = scene.model_copy(update={"views": [View(camera=scene.camera, lights=[light])],
                                    "name": f"{scene.name} and a back light"})
    noise = source_noise(render, both)
    if noise > max(GOAL, found.noise):
        return found  # a highlight the back light makes sharper than the scene resolves: fitted on noise
    why = f"{found.why}; " if found.why else ""
    return FitScene(both, f"{why}with a second view lit from behind ({BACK.theta:g} degrees from the view, "
                          f"weighing {weight:.0%} of the first): the rim and grazing reflection a front light does "
                          "not show", noise, found.scene_noise or found.noise)


def choose_lights(render: Callable[[ProbeScene], np.ndarray], scene: ProbeScene, environment_ok: bool,
                  limit: float, policy: Policy = Policy.AUTO, smooth: bool = False, transmissive: bool = False,
                  source_smooth: bool = False, highlight: Callable[[ProbeScene], float] | None = None) -> FitScene:
    """The fit scene for a source rendered by ``render(scene)``; ``environment_ok``: both adapters
    render the studio environment; ``limit``: the noise above which a scene cannot resolve;
    ``policy``: `Settings.fit_scene`; ``smooth``: the source or the target is a mirror or a smooth
    glass (`ModelSpec.smooth`), which shows a point light as a point at most; ``transmissive``: the
    source lets light through (a point light reaches what is seen through it by rare paths only:
    a rough glass is 70-130 % noise under the probe at 16 spp, 10-15 % under the studio at 256);
    ``source_smooth``: the source itself is smooth (the studio then at half the size: a rough glass
    fitted to a smooth target keeps the full size); ``highlight(scene)``: the pixels the source's
    highlight covers there (`core.engine.schedule.highlight_pixels`), which says a sharp one (`SHARP_PX`).
    An opaque smooth or sharp source is fitted with its point light as a disc (`_discs`) where one is
    built in its direction."""
    if policy == Policy.AS_GIVEN:
        return FitScene(scene)
    noise = source_noise(render, scene)
    if policy == Policy.AUTO and environment_ok and not transmissive and not scene.views and \
            scene.environment is None and (smooth or (SHARP_NOISE < noise < math.inf and highlight is not None and
                                                       highlight(scene) < SHARP_PX)):
        why = SMOOTH_WHY if smooth else \
            f"a highlight smaller than {SHARP_PX:g} pixels under the scene's point light ({noise:.1%} noise " \
            f"at {scene.spp} spp)"
        found = _discs(render, scene, noise, limit, why)
        if found is not None:
            return found
    if transmissive and policy == Policy.AUTO and environment_ok and not scene.views and scene.environment is None:
        # However little its own noise (a real-time renderer's none): a target's glass is noisy under a point
        # light, and what is behind a glass is black there; over the backdrop it is seen through it.
        found = _backdrop(render, scene, noise, limit)
        if found is not None:
            return found
    if (smooth or noise == math.inf or (transmissive and noise > GOAL)) and policy == Policy.AUTO and environment_ok \
            and scene.environment is None and not scene.views:
        # Taken however noisy: under the point lights there is nothing (or less) to fit (the verdict says how noisy).
        why = SMOOTH_WHY if smooth else \
            "the source renders black under the scene's lights" if noise == math.inf else \
            f"light through the sphere, which a point light reaches by rare paths ({noise:.0%} noise at " \
            f"{scene.spp} spp)"
        found = _environment(render, scene, noise, math.inf, why, half=source_smooth or not transmissive)
        if found is not None:
            return found
    if math.isinf(noise):  # black, and nowhere else to look: the engine says so
        return FitScene(scene)
    if noise <= GOAL or scene.views:
        return FitScene(scene, noise=noise, scene_noise=noise)
    spp = _samples_for(noise, scene.spp)
    if scene.spp < spp <= scene.spp * MAX_SPP_FACTOR:
        more = scene.with_(spp=spp)
        n = source_noise(render, more)
        if n <= min(limit, 2 * GOAL):
            return FitScene(more, f"the source's render noise at {scene.spp} spp is {noise:.1%}: fitted at {spp} spp "
                                  f"({n:.1%})", n, noise)
    if policy == Policy.AUTO and environment_ok and scene.environment is None:
        found = _environment(render, scene, noise, limit, f"the source's render noise at {scene.spp} spp is "
                                                          f"{noise:.0%} (a highlight smaller than a pixel)",
                             half=not transmissive)
        if found is not None:
            return found
    return FitScene(scene, noise=noise, scene_noise=noise)


def _discs(render, scene: ProbeScene, noise: float, limit: float, why: str) -> FitScene | None:
    """The scene with its point light as the built-in disc in its direction (`disc_for`), at half its
    resolution (at least `ENV_MIN_RESOLUTION`: the disc's image on a mirror is about 8 pixels across
    there) and the samples that bring the source's noise to GOAL; None where the scene's lights have
    no disc (more than one, or one in a direction none is built in) or the disc cannot resolve it."""
    discs = [disc_for(x, scene) for x in scene.point_lights]
    if len(scene.lights) != 1 or None in discs:
        return None
    found = _resolved(render, scene.model_copy(update={
        "lights": discs, "resolution": min(scene.resolution, max(ENV_MIN_RESOLUTION, scene.resolution // 2)),
        "name": f"{scene.name}, its light as a disc"}), limit)
    if found is None:
        return None
    disc, n = found
    return FitScene(disc, f"{why}: fitted with the light as a disc {2 * DISC_RADIUS:g} degrees across, where it "
                          f"is, at {disc.spp} spp ({n:.1%})", n, noise if math.isfinite(noise) else 0.0, sharp=True)


def _resolved(render, scene: ProbeScene, limit: float) -> tuple[ProbeScene, float] | None:
    """``scene`` at the samples that bring the source's noise to GOAL (up to MAX_SPP_FACTOR times
    more) and that noise; None where the source is black there or its noise stays over ``limit``."""
    n = source_noise(render, scene)
    if math.isinf(n):
        return None
    if n > GOAL:
        scene = scene.with_(spp=min(_samples_for(n, scene.spp), scene.spp * MAX_SPP_FACTOR))
        n = source_noise(render, scene)
    return None if n > limit else (scene, n)


def _backdrop(render, scene: ProbeScene, noise: float, limit: float) -> FitScene | None:
    """For a source that lets light through: the scene with its point light as a soft box in its direction
    over the backdrop (`core.data.environment.BACKDROPS`), where what is behind the sphere is seen through
    it, at the samples that bring the source's noise to GOAL; None where the scene's lights have no backdrop
    (more than one, or one in a direction none is built in) or it cannot resolve the source."""
    lights = [backdrop_for(x, scene) for x in scene.point_lights]
    if len(scene.lights) != 1 or None in lights:
        return None
    found = _resolved(render, scene.model_copy(update={"lights": lights,
                                                       "name": f"{scene.name}, its light over a backdrop"}), limit)
    if found is None:
        return None
    lit, n = found
    shown = "black there" if not math.isfinite(noise) else f"{noise:.0%} noise at {scene.spp} spp" if noise > GOAL \
        else "what is behind it black there"
    return FitScene(lit, f"light through the sphere, which a point light reaches by rare paths ({shown}): fitted "
                         f"with the light as a soft box {2 * SOFT_RADIUS:g} degrees across, where it is, over a "
                         f"backdrop seen through the sphere, at {lit.spp} spp ({n:.1%})",
                    n, noise if math.isfinite(noise) else 0.0)


def _environment(render, scene: ProbeScene, noise: float, limit: float, why: str,
                 half: bool = False) -> FitScene | None:
    """The scene under the studio environment (``half``: at half its resolution, at least
    `ENV_MIN_RESOLUTION`), with the samples that bring the source's noise to GOAL (up to
    MAX_SPP_FACTOR times more), or None when it cannot resolve the source either."""
    res = max(ENV_MIN_RESOLUTION, scene.resolution // 2) if half else scene.resolution
    found = _resolved(render, scene.model_copy(update={
        "lights": [EnvironmentLight(type="environment", map="studio")], "resolution": min(res, scene.resolution),
        "name": f"{scene.name} under the studio environment"}), limit)
    if found is None:
        return None
    env, n = found
    return FitScene(env, f"{why}: fitted under the studio environment at {env.spp} spp ({n:.1%}), which lights "
                         "it from every side", n, noise if math.isfinite(noise) else 0.0)
