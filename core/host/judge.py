"""What a calibration image says of the renderer that drew it: the white Lambertian's image against its
analytic one (`core.host.analytic`), judged the same whether an adapter rendered it (`core.host.check`,
`remap check`) or a user's renderer wrote it to a folder (`core.images.calibrate`).

Each judgement names a cause a fit could not tell from the material: a display curve (the pixels go as a
power of the radiance), a units factor (π, 4π, lumens), a flip or a pixel's shift, highlights clipped or
rolled off, 8-bit levels (however scaled or decoded after), and a pixel's area point-sampled (the silhouette
and a rim light's crescent, which a fit would read as the material's rim). Every function takes images and
returns a `Row`; nothing here renders."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..data.metrics import beyond_noise, eight_bit, relative_rmse
from ..data.scene import ProbeScene
from .analytic import analytic_lambert, box_filtered_lambert


@dataclass(frozen=True)
class Row:
    name: str
    passed: bool | None
    """None: not run (what it needs is missing), which is not a pass."""
    detail: str
    fix: str = ""
    by_design: bool = False
    """A failure the adapter declares a property of its renderer (`Adapter.transmission_limit`)."""
    blocks: bool = True
    """Whether the rows that need this one wait for it when it fails (`core.host.check.NEEDS`): a units error
    of a few percent with no usual cause does not, so that sampling can name what it likely is."""


FACTORS = {"π": math.pi, "1/π": 1 / math.pi, "2": 2.0, "1/2": 0.5, "4π": 4 * math.pi, "1/(4π)": 1 / (4 * math.pi),
           "2π": 2 * math.pi, "1/(2π)": 1 / (2 * math.pi), "1/683 (lumens per watt)": 1 / 683.0,
           "4π/683 (candela read as watts)": 4 * math.pi / 683.0,
           "0.604/0.8 (the albedo 0.8 read as an sRGB colour: pass colours to the renderer as linear)":
           ((0.8 + 0.055) / 1.055) ** 2.4 / 0.8}
"""Scale errors with a usual cause: radiance against irradiance (π), power against intensity (4π)."""
SHAPED = 0.05
"""An image within this of a usual mistake's analytic image (scaled), and four times nearer it than the right one,
has that mistake's shape (a light without falloff, drawn with one sample a pixel: 3 % from it)."""
SMALL_UNITS = 0.05
"""A units error whose scale is within this of 1, with no usual factor: the sampling or the mesh more likely."""
GAMMA_TOLERANCE = 0.08
"""The pixels go as the radiance to a power further than this from 1: an encoded image (sRGB: about 0.45)."""
BRIGHT_TOLERANCE = 0.9
"""The bright image's brightest pixel at least this fraction of its analytic value (at the image's own scale):
a renderer that clamps samples or rolls highlights off below it cuts a material's highlights as well."""
SAMPLING_TOLERANCE = 0.10
"""A grazing or rim light's image further than this beyond its noise from the box-filtered analytic one: the
pixels are not integrated over their area. Measured at 48 px, 64 spp (`box_filtered_lambert`): Mitsuba 3.1 %,
Cycles 4.0 %, three.js 3.8 %, MaterialX 1.0 % under the rim light; one ray at each pixel's centre 60 %."""
QUANTISED_LEVELS, GRADIENT_LEVELS = 256, 1024
"""A gradient the analytic image draws in at least `GRADIENT_LEVELS` values, drawn in at most `QUANTISED_LEVELS`:
8-bit output, whatever curve or scale was applied after."""

UNITS_FIX = ("pixels are radiance (W m^-2 sr^-1): no exposure, gain or tone mapping; a point light's intensity is "
             "radiant intensity in W/sr (a power P in W is 4π·I) falling off as 1/r²; the white Lambertian's BRDF "
             "is albedo/π, its albedo 0.8; the sphere a true sphere or a mesh fine enough that no facet shows")
FLOAT_FIX = ("write or read back 32-bit (or half) float linear pixels: an 8-bit image (PNG, a uint8 read-back) clips "
             "highlights at 1 and rounds the rest to 256 levels; no tone curve or view transform that stops at 1")
ENCODING_FIX = ("write linear radiance: no view transform or display curve (Blender: Standard; other renderers: "
                "linear, raw or scene-referred output), no gamma; a read-back of an sRGB target is decoded first")
