"""The held-out conditions every result is validated under: lights the fit never saw.

A fit matches the source under its scene's lights; "looks the same" means under others too.
After the fit, source and target are rendered under each condition below, with the scene's
camera, sphere and resolution, at `SPP_FACTOR` times the scene's samples (at least `MIN_SPP`)
and seeds the fit never used; the environment at half the resolution and four times those
samples (the same cost). Each side is rendered twice with half the samples: the mean is
the image, the difference measures the noise, so each condition reports how much of its error
the noise does not explain (`metrics.beyond_noise`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .engine.results import Check, Validation
from .metrics import beyond_noise, delta_e_itp, relative_rmse
from .scene import MAX_SEED, MAX_SPP, EnvironmentLight, PointLight, ProbeScene

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
    """The job's own lights, when the fit ran under others (`core.fitscene`)."""


CONDITIONS = (
    Condition("grazing", "grazing light", "a point light 80 degrees from the view: light skimming across the sphere",
              (PointLight(theta=80.0),)),
    Condition("rim", "rim light", "a point light 120 degrees from the view, behind the sphere: a lit rim",
              (PointLight(theta=120.0),)),
    Condition("headlight", "headlight", "a point light on the view axis, in front of the sphere",
              (PointLight(theta=0.0),)),
    Condition("environment", "studio environment", "the built-in studio environment (key, fill and rim lights)",
              (EnvironmentLight(type="environment", map="studio"),)),
)


def given_condition(scene: ProbeScene) -> Condition:
    """The job's scene's own lights as a condition: checked when the fit ran under other lights."""
    return Condition("given", "scene as given", f"the job's scene ({scene.name}) with its own lights, which the fit "
                     "did not use", tuple(scene.view_scenes()[0].lights), given=True)


def scenes(scene: ProbeScene, conditions=CONDITIONS) -> list[tuple[Condition, ProbeScene, ProbeScene]]:
    """Each condition's two half-sample scenes (the scene's first camera, its sphere and size)."""
    first = scene.view_scenes()[0]
    seeds = [(scene.seed + SEED_OFFSET + i) % MAX_SEED for i in (0, 1)]
    out = []
    for c in conditions:
        # An environment is noisier (every direction lights each pixel): half the resolution at four
        # times the samples, the same cost, half the noise.
        k = 4 if any(isinstance(x, EnvironmentLight) for x in c.lights) else 1
        half = max(1, min(MAX_SPP, k * max(MIN_SPP, scene.spp * SPP_FACTOR)) // 2)
        res = max(16, scene.resolution // 2) if k > 1 else scene.resolution
        base = first.model_copy(update={"lights": list(c.lights), "spp": half, "resolution": res,
                                        "name": f"validation:{c.name}"})
        out.append((c, base.with_(seed=seeds[0]), base.with_(seed=seeds[1])))
    return out


def _mean_and_noise(render, a: ProbeScene, b: ProbeScene) -> tuple[np.ndarray, float]:
    """The mean of two half-sample renders and its noise (relative RMSE between them / 2: each
    half has √2 the noise of the mean, and their difference √2 that again)."""
    first, second = np.asarray(render(a), np.float64), np.asarray(render(b), np.float64)
    return ((first + second) / 2).astype(np.float32), relative_rmse(first, second) / 2


def validate(render_source, render_target, scene: ProbeScene, problems, given: bool = False) -> Validation:
    """Render both sides under every condition (``render_*(scene) -> image``); ``problems(scene)``
    says why a side cannot render a condition (a light type it lacks), which is then skipped.
    ``given``: the fit ran under other lights than ``scene``'s, whose own are checked first."""
    result = Validation()
    conditions = ((given_condition(scene),) if given else ()) + CONDITIONS
    for cond, a, b in scenes(scene, conditions):
        why = problems(a)
        if why:
            result.skipped[cond.name] = why
            continue
        src, src_noise = _mean_and_noise(render_source, a, b)
        tgt, tgt_noise = _mean_and_noise(render_target, a, b)
        err = relative_rmse(src, tgt)
        floor = float(np.hypot(src_noise, tgt_noise))
        result.checks.append(Check(condition=cond.name, label=cond.label, description=cond.description,
                                   spp=2 * a.spp, resolution=a.resolution, error=err,
                                   perceptual=delta_e_itp(src, tgt), noise_floor=floor,
                                   beyond_noise=beyond_noise(err, floor), given=cond.given))
    return result
