"""The held-out conditions every result is validated under: lights the fit never saw.

A fit matches the source under its scene's lights; "looks the same" means under others too.
After the fit, source and target are rendered under each condition below, with the scene's
camera and sphere, at `SPP_FACTOR` times the scene's samples (at least `MIN_SPP`) and seeds
the fit never used: point lights at the scene's resolution, a frontal one at half of it where
the source's highlight is large enough to show there (`point_resolution`); the environment at
half the resolution and four times those samples (the same cost). Each side is rendered twice with half the samples: the mean is
the image, the difference measures the noise, so each condition reports how much of its error
the noise does not explain (`metrics.beyond_noise`)."""

from __future__ import annotations

import functools
from dataclasses import dataclass, replace

import numpy as np
from pydantic import ValidationError

from ..data.metrics import beyond_noise, delta_e_itp, relative_rmse
from ..data.environment import BACKDROPS, DISC_RADIUS, DISCS, SOFT_RADIUS
from ..data.scene import EnvironmentLight, Lighting, MAX_SEED, MAX_SPP, PointLight, ProbeScene
from ..engine.results import Check, Validation

SPP_FACTOR, MIN_SPP = 4, 64
SEED_OFFSET = 1000
"""The validation renders' seeds: the scene's seed plus this and plus one more (the fit renders
the scene's seed, and the noise floor seed + 1)."""


@dataclass(frozen=True)
class Condition:
    name: str
    label: str
    description: str
    lights: tuple[PointLight | EnvironmentLight, ...]
    given: bool = False
    """The job's own lights, when the fit ran under others (`core.job.fitscene`)."""
    disc: str = ""
    """The built-in disc map (`core.data.environment.DISCS`) that stands in for this condition's point
    light where that cannot resolve the material: empty for none."""
    backdrop: str = ""
    """The built-in backdrop (`core.data.environment.BACKDROPS`) that stands in for this condition's point
    light where the source lets light through: empty for none."""

    def as_disc(self, measured: str = "") -> Condition:
        """This condition under a disc light of finite size where its point light is, at the same
        irradiance on the sphere (`place_disc`); ``measured``: what the point light showed."""
        across = 2 * DISC_RADIUS
        why = f"; the point light: {measured}" if measured else ""
        return Condition(self.name, f"{self.label} as a disc {across:g} degrees across",
                         f"{self.description}; a disc light {across:g} degrees across in its place (a point light "
                         f"shows this material's highlight smaller than a pixel{why})",
                         (EnvironmentLight(type="environment", map=self.disc),))

    def as_backdrop(self, light: EnvironmentLight | None = None) -> Condition:
        """This condition for a source that lets light through: a soft box where its point light is, at
        the same irradiance, over a dim pattern seen through the sphere (`core.data.environment.backdrop`).
        Under a point light (or a disc) alone what is behind a glass is black and only the rare path
        that reflects the light lights a pixel: two renders part by 60-1450 %. ``light``: the backdrop
        placed already (the scene's own light's)."""
        light = light or EnvironmentLight(type="environment", map=self.backdrop)
        return Condition(self.name, f"{self.label} over a backdrop",
                         f"{self.description}; a soft box {2 * SOFT_RADIUS:g} degrees across in its place, over a "
                         "dim pattern on every side that is seen through the sphere (the source lets light through)",
                         (light,), self.given)


CONDITIONS = (
    Condition(Lighting.GRAZING, "grazing light", "a point light 80 degrees from the view: light skimming across the sphere",
              (PointLight(theta=80.0),), disc="grazing-disc",
              backdrop="grazing-backdrop"),
    Condition(Lighting.RIM, "rim light", "a point light 120 degrees from the view, behind the sphere: a lit rim",
              (PointLight(theta=120.0),), disc="rim-disc",
              backdrop="rim-backdrop"),
    Condition(Lighting.HEADLIGHT, "headlight", "a point light on the view axis, in front of the sphere",
              (PointLight(theta=0.0),), disc="headlight-disc",
              backdrop="headlight-backdrop"),
    Condition(Lighting.ENVIRONMENT, "studio environment", "the built-in studio environment (key, fill and rim lights)",
              (EnvironmentLight(type="environment", map="studio"),)),
)