GRAZING_FIX = ("the calibration material must be a Lambertian at every angle: no specular or Fresnel term left on "
               "(a Phong or a principled material with its specular at 0 still reflects at grazing angles; use a "
               "diffuse-only material); the silhouette round (a mesh of too few segments draws a polygon, and its "
               "interpolated normals a crescent of their own); each pixel integrated over its area (several "
               "samples a pixel, a box filter)")
SAMPLING_FIX = ("integrate each pixel over its area: several samples a pixel spread over it with a box filter (a path "
                "tracer's pixel filter, a rasteriser's supersampling); one sample at each pixel's centre draws the "
                "silhouette and a rim light's crescent wrong, and a fit reads that as the material")


def usual_factor(ratio: float) -> str:
    """The usual factor a ratio is nearest to (within 3 %), or "" (a black image's 0 included)."""
    if not ratio > 0 or not math.isfinite(ratio):
        return ""
    name, value = min(FACTORS.items(), key=lambda kv: abs(math.log(ratio / kv[1])))
    return name if abs(math.log(ratio / value)) < 0.03 else ""


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


def encoding(img: np.ndarray, want: np.ndarray, inner: np.ndarray, where: str = "",
             otherwise: dict[str, np.ndarray] | None = None) -> Row:
    """The power the pixels go as of the radiance (a log-log line through the lit interior, the image placed
    as it lies): a display curve (sRGB, a gamma) named as such, not as a units factor or a shift. An image
    linear in one of ``otherwise`` (the image a usual mistake makes: a light without falloff) is linear: the
    mistake is units' to name."""
    power = _power(img, want, inner)
    if power is None:
        levels = np.unique(img[inner & (img.mean(axis=2) > 0)]).size
        return Row("encoding", None, f"{where}too few lit pixels or levels to fit a curve ({levels} levels: see "
                   "quantisation)")
    if abs(power - 1.0) <= GAMMA_TOLERANCE:
        return Row("encoding", True, f"{where}the pixels go as the radiance to the power {power:.3f}: linear")
    for words, alt in (otherwise or {}).items():
        if abs((_power(img, alt, inner) or 0.0) - 1.0) <= GAMMA_TOLERANCE:
            return Row("encoding", True, f"{where}the pixels are linear in the analytic image {words} (see units)")
    cause = "gamma- or sRGB-encoded (a display curve)" if power < 1 else \
        "a curve applied, or not the white Lambertian of albedo 0.8"
    return Row("encoding", False, f"{where}the pixels go as the radiance to the power {power:.2f}, not 1: {cause}",
               ENCODING_FIX)


def _sampled_off_centre(img: np.ndarray, scene: ProbeScene) -> tuple[tuple[float, float], float] | None:
    """((x, y) within the pixel, error) of the one ray a pixel, at quarter-pixel steps other than the centre, whose
    analytic image the image is within `SAMPLING_TOLERANCE` of (a rasteriser's sample position without its
    anti-aliasing), else None."""
    from .analytic import _directions, _surface, lambert_radiance

    idx = np.arange(scene.resolution, dtype=np.float64)
    found = {}
    for ox in (0.0, 0.25, 0.75, 1.0):
        for oy in (0.0, 0.25, 0.5, 0.75, 1.0):
            xx, yy = np.meshgrid(idx + ox, idx + oy)
            found[(ox, oy)] = relative_rmse(lambert_radiance(scene, _surface(scene, *_directions(scene, xx, yy))), img)
    for oy in (0.0, 0.25, 0.75, 1.0):
        xx, yy = np.meshgrid(idx + 0.5, idx + oy)
        found[(0.5, oy)] = relative_rmse(lambert_radiance(scene, _surface(scene, *_directions(scene, xx, yy))), img)
    best = min(found, key=found.get)
    return (best, found[best]) if found[best] < SAMPLING_TOLERANCE else None


def _power(img: np.ndarray, want: np.ndarray, inner: np.ndarray) -> float | None:
    """The slope of log pixel against log radiance over the lit interior, the expected image placed as the image
    lies; None where too few pixels or levels fit a curve."""
    errors = placements(want, img, inner, same_total=True)
    want = PLACEMENTS[min(errors, key=errors.get)](want)
    lit = inner & (want.mean(axis=2) > 0.02 * want.max()) & (img.mean(axis=2) > 0)
    if lit.sum() < 16 or np.unique(img[lit]).size < 32:
        return None
    return float(np.polyfit(np.log(want[lit].mean(axis=1)), np.log(img[lit].mean(axis=1)), 1)[0])


