"""`remap check`: the adapter contract run from the command line, for any adapter.

Each check renders the probe and compares it with what the conventions say it must be, judged by
`core.host.judge` (which judges a user's images the same): the white Lambertian's pixels linear in the
analytic radiance (a display curve named as such), equal to it (when off, the factor: π, 2, 4π ... name
the usual mistakes), its orientation under an asymmetric light (a flip, or a shift by a pixel or half of
one), no 8-bit levels in its gradient and no highlight clipped or rolled off under a bright light, its
silhouette and a rim light's crescent integrated over each pixel's area (against a box-filtered analytic
image: aliasing is the adapter's, not the renderers' disagreement); bit-identical renders for one seed and
different ones for two, lobes that sum to the full image, a clear glass against its analytic image. Every
result is a row with what to fix; a row whose cause another row names is not judged until that one
passes; a render that never ends is a row saying why it likely did not. Nothing here names a renderer."""

from __future__ import annotations

import dataclasses
from typing import Callable

import numpy as np

from ..data.errors import RenderTimeoutError
from ..data.imageio import HALF_EPS
from ..data.metrics import beyond_noise, relative_rmse
from ..data.scene import EnvironmentLight, PointLight, ProbeScene
from . import judge
from .analytic import analytic_glass, analytic_lambert, analytic_mirror, box_filtered_lambert, scene_for, sphere_hits
from .judge import (FACTORS, FLIP_FIX, FLIPS, PLACEMENTS, SHIFT_FIX, SHIFTS, Row,  # noqa: F401 (the rows' names)
                    placements, usual_factor)

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
    "determinism": "determinism: one seed, the same image",
    "quantisation": "quantisation: no 8-bit levels in the probe's gradient",
    "encoding": "encoding: linear radiance, no display curve",
    "units": "units: white Lambertian against the analytic radiance",
    "orientation": "orientation: an asymmetric light, left from right and up from down",
    "seed": "seed: two seeds, two images",
    "lobes": "lobes: diffuse + specular = the full image",
    "precision": "precision: highlights far above 1, unclipped",
    "sampling": "sampling: the silhouette and a rim light, each pixel's area",
    "environment": "environment: the white Lambertian under the studio environment",
    "glossy": "glossy: a perfect mirror against its analytic image (the specular path)",
    "transmission": "transmission: a smooth glass against its analytic image",
}
"""Every check's row name, in the order `run` runs them."""


NO_WHITE = "declare one (see units)"


