"""`remap check`: the adapter contract run from the command line, for any adapter.

Each check renders the probe and compares it with what the conventions say it must be: the
white Lambertian sphere against the analytic radiance (and, when it is off, the factor: π, 2,
4π ... name the usual mistakes), the image's orientation under an asymmetric light (a flip, or a
shift by a pixel or half of one, named as such), bit-identical renders for one seed and different
ones for two, lobes that sum to the full image, pixel precision and clipping. Every result is a
row with what to fix, and a render that never ends is a row saying why it likely did not; nothing
here names a renderer."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..data.errors import RenderTimeoutError
from ..data.imageio import HALF_EPS
from ..data.metrics import beyond_noise, eight_bit, relative_rmse
from ..data.scene import EnvironmentLight, PointLight, ProbeScene
from .analytic import analytic_glass, analytic_lambert, scene_for, sphere_hits

SCENE = ProbeScene(resolution=48, spp=16)
CALIBRATION = ProbeScene(resolution=64, spp=64)
ALBEDO = 0.8
CALIBRATION_TOLERANCE, LOBE_TOLERANCE = 0.01, 1e-4
HALF_LOBE_TOLERANCE = 4 * HALF_EPS
"""Three half-float images (the full one and each lobe) round apart by up to about this."""


def _half(img: np.ndarray) -> bool:
    lit = np.asarray(img, np.float32)
    lit = lit[lit > 0]
    return bool(lit.size) and np.array_equal(lit, lit.astype(np.float16).astype(np.float32))
FACTORS = {"π": math.pi, "1/π": 1 / math.pi, "2": 2.0, "1/2": 0.5, "4π": 4 * math.pi, "1/(4π)": 1 / (4 * math.pi),
           "2π": 2 * math.pi, "1/(2π)": 1 / (2 * math.pi), "1/683 (lumens per watt)": 1 / 683.0,
           "4π/683 (candela read as watts)": 4 * math.pi / 683.0}
"""Scale errors with a usual cause: radiance against irradiance (π), power against intensity (4π)."""
BRIGHT = 200.0
"""The intensity scale of the clipping check: the sphere's brightest pixels well above 1."""
NOISY = ProbeScene(resolution=48, spp=4)
"""The seed check's scene: few samples, so that a sampler's noise shows."""
CONVERGED = 16
"""The seed check's second sample count, as a multiple of the first: its noise 4x lower."""
NOISE_FREE = 1e-3
"""How far a render may move between ``NOISY.spp`` and ``CONVERGED`` times as many samples (inside the
sphere) and be noise-free: a fixed supersampling grid moves a few 1e-4, a path tracer's jittered pixels
about 1e-2 under the probe light and more under an environment."""

TITLES = {
    "images": "images: RGB float, finite, lit, black background",
    "units": "units: white Lambertian against the analytic radiance",
    "orientation": "orientation: an asymmetric light, left from right and up from down",
    "determinism": "determinism: one seed, the same image",
    "seed": "seed: two seeds, two images",
    "lobes": "lobes: diffuse + specular = the full image",
    "precision": "precision: unclipped 32-bit float pixels",
    "transmission": "transmission: a smooth glass against its analytic image",
}
"""Every check's row name, in the order `run` runs them."""


@dataclass(frozen=True)
class Row:
    name: str
    passed: bool | None
    """None: not run (what it needs is missing), which is not a pass."""
    detail: str
    fix: str = ""
    by_design: bool = False
    """A failure the adapter declares a property of its renderer (`Adapter.transmission_limit`)."""


def usual_factor(ratio: float) -> str:
    """The usual factor a ratio is nearest to (within 3 %), or ""."""
    name, value = min(FACTORS.items(), key=lambda kv: abs(math.log(ratio / kv[1])))
    return name if abs(math.log(ratio / value)) < 0.03 else ""


def calibration(render: Callable, white: tuple[str, dict] | None) -> Row:
    name = TITLES["units"]
    if white is None:
        return Row(name, None, "no calibration material", "declare a white diffuse material of albedo 0.8 "
                   "(a definition's `calibration: {model: ..., params: {...}}`)")
    img = render(white[0], white[1], CALIBRATION)
    inner = inner_pixels(CALIBRATION)
    full = analytic_lambert(CALIBRATION, ALBEDO)
    # Judged on the image as it would be placed right: a flipped or shifted image is orientation's
    # failure, not a units factor (one row low read as "10.92 % off; 1.023x").
    errors = placements(full, img, inner)
    best = min(errors, key=errors.get)
    err = errors[best]
    if err < CALIBRATION_TOLERANCE:
        placed = "" if best == "as expected" else f" with the image placed right (it is {best}: see orientation)"
        return Row(name, True, f"{err:.2%} from the analytic radiance{placed}")
    ratio = float(img[inner].sum() / max(full[inner].sum(), 1e-30))
    known = usual_factor(ratio)
    why = f"{err:.2%} off; the image is {ratio:.4g}x the analytic radiance" + (f" (a factor of {known})" if known else "")
    return Row(name, False, why, "pixels are radiance (W m^-2 sr^-1); the light's intensity is radiant intensity in "
               "W/sr (a power P in W is 4π·I); the diffuse BRDF is albedo/π; no tone mapping or 8-bit output "
               "(see precision)")