def given_condition(scene: ProbeScene, transmissive: bool = False) -> Condition:
    """The job's scene's own lights as a condition: checked when the fit ran under other lights; for a
    source that lets light through, its one point light as its backdrop (`Condition.as_backdrop`) where
    one is built in its direction."""
    lights = tuple(scene.view_scenes()[0].lights)
    given = Condition(Lighting.GIVEN, "scene as given", f"the job's scene ({scene.name}) with its own lights, which "
                      "the fit did not use", lights, given=True)
    backdrop = backdrop_for(lights[0], scene) if transmissive and len(lights) == 1 and \
        isinstance(lights[0], PointLight) else None
    return given if backdrop is None else given.as_backdrop(backdrop)


DEFAULT = PointLight()
"""The default probe light: where a scene has no point light, condition lights keep its distance
and irradiance in proportion to the sphere."""
TURNED = 180.0
"""The studio's rotation when the fit itself ran under the studio: held out, it must be other light."""


def _reference(scene: ProbeScene) -> tuple[float, float]:
    """The distance from the sphere's centre and the intensity of the scene's first point light, or the
    default probe's scaled to the sphere's radius."""
    ref = next(iter(scene.point_lights), None)
    if ref is not None:
        return float(np.linalg.norm(np.asarray(ref.position) - np.asarray(scene.sphere.center))), ref.intensity
    dist = DEFAULT.r * scene.sphere.radius / 2.0
    return dist, DEFAULT.intensity * (dist / DEFAULT.r) ** 2


def place_light(light: PointLight, scene: ProbeScene) -> PointLight:
    """A condition's light about the scene's sphere (its angles from the view axis, as written),
    at the distance and intensity of the scene's first point light, or the default probe's scaled
    to the sphere's radius."""
    centre = np.asarray(scene.sphere.center, np.float64)
    dist, intensity = _reference(scene)
    t, ph = np.radians(light.theta), np.radians(light.phi)
    pos = centre + dist * np.array([np.sin(t) * np.cos(ph), np.sin(t) * np.sin(ph), np.cos(t)])
    r = float(np.linalg.norm(pos))
    return PointLight(r=r, theta=float(np.degrees(np.arccos(np.clip(pos[2] / r, -1, 1)))),
                      phi=float(np.degrees(np.arctan2(pos[1], pos[0]))), intensity=intensity)


def is_disc(light) -> bool:
    return isinstance(light, EnvironmentLight) and light.map in DISCS


def is_backdrop(light) -> bool:
    """A built-in soft box over the backdrop (`BACKDROPS`): placed as a disc is, rendered as an environment."""
    return isinstance(light, EnvironmentLight) and light.map in BACKDROPS


def place_disc(light: EnvironmentLight, scene: ProbeScene) -> EnvironmentLight:
    """A disc light at the irradiance the scene's first point light gives the sphere's centre (I / r²):
    a disc map's scale is its irradiance (`core.data.environment.disc`)."""
    dist, intensity = _reference(scene)
    return light.model_copy(update={"scale": float(f"{intensity / dist ** 2:.6g}")})


def disc_for(light: PointLight, scene: ProbeScene) -> EnvironmentLight | None:
    """The built-in disc (`DISCS`) in this point light's direction from the sphere's centre (within half a
    degree), at its irradiance there (I / r²); None where no disc is built in that direction."""
    offset = np.asarray(light.position) - np.asarray(scene.sphere.center)
    dist = float(np.linalg.norm(offset))
    for name, where in DISCS.items():
        if float(np.dot(offset / dist, where.direction)) > np.cos(np.radians(0.5)):
            return EnvironmentLight(type="environment", map=name, scale=float(f"{light.intensity / dist ** 2:.6g}"))
    return None


def backdrop_for(light: PointLight, scene: ProbeScene) -> EnvironmentLight | None:
    """The built-in backdrop (`BACKDROPS`) in this point light's direction, its soft box at the light's irradiance
    there; None where none is built in that direction."""
    disc = disc_for(light, scene)
    if disc is None:
        return None
    name = next(n for n, where in BACKDROPS.items() if where == DISCS[disc.map])
    return disc.model_copy(update={"map": name})