def _probe(render: Callable, white: tuple[str, dict]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The white Lambertian under the probe's light (`CALIBRATION`), its analytic image (box-filtered, as a
    renderer's pixels are) and the pixels judged: inside the sphere in every placement, less any on a plateau
    (clipped: what they were is lost; precision names it)."""
    img = np.asarray(render(white[0], white[1], CALIBRATION), np.float64)
    return img, box_filtered_lambert(CALIBRATION, ALBEDO).astype(np.float64), \
        inner_pixels(CALIBRATION) & ~judge.plateau(img)


def encoding(render: Callable, white: tuple[str, dict] | None) -> Row:
    """The white Lambertian's pixels as a power of the analytic radiance: linear, or a display curve."""
    if white is None:
        return Row(TITLES["encoding"], None, "no calibration material", NO_WHITE)
    img, want, inner = _probe(render, white)
    return _titled(judge.encoding(img, want, inner, otherwise=_mistaken(want)))


def calibration(render: Callable, white: tuple[str, dict] | None) -> Row:
    if white is None:
        return Row(TITLES["units"], None, "no calibration material", "declare a white diffuse material of albedo 0.8 "
                   "(a definition's `calibration: {model: ..., params: {...}}`)")
    img, want, inner = _probe(render, white)
    return _titled(judge.units(img, want, inner, CALIBRATION_TOLERANCE, otherwise=_mistaken(want)))


def _mistaken(want: np.ndarray) -> dict[str, np.ndarray]:
    """The probe's image as a usual mistake draws it, by its words: a point light without its 1/r² falloff."""
    hits = sphere_hits(CALIBRATION)
    near = ((np.asarray(CALIBRATION.point_lights[0].position) - hits.position) ** 2).sum(-1)
    return {"without the light's inverse-square falloff (a light's decay 0, or a sun)": want * near[..., None]}


def _titled(row: Row) -> Row:
    """A judgement's row under this check's title (`TITLES`)."""
    return dataclasses.replace(row, name=TITLES[row.name])


def _symmetric(mask: np.ndarray) -> np.ndarray:
    """The pixels inside the sphere in every flip of the image (a centred sphere: nearly all)."""
    return mask & FLIPS["rotated half a turn"](mask) & FLIPS["transposed"](mask)


def inner_pixels(scene: ProbeScene) -> np.ndarray:
    """The pixels inside the sphere in every placement of the image (`PLACEMENTS`): the symmetric
    interior, less a pixel all round (what a shift moves in or out)."""
    m = _symmetric(sphere_hits(scene).interior)
    return m & np.roll(m, 1, 0) & np.roll(m, -1, 0) & np.roll(m, 1, 1) & np.roll(m, -1, 1)


def orientation(render: Callable, white: tuple[str, dict] | None) -> Row:
    """A light upper left in front (+x right, +y up in the image): which placement of the analytic
    image (as it is, flipped, shifted by a pixel or half of one) the render is nearest to."""
    if white is None:
        return Row(TITLES["orientation"], None, "no calibration material", NO_WHITE)
    scene = SCENE.model_copy(update={"lights": [PointLight(theta=50.0, phi=150.0)]})
    img = np.asarray(render(white[0], white[1], scene), np.float64)
    return _titled(judge.orientation(img, analytic_lambert(scene, ALBEDO), inner_pixels(scene)))


STATE_FIX = ("each render starts from nothing: clear the frame and depth buffers, replace the material and its "
             "textures, reset the sampler; nothing of the render before it may show")


def determinism(render: Callable, models: dict, white: tuple[str, dict] | None = None) -> Row:
    """Each model at its defaults twice with one seed, bit for bit; with another material rendered between the
    two (the white Lambertian), so that state one render leaves (a buffer not cleared, a material not replaced)
    shows as a difference, not as a material."""
    name = TITLES["determinism"]
    for model, spec in models.items():
        p = spec.complete({})
        first = render(model, p, SCENE)
        if not np.array_equal(first, render(model, p, SCENE)):
            return Row(name, False, f"model {model}: two renders with seed {SCENE.seed} differ",
                       "pass the scene's seed to the renderer's sampler; a renderer without one changes frame to frame "
                       "in its post-processing (dithering, temporal anti-aliasing, auto exposure): turn it off",
                       blocks=False)  # noise: the rest still judge
        if white is not None and (white[0], white[1]) != (model, p):
            if np.array_equal(first, render(white[0], white[1], SCENE)):
                return Row(name, False, f"model {model} at its defaults and the calibration material give one image, "
                           "bit for bit (the render before shows through)", STATE_FIX)
            if not np.array_equal(first, render(model, p, SCENE)):
                return Row(name, False, f"model {model}: its render differs after the calibration material was "
                           "rendered between (the render before it left something behind)", STATE_FIX)
    between = " with another material rendered between" if white is not None else ""
    return Row(name, True, f"{len(models)} model(s), bit for bit{between}")


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
        if img.shape == (n, n, 3) and not np.isfinite(img).all():
            return Row(name, False, f"model {model}: {int((~np.isfinite(img)).any(axis=-1).sum())} pixels are not "
                       "finite (NaN or infinity)", "a pixel filter or a division that can reach 0 (a normalised "
                       "filter's weights, pow of a negative, 0/0 at the sphere's edge): clamp, or filter with a box")
        if img.shape == (n, n, 3) and img.max() <= 0:
            return Row(name, False, f"model {model}: every pixel is 0 (nothing lit)", "the sphere in the camera's "
                       "view, lit by the scene's light at its intensity in W/sr; an exposure so low that an 8-bit "
                       "read-back rounds the image to 0 (a fixed camera exposure: scale the light by its inverse)")
        if img.shape != (n, n, 3) or not np.isfinite(img).all():
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
                       "each lobe's overrides must switch the other lobe off and nothing else; or the output rounds "
                       "(8-bit reads, merged or not, half floats: three images rounded apart miss their sum by about "
                       "a level; see precision and quantisation)")
    return Row(name, True, f"{checked} model(s) with two lobes" if checked else "no model with two lobes")