FLIPS = {"mirrored left-right": lambda a: a[:, ::-1], "upside down": lambda a: a[::-1, :],
          "rotated half a turn": lambda a: a[::-1, ::-1], "transposed": lambda a: np.swapaxes(a, 0, 1)}


def _moved(rows: int, columns: int, half: bool = False) -> Callable:
    """An image moved ``rows`` down and ``columns`` right (half that: the mean of it and the image)."""
    def move(a: np.ndarray) -> np.ndarray:
        moved = np.roll(a, (rows, columns), axis=(0, 1))
        return (a + moved) / 2 if half else moved
    return move


SHIFTS = {"shifted one row down": _moved(1, 0), "shifted one row up": _moved(-1, 0),
           "shifted one column right": _moved(0, 1), "shifted one column left": _moved(0, -1),
           "shifted half a row down": _moved(1, 0, True), "shifted half a row up": _moved(-1, 0, True),
           "shifted half a column right": _moved(0, 1, True), "shifted half a column left": _moved(0, -1, True)}
"""An image a pixel or half of one off (pixel centres at i or i + 1 instead of i + 0.5, a film with a
border row): what it looks like, the analytic image moved so; half a pixel, as the mean of two rows."""
PLACEMENTS = {"as expected": lambda a: a, **FLIPS, **SHIFTS}
FLIP_FIX = "right-handed world, the camera looking down -z with +y up; image row 0 at the top, column 0 at the left"
SHIFT_FIX = ("pixel centres at ((j + 0.5)/W, (i + 0.5)/H) of the image plane, row 0 at the top, column 0 at the "
              "left: no border row or column, no half-pixel offset in the camera or the film")


def _symmetric(mask: np.ndarray) -> np.ndarray:
    """The pixels inside the sphere in every flip of the image (a centred sphere: nearly all)."""
    return mask & FLIPS["rotated half a turn"](mask) & FLIPS["transposed"](mask)


def inner_pixels(scene: ProbeScene) -> np.ndarray:
    """The pixels inside the sphere in every placement of the image (`PLACEMENTS`): the symmetric
    interior, less a pixel all round (what a shift moves in or out)."""
    m = _symmetric(sphere_hits(scene).interior)
    return m & np.roll(m, 1, 0) & np.roll(m, -1, 0) & np.roll(m, 1, 1) & np.roll(m, -1, 1)


def placements(want: np.ndarray, img: np.ndarray, inner: np.ndarray, same_total: bool = False) -> dict[str, float]:
    """How far the image is from the expected one placed each way (`PLACEMENTS`); with ``same_total``,
    each placed at the image's total (so that a scale error, units' failure, does not hide the shape)."""
    errors = {}
    for k, f in PLACEMENTS.items():
        placed = f(want)[inner]
        if same_total:
            placed = placed * float(img[inner].sum() / max(float(placed.sum()), 1e-30))
        errors[k] = relative_rmse(placed, img[inner])
    return errors


def orientation(render: Callable, white: tuple[str, dict] | None) -> Row:
    """A light upper left in front (+x right, +y up in the image): which placement of the analytic
    image (as it is, flipped, shifted by a pixel or half of one) the render is nearest to."""
    name = TITLES["orientation"]
    if white is None:
        return Row(name, None, "no calibration material", "declare one (see units)")
    scene = SCENE.model_copy(update={"lights": [PointLight(theta=50.0, phi=150.0)]})
    img = render(white[0], white[1], scene)
    errors = placements(analytic_lambert(scene, ALBEDO), np.asarray(img, np.float64), inner_pixels(scene), same_total=True)
    best = min(errors, key=errors.get)
    if best == "as expected":
        return Row(name, True, f"{errors[best]:.2%} from the expected image (scaled to its total)")
    return Row(name, False, f"the image is {best} ({errors[best]:.2%} from that, {errors['as expected']:.2%} from "
               "the expected one)", SHIFT_FIX if best in SHIFTS else FLIP_FIX)


def determinism(render: Callable, models: dict) -> Row:
    name = TITLES["determinism"]
    for model, spec in models.items():
        p = spec.complete({})
        if not np.array_equal(render(model, p, SCENE), render(model, p, SCENE)):
            return Row(name, False, f"model {model}: two renders with seed {SCENE.seed} differ",
                       "pass the scene's seed to the renderer's sampler")
    return Row(name, True, f"{len(models)} model(s), bit for bit")