def _placed(light, scene: ProbeScene):
    return place_light(light, scene) if isinstance(light, PointLight) else \
        place_disc(light, scene) if is_disc(light) or is_backdrop(light) else light


def _held_out(c: Condition, scene: ProbeScene, fit_keys: list) -> Condition:
    """The condition as rendered for this scene: point lights and discs placed about its sphere; the
    studio turned round when the fit saw the studio itself."""
    if c.given:
        return c
    lights = tuple(_placed(x, scene) for x in c.lights)
    if any(isinstance(x, EnvironmentLight) and x.key() in fit_keys for x in lights):
        lights = tuple(x.model_copy(update={"rotation": (x.rotation + TURNED) % 360})
                       if isinstance(x, EnvironmentLight) else x for x in lights)
        return replace(c, label=f"{c.label} turned {TURNED:g} degrees", lights=lights,
                       description=f"{c.description}, turned about the up axis (the fit saw it as it is)")
    return replace(c, lights=lights)


HIGHLIGHT_PX = 16.0
"""A frontal point light's condition is rendered at half the scene's resolution where the source's
highlight, as the scene shows it, covers at least this many pixels there (`point_resolution`)."""
FRONTAL = 45.0
"""Point lights at most this far from the view axis light the sphere's face. Those further round
(grazing, rim) light its outline most, whose pixels' share of the image doubles at half the
resolution (a white paint's rim light: 4.8 % at 128 px, 6.0 % at 64): they keep the scene's."""