def quantisation(render: Callable, white: tuple[str, dict] | None) -> Row:
    """The probe's gradient (the analytic image draws it in 1845 values) in few levels: 8-bit output, however
    scaled, decoded or curved after (what units, encoding and orientation would misread)."""
    if white is None:
        return Row(TITLES["quantisation"], None, "no calibration material", NO_WHITE)
    probe, want, _ = _probe(render, white)
    levels = judge.quantised(probe, want)
    if levels:
        return Row(TITLES["quantisation"], False, f"the probe: {levels}", judge.FLOAT_FIX)
    lit = probe.max(axis=-1) > 0
    return Row(TITLES["quantisation"], True, f"the probe's {int(lit.sum())} lit pixels in "
               f"{np.unique(probe[lit]).size} values")


def precision(render: Callable, white: tuple[str, dict] | None) -> Row:
    """A light `BRIGHT` times the probe's: its brightest pixel against the analytic one (clipped at a
    plateau, or rolled off by a tone curve or clamped samples), and half floats."""
    if white is None:
        return Row(TITLES["precision"], None, "no calibration material", NO_WHITE)
    light = SCENE.point_lights[0]
    scene = SCENE.model_copy(update={"lights": [light.model_copy(update={"intensity": light.intensity * BRIGHT})]})
    img = np.asarray(render(white[0], white[1], scene), np.float32)
    row = _titled(judge.bright(img, analytic_lambert(scene, ALBEDO), where=f"under {BRIGHT:g}x the light: "))
    if row.passed and _half(img):
        return dataclasses.replace(row, detail=f"{row.detail}; every pixel is a half float: they round at "
                                   f"{HALF_EPS:.2%}, far below the render noise and the fit's steps, so they pass",
                                   fix="32-bit float pixels, where the renderer can write them, leave nothing to round")
    return row


SAMPLED = {"grazing light": 80.0, "rim light": 120.0}
"""The sampling check's point lights (theta from the view): the one skims the sphere, the other lights a crescent
on its silhouette; rendered at `SAMPLING` (64 spp: a path tracer's rim within 4 % of the exact filter)."""
SAMPLING = ProbeScene(resolution=48, spp=64)


def sampling(render: Callable, white: tuple[str, dict] | None) -> Row:
    """The silhouette and a rim light's crescent against the box-filtered analytic image (two seeds: beyond
    their noise): pixels integrated over their area, or one sample at each centre (aliased), which a fit would
    read as the material, and a floor as the renderers' disagreement."""
    if white is None:
        return Row(TITLES["sampling"], None, "no calibration material", NO_WHITE)
    scenes = {k: SAMPLING.model_copy(update={"lights": [PointLight(theta=t)]}) for k, t in SAMPLED.items()}
    images = {}
    for label, scene in scenes.items():
        a, b = (np.asarray(render(white[0], white[1], scene.with_(seed=s)), np.float64) for s in (0, 1))
        images[label] = ((a + b) / 2, relative_rmse(a, b) / 2)
    return _titled(judge.sampling(images, scenes))


STUDIO = ProbeScene(lights=[EnvironmentLight(type="environment", map="studio")], resolution=48, spp=64)
"""The glossy and environment rows' scene: the studio environment alone."""
GLOSSY_TOLERANCE = 0.10
"""A mirror further than this beyond its noise from its analytic image (48 px, 64 spp, two seeds): Mitsuba 0.6 %,
Cycles 0.5 %, three.js 3.0 %, MaterialX 2.6 %; the environment mirrored in the reflection 134 %, turned 10° 73 %,
1/π of it 68 %."""
MIRROR_FIX = ("a perfect mirror reflects the environment along d - 2(d.n)n, the map oriented as the diffuse sphere "
              "sees it (see environment), at its full radiance: the float map's pixels as given (no sRGB decoding of "
              "them, no exposure), no prefiltering blur at roughness 0, no extra factor")