SEED_FIX = ("pass the scene's seed to the renderer's sampler; a renderer that ignores it makes every noise floor 0 "
            "and every verdict is judged against no noise")


def seed(render: Callable, white: tuple[str, dict] | None, environment: bool = False) -> Row:
    """Two seeds, two images: the tool measures a render's noise as the difference of two seeds'
    renders, and a renderer that ignores its seed makes that 0.

    The rule: the white Lambertian at few samples (`NOISY`; under the studio environment where the
    adapter renders one, whose sampling is noisy in any Monte Carlo renderer) must differ between
    seeds 0 and 1, unless the renderer has no sampling noise at all. When the two are identical it
    is rendered at `CONVERGED` times the samples: an image that does not move with the sample count
    either (within `NOISE_FREE`: an analytic or rasterised one, noise-free by design, its noise
    floor of 0 true) passes; one that does samples, and ignores its seed: it fails."""
    name = TITLES["seed"]
    if white is None:
        return Row(name, None, "no calibration material", "declare one (see units)")
    scene = NOISY.model_copy(update={"lights": [EnvironmentLight(type="environment", map="studio")]}) \
        if environment else NOISY
    inner = inner_pixels(scene)
    first, second = (np.asarray(render(white[0], white[1], scene.with_(seed=s)), np.float64) for s in (0, 1))
    if not np.array_equal(first, second):
        return Row(name, True, f"seeds 0 and 1 are {relative_rmse(first[inner], second[inner]):.2%} apart at "
                   f"{scene.spp} spp")
    more = scene.spp * CONVERGED
    moved = relative_rmse(np.asarray(render(white[0], white[1], scene.with_(spp=more)), np.float64)[inner],
                          first[inner])
    if moved < NOISE_FREE:
        return Row(name, True, f"one image for seeds 0 and 1, and within {moved:.2%} of it at {more} spp: no "
                   "sampling noise, so a noise floor of 0 is true")
    return Row(name, False, f"seeds 0 and 1 give the same image, which has sampling noise (it moves {moved:.2%} at "
               f"{more} spp instead of {scene.spp})", SEED_FIX)


def images(render: Callable, models: dict, environment: bool = True) -> Row:
    """Each model's image at the probe (a perfectly smooth one under the studio where the adapter
    renders an environment: ``environment``, as a fit would see it)."""
    name = TITLES["images"]
    n = SCENE.resolution
    for model, spec in models.items():
        img = np.asarray(render(model, spec.complete({}), scene_for(spec, SCENE, environment)))
        if img.shape != (n, n, 3) or not np.isfinite(img).all() or img.max() <= 0:
            top = float(np.nanmax(img)) if img.size and not np.isnan(img).all() else float("nan")
            return Row(name, False, f"model {model}: shape {img.shape}, max {top:.3g}",
                       f"write {n}x{n} RGB float pixels of the lit sphere")
        if img[0, 0].max() != 0 or img[-1, -1].max() != 0:
            return Row(name, False, f"model {model}: the background is not black",
                       "no environment or ambient light; the sphere alone, lit by the scene's light")
    return Row(name, True, f"{len(models)} model(s)")


def lobes(render: Callable, models: dict) -> Row:
    name = TITLES["lobes"]
    checked = 0
    for model, spec in models.items():
        if not spec.has_lobes or any(lobe.empty for lobe in spec.lobes.values()):
            continue
        p = spec.complete({})
        full = render(model, p, SCENE)
        err = relative_rmse(full, render(model, p, SCENE, "diffuse") + render(model, p, SCENE, "specular"))
        checked += 1
        tolerance = HALF_LOBE_TOLERANCE if _half(full) else LOBE_TOLERANCE
        if err >= tolerance:
            return Row(name, False, f"model {model}: the lobes' sum is {err:.2e} from the full image (allowed "
                       f"{tolerance:.0e}{' for half floats' if tolerance > LOBE_TOLERANCE else ''})",
                       "each lobe's overrides must switch the other lobe off and nothing else; if precision fails "
                       "too, fix that first (rounding breaks the sum)")
    return Row(name, True, f"{checked} model(s) with two lobes" if checked else "no model with two lobes")