def units(img: np.ndarray, want: np.ndarray, inner: np.ndarray, tolerance: float, noise: float = 0.0,
          where: str = "", otherwise: dict[str, np.ndarray] | None = None) -> Row:
    """The image against the analytic radiance, placed right (a flip or a shift is orientation's failure, not a
    units factor: one row low read as "10.92 % off; 1.023x"), beyond its noise; off, the ratio and its usual
    factor, and which of ``otherwise`` (the image a usual mistake makes, by its words) it has the shape of."""
    errors = placements(want, img, inner)
    best = min(errors, key=errors.get)
    far = beyond_noise(errors[best], noise)
    placed = "" if best == "as expected" else f" with the image placed right (it is {best}: see orientation)"
    beyond = f" ({far:.2%} beyond the noise)" if noise else ""
    if far < tolerance:
        return Row("units", True, f"{where}{errors[best]:.2%} from the analytic radiance{beyond}{placed}")
    ratio = float(img[inner].sum() / max(float(want[inner].sum()), 1e-30))
    known = usual_factor(ratio)
    said = f" (a factor of {known})" if known else ""
    for words, alt in (otherwise or {}).items():
        shaped = relative_rmse(alt[inner] * float(img[inner].sum() / max(float(alt[inner].sum()), 1e-30)), img[inner])
        if beyond_noise(shaped, noise) < max(tolerance, SHAPED) and shaped < errors[best] / 4:
            said += f"; it has the shape of the analytic image {words} ({shaped:.2%} from it, scaled)"
    small = not said and abs(ratio - 1.0) < SMALL_UNITS
    if small:
        said = ("; its scale is right but not its shape, with no usual cause: more likely how the pixels are sampled "
                "(see sampling), the sphere's facets (a coarse or flat-shaded mesh) or a specular term left on the "
                "calibration material than units")
    return Row("units", False, f"{where}{errors[best]:.2%} off the analytic radiance; the image is {ratio:.4g}x it"
               f"{said}", UNITS_FIX, blocks=not small)


def orientation(img: np.ndarray, want: np.ndarray, inner: np.ndarray, where: str = "") -> Row:
    """Which placement of the analytic image (as it is, flipped, shifted by a pixel or half of one) the image
    is nearest to, each scaled to the image's total."""
    errors = placements(want, img, inner, same_total=True)
    best = min(errors, key=errors.get)
    if best == "as expected" or errors[best] > errors["as expected"] / 2:  # a placement is named where it is clear
        return Row("orientation", True, f"{where}{errors['as expected']:.2%} from the expected image (scaled to its "
                   "total)")
    return Row("orientation", False, f"{where}the image is {best} ({errors[best]:.2%} from that, "
               f"{errors['as expected']:.2%} from the expected one)", SHIFT_FIX if best in SHIFTS else FLIP_FIX)


def quantised(img: np.ndarray, want: np.ndarray | None = None) -> str:
    """Words when the image is 8-bit however it was converted after, else "": its lit pixels take at most
    `QUANTISED_LEVELS` values where the analytic image ``want`` draws a gradient in `GRADIENT_LEVELS` or more
    (any curve or scale: levels of a known gradient), or (no ``want``) 256 levels of 8-bit linear or sRGB, or at
    most 256 whole multiples of one step (an 8-bit image scaled after)."""
    img = np.asarray(img, np.float64)
    values = np.unique(img[img > 0])  # a channel at 0 is no level of a step
    step = _one_step(values) if np.count_nonzero(img > 0) >= 1024 else None  # lit values, every channel
    kind = eight_bit(img)
    named = {"linear": "levels k/255, as an 8-bit image reads", "sRGB": "sRGB-decoded 8-bit levels"}
    how = named.get(kind, "") or (f"{values.size} levels {step:.4g} apart, scaled after" if step else "")
    if want is not None:  # over the pixels the analytic image lights: an image rounding most of them to 0 included
        lit = np.asarray(want).max(axis=-1) > 0
        shown = img[lit]
        expected, got = np.unique(np.asarray(want, np.float32)[lit]).size, np.unique(shown[shown > 0]).size
        if expected >= GRADIENT_LEVELS and got <= QUANTISED_LEVELS:
            return (f"its lit pixels take {got} values where the analytic gradient has {expected}: 8-bit"
                    + (f" ({how})" if how else ", converted after"))
    return f"every lit pixel one of {how} (8-bit)" if how else ""