def _named(img: np.ndarray, want: np.ndarray, err: float, flipped: str) -> str:
    """What an image far from its analytic one under the studio shows: black, ``flipped`` one way (the
    environment turned in its lookups), and its scale with the usual factor it is nearest."""
    if not img.any():
        return "; the image is black (the material lit by no environment light)"
    flips = {k: relative_rmse(f(want), img) for k, f in judge.FLIPS.items()}
    flip = min(flips, key=flips.get)
    ratio = float(img.sum() / max(float(want.sum()), 1e-30))
    known = judge.usual_factor(ratio)
    return (f"; {flipped} {flip} ({flips[flip]:.2%} from that)" if flips[flip] < err / 2 else "") + \
        f"; the image is {ratio:.4g}x it" + (f" (a factor of {known})" if known else "")


def glossy(render: Callable, mirror: tuple[str, dict] | None, environment: bool) -> Row:
    """The specular path: a perfect mirror under the studio environment against its analytic image (box-filtered,
    two seeds: beyond their noise), where the adapter renders an environment; a fault is named as a flip or a
    usual factor where it is one."""
    name = TITLES["glossy"]
    if not environment:
        return Row(name, True, "no environment light: a mirror shows point lights as points, nothing to judge")
    if mirror is None:
        return Row(name, None, "no mirror declared", "declare a perfect mirror (`Adapter.mirror`: reflectance 1 at "
                   "every angle, roughness 0; a conductor of IOR 0 + 10i, or a white metal)")
    return _under_studio(name, render, mirror, analytic_mirror(STUDIO, supersample=8), "the analytic mirror",
                         GLOSSY_TOLERANCE, "the reflection is", MIRROR_FIX)


ENVIRONMENT_TOLERANCE = 0.05
"""The white Lambertian under the studio further than this beyond its noise from its analytic image (48 px, 64 spp,
two seeds): Mitsuba, Cycles, three.js, MaterialX within 1 % (tests/adapters/test_light_rendering.py); the map
mirrored or turned a quarter, tens of percent."""
ENVIRONMENT_FIX = ("the map is equirectangular, u = atan2(x, -z) / 2π from the left, v = acos(y) / π from the top (the "
                   "scene document's `convention`), its pixels radiance in W m^-2 sr^-1 as given (no exposure, no "
                   "sRGB decoding of an EXR), integrated over the hemisphere (a rasteriser's irradiance map: E(n) = "
                   "∫ L cos, the diffuse BRDF's 1/π once)")


def lit_by_environment(render: Callable, white: tuple[str, dict] | None, environment: bool) -> Row:
    """The white Lambertian under the studio environment (where the adapter renders one) against its analytic
    image: the map's orientation, units and integration, which a fit under the studio would read as the model's;
    a mirrored or upside-down map is named so."""
    name = TITLES["environment"]
    if not environment:
        return Row(name, True, "no environment light: nothing to judge")
    if white is None:
        return Row(name, None, "no calibration material", NO_WHITE)
    return _under_studio(name, render, white, box_filtered_lambert(STUDIO, ALBEDO), "the analytic image",
                         ENVIRONMENT_TOLERANCE, "the map is", ENVIRONMENT_FIX)


def _under_studio(name: str, render: Callable, material: tuple[str, dict], want: np.ndarray, what: str,
                  tolerance: float, flipped: str, fix: str) -> Row:
    """A material under the studio (`STUDIO`, two seeds) against ``want``, its analytic image (``what``), within
    ``tolerance`` beyond the noise; off, what the image shows (`_named`) and ``fix``."""
    a, b = (np.asarray(render(material[0], material[1], STUDIO.with_(seed=s)), np.float64) for s in (0, 1))
    img, noise = (a + b) / 2, relative_rmse(a, b) / 2
    want = np.asarray(want, np.float64)
    err = relative_rmse(want, img)
    far = beyond_noise(err, noise)
    said = f"{err:.2%} from {what} ({far:.2%} beyond the noise)"
    if far <= tolerance:
        return Row(name, True, said)
    return Row(name, False, said + _named(img, want, err, flipped), fix)


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