def precision(render: Callable, white: tuple[str, dict] | None) -> Row:
    """Clipping at 1 (an 8-bit image) under a light bright enough to exceed it, and half floats."""
    name = TITLES["precision"]
    if white is None:
        return Row(name, None, "no calibration material", "declare one (see units)")
    light = SCENE.point_lights[0]
    scene = SCENE.model_copy(update={"lights": [light.model_copy(update={"intensity": light.intensity * BRIGHT})]})
    img = np.asarray(render(white[0], white[1], scene), np.float32)
    want = analytic_lambert(scene, ALBEDO)
    top = float(img.max())
    if float(want.max()) > 1.5 and top <= 1.0 + 1e-6:
        return Row(name, False, f"no pixel above {top:.3g} where the brightest should be {float(want.max()):.3g}: "
                   "clipped", "write float EXR, PFM or HDR (an 8-bit PNG clips highlights at 1)")
    levels = eight_bit(np.minimum(render(white[0], white[1], SCENE), 1.0))
    if levels:
        return Row(name, False, f"every pixel is one of 256 {levels} levels: an 8-bit image",
                   "write float EXR, PFM or HDR")
    if _half(img):
        return Row(name, True, f"brightest {top:.3g} (expected {float(want.max()):.3g}); every pixel is a half float: "
                   f"they round at {HALF_EPS:.2%}, far below the render noise and the fit's steps, so they pass",
                   "32-bit float pixels, where the renderer can write them, leave nothing to round")
    return Row(name, True, f"brightest {top:.3g} (expected {float(want.max()):.3g})")


GLASS = ProbeScene(lights=[EnvironmentLight(type="environment", map="studio")], resolution=48, spp=256)
GLASS_TOLERANCE = 0.03


def transmission(render: Callable, models: dict, glass: tuple[str, dict] | None, environment: bool,
                 limit: str = "") -> Row:
    """Light through a sphere: a clear smooth glass of IOR 1.5 against its analytic image under the studio
    environment (paths deep enough to enter and leave it; what is seen through it, the same)."""
    name = TITLES["transmission"]
    through = sorted(m for m, spec in models.items() if spec.transmits or spec.transmits_with)
    if not through:
        return Row(name, True, "no model lets light through")
    if glass is None:
        return Row(name, False, f"{', '.join(through)} let light through, and no clear glass is declared",
                   "declare a smooth clear glass of IOR 1.5 (an adapter's `glasses['smooth']`)")
    if not environment:
        return Row(name, None, "needs an environment light, which this adapter does not render")
    inner = sphere_hits(GLASS).interior
    first, second = (np.asarray(render(glass[0], glass[1], GLASS.with_(seed=s)), np.float64)[inner] for s in (0, 1))
    exact = analytic_glass(GLASS, 1.5, supersample=6)[inner]
    err, floor = relative_rmse(exact, (first + second) / 2), relative_rmse(first, second) / 2
    far = beyond_noise(err, floor)
    ratio = float((first + second).sum() / 2 / max(float(exact.sum()), 1e-30))
    if far < GLASS_TOLERANCE:
        return Row(name, True, f"{far:.2%} beyond the noise ({err:.2%}, noise {floor:.2%})")
    return Row(name, False, f"{far:.2%} beyond the noise; {ratio:.3g}x the analytic image's light", by_design=bool(limit),
               fix=limit or "trace paths deep enough to enter the sphere and leave it (at least 3 segments, a few more "
               "for internal reflections), show the environment through it, and hit the sphere from inside")


HANG_FIX = ("the renderer likely does not honour the sample count it is given (a progressive or tile engine renders "
            "until it is halted): map the scene's samples (`{spp}` in a definition) to its halt condition; a render "
            "that is only slow needs a longer `timeout`")


def run(render: Callable, models: dict, white: tuple[str, dict] | None, glass: tuple[str, dict] | None = None,
        environment: bool = False, transmission_limit: str = "") -> list[Row]:
    """Every check (`TITLES`); ``render(model, params, scene, lobe=None) -> image``. A check one of
    whose renders did not finish (`RenderTimeoutError`) is a failed row with the likely cause, and the
    checks after it do not run (each would wait as long)."""
    checks = {"images": lambda: images(render, models, environment),
              "units": lambda: calibration(render, white), "orientation": lambda: orientation(render, white),
              "determinism": lambda: determinism(render, models), "seed": lambda: seed(render, white, environment),
              "lobes": lambda: lobes(render, models), "precision": lambda: precision(render, white),
              "transmission": lambda: transmission(render, models, glass, environment, transmission_limit)}
    rows: list[Row] = []
    stopped: str | None = None  # why the checks left do not run
    for key, check in checks.items():
        if stopped is not None:
            rows.append(Row(TITLES[key], None, f"not run: {stopped}"))
            continue
        try:
            row = check()
        except RenderTimeoutError as exc:
            row = Row(TITLES[key], False, f"a render did not finish in {exc.seconds:g} s (it was stopped)", HANG_FIX)
            stopped = f"a render did not finish (see {key})"
        if key == "images" and not row.passed:  # the others index the image: not run rather than failed on its shape
            stopped = stopped or "the images are not right (see images)"
        rows.append(row)
    return rows