def _one_step(levels: np.ndarray) -> float | None:
    """The step when 2 to 256 levels are all whole multiples of one (an 8-bit image scaled after), else None."""
    if not 2 <= levels.size <= QUANTISED_LEVELS:
        return None
    step = float(np.diff(np.concatenate([[0.0], levels])).min())
    ratio = levels / step
    return step if np.allclose(ratio, np.round(ratio), atol=1e-3) else None


def plateau(img: np.ndarray) -> np.ndarray:
    """The pixels on a plateau (`clipped`): a mask, empty where the image has none."""
    lit = np.asarray(img, np.float64).max(axis=-1)
    return lit >= float(lit.max()) * (1 - 1e-6) if clipped(img) else np.zeros(lit.shape, bool)


def clipped(img: np.ndarray) -> str:
    """Words when the image's brightest pixels sit on one plateau (a ceiling: 1, or any a renderer clamps
    at), with lit pixels below it, else ""."""
    lit = np.asarray(img, np.float64).max(axis=-1)
    top = float(lit.max())
    at_top = lit >= top * (1 - 1e-6)
    n, below = int(np.count_nonzero(at_top)), int(np.count_nonzero((lit > 0) & ~at_top))
    return f"{n} pixels at exactly {top:.4g} (clipped)" if top > 0 and n >= 8 and below >= 0.05 * (n + below) else ""


def bright(img: np.ndarray, want: np.ndarray, scale: float = 1.0, where: str = "") -> Row:
    """A light bright enough to put the sphere far above 1: its brightest pixel against the analytic one at
    the image's own ``scale`` (the calibration's ratio to the analytic radiance, so that a units factor is
    units' failure, not this one's)."""
    top, expected = float(np.max(img)), float(np.max(want)) * scale
    if top < BRIGHT_TOLERANCE * expected:
        plateau = clipped(img)
        return Row("precision", False, f"{where}the brightest pixel is {top:.3g} where it should be {expected:.3g}: "
                   + (plateau if plateau else "highlights compressed (a tone curve, or samples clamped)"), FLOAT_FIX)
    return Row("precision", True, f"{where}brightest {top:.3g} (expected {expected:.3g})")


def sampling(images: dict[str, tuple[np.ndarray, float]], scenes: dict[str, ProbeScene]) -> Row:
    """Each condition's white Lambertian (its mean image, its noise) against the analytic image box-filtered
    over each pixel (`box_filtered_lambert`), silhouette included: a renderer that samples each pixel at its
    centre draws the edge and a rim light's crescent otherwise, which would be booked as the renderers'
    disagreement or the material's rim."""
    found = {}
    for label, (img, noise) in images.items():
        err = relative_rmse(box_filtered_lambert(scenes[label]), img)
        point = relative_rmse(analytic_lambert(scenes[label]), img)
        found[label] = (err, beyond_noise(err, noise), point)
    worst = max(found, key=lambda k: found[k][1])
    err, far, point = found[worst]
    said = ", ".join(f"{k} {e:.2%}" for k, (e, _, _) in found.items())
    if far <= SAMPLING_TOLERANCE:
        return Row("sampling", True, f"{said} from the box-filtered analytic image (at most {far:.2%} beyond the "
                   "noise)")
    off = _sampled_off_centre(images[worst][0], scenes[worst]) if point >= min(err / 2, SAMPLING_TOLERANCE) else None
    if point < min(err / 2, SAMPLING_TOLERANCE):
        why, fix = f"; {point:.2%} from the analytic image sampled at each pixel's centre: one sample a pixel", \
            SAMPLING_FIX
    elif off is not None:
        why, fix = (f"; {off[1]:.2%} from the analytic image sampled at ({off[0][0]:g}, {off[0][1]:g}) of each pixel: "
                    "one sample a pixel, off its centre (0.5, 0.5)"), SAMPLING_FIX
    else:
        why, fix = (f"; {point:.2%} from the analytic image sampled at each pixel's centre too, and from it sampled "
                    "anywhere else in the pixel: not the pixel filter alone; the sphere's edge or the material at "
                    "grazing angles drawn otherwise"), GRAZING_FIX
    return Row("sampling", False, f"{worst}: {err:.2%} from the box-filtered analytic image ({far:.2%} beyond the "
               f"noise){why}", fix)