NEEDS = {"quantisation": ("determinism",), "encoding": ("determinism",), "lobes": ("determinism",),
         "transmission": ("determinism",), "units": ("quantisation", "encoding"), "orientation": ("units",),
         "precision": ("units",), "sampling": ("units", "orientation"), "environment": ("sampling",),
         "glossy": ("sampling", "precision")}
"""A row judged only where the row it names passed (else its failure would be that row's cause read again:
a display curve read as a units factor and a shift, a units factor as aliasing)."""


STUDIO_ROWS = frozenset({"environment", "glossy"})
"""Rows that judge only where the adapter renders an environment (else they pass, having nothing to judge)."""


def _remembered(render: Callable) -> Callable:
    """``render`` with the white Lambertian's probe rendered once for the rows that judge it (encoding,
    units, precision); every other render as it comes (determinism and seed render twice on purpose)."""
    kept: dict = {}

    def once(model, params, scene, lobe=None):
        if scene is not CALIBRATION:
            return render(model, params, scene, lobe)
        key = (model, repr(sorted(params.items())), lobe)
        if key not in kept:
            kept[key] = render(model, params, scene, lobe)
        return kept[key]
    return once


def run(render: Callable, models: dict, white: tuple[str, dict] | None, glass: tuple[str, dict] | None = None,
        environment: bool = False, transmission_limit: str = "", mirror: tuple[str, dict] | None = None) -> list[Row]:
    """Every check (`TITLES`); ``render(model, params, scene, lobe=None) -> image``. A check one of
    whose renders did not finish (`RenderTimeoutError`) is a failed row with the likely cause, and the
    checks after it do not run (each would wait as long); a check whose prerequisite failed (`NEEDS`) is
    not judged."""
    render = _remembered(render)
    rows: dict[str, Row] = {}
    checks = {"images": lambda: images(render, models, environment), "encoding": lambda: encoding(render, white),
              "units": lambda: calibration(render, white), "orientation": lambda: orientation(render, white),
              "determinism": lambda: determinism(render, models, white),
              "seed": lambda: seed(render, white, environment),
              "lobes": lambda: lobes(render, models),
              "precision": lambda: precision(render, white), "quantisation": lambda: quantisation(render, white),
              "sampling": lambda: sampling(render, white), "glossy": lambda: glossy(render, mirror, environment),
              "environment": lambda: lit_by_environment(render, white, environment),
              "transmission": lambda: transmission(render, models, glass, environment, transmission_limit)}
    stopped: str | None = None  # why the checks left do not run
    blocked: set[str] = set()  # rows not judged for a prerequisite's failure (`NEEDS`), and so theirs
    for key in TITLES:
        check = checks[key]
        needs = NEEDS.get(key, ()) if environment or key not in STUDIO_ROWS else ()  # else nothing to wait for
        failed = [n for n in needs if (rows[n].passed is False and rows[n].blocks) or n in blocked]
        if stopped is not None:
            rows[key] = Row(TITLES[key], None, f"not run: {stopped}")
            continue
        if failed:
            blocked.add(key)
            rows[key] = Row(TITLES[key], None, f"not judged: {' and '.join(failed)} did not pass, whose cause "
                            "would be read again here")
            continue
        try:
            rows[key] = check()
        except RenderTimeoutError as exc:
            rows[key] = Row(TITLES[key], False, f"a render did not finish in {exc.seconds:g} s (it was stopped)",
                            HANG_FIX)
            stopped = f"a render did not finish (see {key})"
        if key == "images" and not rows[key].passed:  # the others index the image: not run rather than failed
            stopped = stopped or "the images are not right (see images)"
    return list(rows.values())