def point_resolution(scene: ProbeScene, highlight_px: float) -> int:
    """The resolution of the frontal point-light conditions: half the scene's (a quarter of the
    cost, the same samples per pixel and so the same noise in a relative RMSE) where the source's
    highlight (``highlight_px``, the pixels the brightest half of its light covers in the scene)
    still covers `HIGHLIGHT_PX` pixels there; else the scene's."""
    half = max(16, scene.resolution // 2)
    return half if highlight_px * (half / scene.resolution) ** 2 >= HIGHLIGHT_PX else scene.resolution


def _frontal(c: Condition) -> bool:
    return all(isinstance(x, PointLight) and x.theta <= FRONTAL for x in c.lights)


def scenes(scene: ProbeScene, conditions=CONDITIONS, fit_lights=(),
           resolution: int | None = None) -> list[tuple[Condition, ProbeScene, ProbeScene]]:
    """Each condition's two half-sample scenes (the scene's first camera, its sphere and size);
    ``fit_lights``: the lights the fit ran under; ``resolution``: the frontal point lights' (default
    the scene's)."""
    first = scene.view_scenes()[0]
    fit_keys = [x.key() for x in fit_lights]
    out = []
    for c in (_held_out(c, first, fit_keys) for c in conditions):
        # An environment is noisier (every direction lights each pixel): half the resolution at four
        # times the samples, the same cost, half the noise.
        # A disc is sampled as a light of finite size is: the point lights' samples and size.
        k = 4 if any(isinstance(x, EnvironmentLight) and not is_disc(x) for x in c.lights) else 1
        half = max(1, min(MAX_SPP, k * max(MIN_SPP, scene.spp * SPP_FACTOR)) // 2)
        res = max(16, scene.resolution // 2) if k > 1 else \
            (resolution or scene.resolution) if _frontal(c) else scene.resolution
        base = first.model_copy(update={"lights": list(c.lights), "spp": half, "resolution": res,
                                        "name": f"validation:{c.name}"})
        out.append((c, base.with_(seed=(scene.seed + SEED_OFFSET) % MAX_SEED),
                    base.with_(seed=(scene.seed + SEED_OFFSET + 1) % MAX_SEED)))
    return out


def held_out_scenes(scene: ProbeScene, given: bool = False, fit_lights=(), resolution: int | None = None,
                    sharp: bool = False, transmissive: bool = False) -> list:
    """Every condition a result is validated under, with its two half-sample scenes: the job's own
    lights first when the fit ran under others (``given``), each point light as its disc where the
    source is ``sharp`` (its highlight under a point light is smaller than a pixel:
    `core.job.fitscene.SHARP_PX`), as its backdrop where the source is ``transmissive``;
    ``resolution``: the frontal point lights'."""
    own = given_condition(scene, transmissive) if given else None
    if own is not None and all(x.key() in [y.key() for y in fit_lights] for x in own.lights):
        own = None  # the fit ran under the scene's own light over its backdrop: nothing held out
    conditions = ((own,) if own is not None else ()) + tuple(
        c.as_backdrop() if transmissive and c.backdrop else c.as_disc() if sharp and c.disc else c
        for c in CONDITIONS)
    return scenes(scene, conditions, fit_lights, resolution)


def _problem(scene: ProbeScene) -> str | None:
    """Why a condition's scene cannot be rendered here (a light inside the sphere), checked as a
    scene file is."""
    try:
        ProbeScene.model_validate(scene.model_dump(mode="json"))
    except ValidationError as exc:
        return f"its scene is not valid here: {exc.errors()[0]['msg']}"
    return None


def _other_seeds(a: ProbeScene, b: ProbeScene) -> tuple[ProbeScene, ProbeScene]:
    """The target's seeds: two more than the source's. At one seed a renderer draws the same pixel
    positions for both sides, which hides part of their difference from the noise floor."""
    return a.with_(seed=(a.seed + 2) % MAX_SEED), b.with_(seed=(b.seed + 2) % MAX_SEED)


def _mean_and_noise(render, a: ProbeScene, b: ProbeScene) -> tuple[np.ndarray, float]:
    """The mean of two half-sample renders and its noise (relative RMSE between them / 2: each
    half has √2 the noise of the mean, and their difference √2 that again)."""
    first, second = np.asarray(render(a), np.float64), np.asarray(render(b), np.float64)
    return ((first + second) / 2).astype(np.float32), relative_rmse(first, second) / 2


RESOLVE_FACTOR = 8
"""A condition whose noise floor is over the resolve limit is rendered again at up to this many times
its samples, when the noise (∝ 1/√spp) predicts that brings it within the limit; else it is left
unresolved (the verdict then says it was not checked)."""


def _more_samples(floor: float, limit: float | None, spp: int) -> int | None:
    """The samples per half that bring ``floor`` at ``spp`` within ``limit`` (a power of two times
    ``spp``, with a fifth to spare), or None: resolved already, or beyond `RESOLVE_FACTOR`."""
    if limit is None or floor <= limit:
        return None
    k = 2 ** int(np.ceil(np.log2(1.2 * (floor / limit) ** 2)))
    return spp * k if k <= RESOLVE_FACTOR and spp * k <= MAX_SPP else None


BLACK = "the source renders black under this light"


def _check(render_source, render_target, cond: Condition, a: ProbeScene, b: ProbeScene, scene: ProbeScene,
           given_noise: float, source_noise=None) -> Check | None:
    """One condition's check from two renders a side; None where the source renders black there.
    ``source_noise(scene)``: two source renders' difference there where a second cannot be rendered (one image
    given), estimated; None where it is measured."""
    src, src_noise = _mean_and_noise(render_source, a, b)
    estimate = source_noise(a) if source_noise is not None else None
    if estimate is not None:
        src_noise = estimate / np.sqrt(2)  # one image's noise, where two renders' differ by the estimate
    if not np.any(src > 0):
        return None
    ta, tb = _other_seeds(a, b)
    tgt, tgt_noise = _mean_and_noise(render_target, ta, tb)
    err = relative_rmse(src, tgt)
    floor = float(np.hypot(src_noise, tgt_noise))
    if cond.given and not any(is_backdrop(x) for x in cond.lights):
        # Where a few samples carry the image (the sub-pixel highlight that sent the fit
        # elsewhere) one pair of renders is itself a lucky draw: two seeds of Au α 0.002 at
        # 64 spp differed by 3 % where a third differs from them by 70 %. The difference measured
        # before the fit, scaled to these samples, is a second estimate; the larger is taken.
        floor = max(floor, given_noise * float(np.sqrt(scene.spp / (2 * a.spp))))
    return Check(condition=cond.name, label=cond.label, description=cond.description, spp=2 * a.spp,
                 resolution=a.resolution, error=err, perceptual=delta_e_itp(src, tgt), noise_floor=floor,
                 beyond_noise=beyond_noise(err, floor), given=cond.given)


def _measured(render_source, render_target, scene: ProbeScene, given_noise: float, resolve_limit: float | None,
              source_noise, cond: Condition, a: ProbeScene,
              b: ProbeScene) -> tuple[Check | None, ProbeScene, ProbeScene]:
    """One condition's check, rendered again at more samples where that can resolve it (`_more_samples`),
    and the two scenes it was taken at."""
    check = _check(render_source, render_target, cond, a, b, scene, given_noise, source_noise)
    more = None if check is None else _more_samples(check.noise_floor, resolve_limit, a.spp)
    if more is not None:
        a, b = a.with_(spp=more), b.with_(spp=more)
        check = _check(render_source, render_target, cond, a, b, scene, given_noise, source_noise)
    return check, a, b


def validate(render_source, render_target, scene: ProbeScene, problems, given: bool = False,
             given_noise: float = 0.0, fit_lights=(), resolution: int | None = None,
             resolve_limit: float | None = None, sharp: bool = False, transmissive: bool = False,
             source_noise=None) -> Validation:
    """Render both sides under every condition (``render_*(scene) -> image``); ``problems(scene)``
    says why a side cannot render a condition (a light type it lacks), which is then skipped.
    ``given``: the fit ran under other lights than ``scene``'s, whose own are checked first;
    ``given_noise``: two source renders' difference there at ``scene.spp``, measured before the fit;
    ``fit_lights``: the lights the fit ran under (the studio among them is turned for its check);
    ``resolution``: the frontal point lights' (`point_resolution`); ``resolve_limit``: a condition
    noisier than this is rendered again at more samples where that can resolve it (`_more_samples`),
    and a point light that even they cannot resolve gives way to its disc; ``sharp``: every point
    light is its disc from the start (`held_out_scenes`); ``transmissive``: the source lets light through,
    and every point light is its backdrop (`Condition.as_backdrop`); ``source_noise(scene)``: the source's
    noise there where it cannot render a second seed (`_check`)."""
    result = Validation()
    measure = functools.partial(_measured, render_source, render_target, scene, given_noise, resolve_limit,
                                source_noise)

    def blocked(sc: ProbeScene) -> str | None:
        return problems(sc) or _problem(sc)

    for cond, a, b in held_out_scenes(scene, given, fit_lights, resolution, sharp, transmissive):
        why = blocked(a)
        if why:
            result.skipped[cond.name] = why
            continue
        check, a, b = measure(cond, a, b)
        if cond.disc and resolve_limit is not None and (check is None or check.noise_floor > resolve_limit):
            # A highlight smaller than a pixel, or none (a smooth glass shows a point light nowhere): the light
            # of finite size in its place resolves it (a smooth material is judged, not left unchecked).
            seen = "the source renders black" if check is None else f"{check.noise_floor:.0%} noise at {check.spp} spp"
            disc, da, db = scenes(scene, (cond.as_disc(seen),), fit_lights, resolution)[0]
            # At its first samples only: where a disc needs more, the light through a glass (a few paths
            # find it), more samples cost tens of seconds and leave the front discs unresolved. The source
            # first (cached for the check): where it alone is over the limit, the target is not rendered.
            if not blocked(da) and _mean_and_noise(render_source, da, db)[1] <= resolve_limit:
                instead = _check(render_source, render_target, disc, da, db, scene, given_noise, source_noise)
                if instead is not None and instead.noise_floor <= resolve_limit:
                    check, a, b = instead, da, db  # else the point light's outcome stands (unresolved, or black)
        if check is None:
            result.skipped[cond.name] = BLACK
        else:
            result.checks.append(check)
            result.scenes[cond.name] = (a, b)
    return result
