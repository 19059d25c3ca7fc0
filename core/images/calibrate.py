"""The calibration images checked before anything is fitted: the white Lambertian of the export rendered
by the user's renderer, against its analytic image (`core.host.analytic`). The rows are `remap check`'s
(`core.host.check`: units, orientation, seed, precision) on images instead of renders, with the
encoding named (a gamma or sRGB curve: the pixels go as a power of the radiance), and each point-light
condition's agreement with the analytic image measured. A material's own images are checked for what
any image can show (finite, a black background, clipped, 8-bit)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..data.errors import ConfigError

from ..data.metrics import beyond_noise, clipped_at, eight_bit, relative_rmse
from ..host.analytic import analytic_lambert
from ..host.check import FLIP_FIX, PLACEMENTS, SHIFT_FIX, SHIFTS, usual_factor, inner_pixels, placements, Row
from .exported import ALBEDO, CALIBRATION, Shot
from ..data.scene import ProbeScene
from .folder import ImageFolder, downsampled

UNITS_TOLERANCE = 0.02
"""The calibration's probe within this of the analytic radiance beyond its noise (Mitsuba from its exported
XML: 0.3 %; Cycles from the exported USD: see docs/images.md)."""
GAMMA_TOLERANCE = 0.08
"""The pixels go as the radiance to a power further than this from 1: an encoded image (sRGB: about 0.45)."""
BRIGHT_TOLERANCE = 0.9
"""The bright shot's brightest pixel at least this fraction of its analytic value: a renderer that clamps
samples or rolls highlights off below it would cut a material's highlights as well."""
CONDITION_TOLERANCE = 0.10
"""A point-light condition further than this beyond its noise from the analytic image: the renderer draws
that light otherwise (a grazing or rim light a renderer places or samples wrong), which no fit can absorb."""


def _pair(folder: ImageFolder, shot: Shot) -> tuple[np.ndarray, float | None]:
    """The shot's mean image and its noise (None: one seed given)."""
    imgs = [folder.image(shot, i).astype(np.float64) for i in range(len(folder.files(shot)))]
    if len(imgs) < 2:
        return imgs[0], None
    return (imgs[0] + imgs[1]) / 2, relative_rmse(imgs[0], imgs[1]) / 2


def _basic(name: str, img: np.ndarray) -> str | None:
    if not np.isfinite(img).all():
        return f"{name}: has pixels that are not finite numbers (NaN or infinity)"
    if (img < 0).any():
        return f"{name}: has negative pixels (a denoiser's or a sharpening filter's ringing)"
    if max(float(img[0, 0].max()), float(img[-1, -1].max())) != 0:
        return f"{name}: the background is not black (a world colour, an environment seen directly)"
    return None


def quantized(img: np.ndarray) -> tuple[int, float] | None:
    """(levels, step) where the lit pixels take at most 256 values, all whole multiples of one step: an 8-bit
    image, whatever it was scaled by after (an exposure undone); float renders take nearly one value a pixel."""
    lit = np.asarray(img, np.float64)
    lit = lit[lit > 0]
    levels = np.unique(lit)
    if lit.size < 1024 or not 2 <= levels.size <= 256:
        return None
    step = float(np.diff(np.concatenate([[0.0], levels])).min())
    ratio = levels / step
    return (int(levels.size), step) if np.allclose(ratio, np.round(ratio), atol=1e-3) else None


def image_rows(folder: ImageFolder) -> list[Row]:
    """What any image must be (the calibration's or a material's): finite, non-negative, a black
    background, not clipped at 1, not 8-bit."""
    out = []
    for shot in folder.given:
        for i, path in enumerate(folder.files(shot)):
            img = folder.image(shot, i)
            why = _basic(path.name, img)
            if why:
                return [Row("images", False, why, "render the sphere alone: no world light seen by the camera, no "
                            "denoiser, no post-processing")]
            clip, levels, steps = clipped_at(img), eight_bit(img), quantized(img)
            words = ([f"every pixel one of 256 {levels} levels (8-bit)"] if levels else [
                f"every lit pixel one of {steps[0]} levels {steps[1]:.4g} apart (8-bit, scaled)"] if steps else []) + (
                [f"{clip[1]} pixels at exactly {clip[0]:.4g} (clipped)"] if clip and not steps else [])
            if words:
                return [Row("precision", False, f"{path.name}: {' and '.join(words)}", "write 32-bit or half float "
                            "EXR: no 8-bit output, no tone curve or view transform that stops at 1")]
    return out


def _encoding(img: np.ndarray, want: np.ndarray, inner: np.ndarray) -> Row | None:
    """The power the pixels go as of the radiance (a log-log line through the lit interior): an encoded
    image (sRGB, a display gamma) is named as such, not as a units factor or a shift."""
    errors = placements(want, img, inner, same_total=True)
    want = PLACEMENTS[min(errors, key=errors.get)](want)  # a flipped image's curve, as it lies
    lit = inner & (want.mean(axis=2) > 0.02 * want.max()) & (img.mean(axis=2) > 0)
    if lit.sum() < 16:
        return None
    x, y = np.log(want[lit].mean(axis=1)), np.log(img[lit].mean(axis=1))
    power = float(np.polyfit(x, y, 1)[0])
    if abs(power - 1.0) <= GAMMA_TOLERANCE:
        return None
    return Row("encoding", False, f"probe: the pixels go as the radiance to the power {power:.2f}, not 1: "
               f"{'gamma- or sRGB-encoded (a display curve)' if power < 1 else 'a curve applied, or not the white Lambertian of albedo 0.8 the export holds'}",
               "write linear radiance: no view transform or display curve (Blender: Standard; other renderers: "
               "linear, raw or scene-referred output), no gamma")


def _units(img: np.ndarray, noise: float | None, want: np.ndarray, inner: np.ndarray) -> Row:
    errors = placements(want, img, inner)
    best = min(errors, key=errors.get)
    far = beyond_noise(errors[best], noise or 0.0)
    if far < UNITS_TOLERANCE:
        return Row("units", True, f"probe: {errors[best]:.2%} from the analytic radiance ({far:.2%} beyond the noise)")
    ratio = float(img[inner].sum() / max(float(want[inner].sum()), 1e-30))
    known = usual_factor(ratio)
    said = f" (a factor of {known})" if known else ""
    return Row("units", False, f"probe: {errors[best]:.2%} from the analytic radiance; the image is {ratio:.4g}x it"
               f"{said}", "pixels are radiance (W m^-2 sr^-1): no exposure or gain; a point light's intensity is "
               "radiant intensity in W/sr (a power P in W is 4π·I); the calibration material's albedo is 0.8")


def _orientation(img: np.ndarray, want: np.ndarray, inner: np.ndarray) -> Row:
    errors = placements(want, img, inner, same_total=True)
    best = min(errors, key=errors.get)
    if best == "as expected":
        return Row("orientation", True, f"probe: {errors[best]:.2%} from the expected image (scaled to its total)")
    return Row("orientation", False, f"probe: the image is {best} ({errors[best]:.2%} from that, "
               f"{errors['as expected']:.2%} from the expected one)", SHIFT_FIX if best in SHIFTS else FLIP_FIX)


def _bright(folder: ImageFolder) -> Row | None:
    if not any(s.name == "bright" for s in folder.manifest.shots):
        return None  # a probe of no point light: no bright shot was exported
    shot = next((s for s in folder.given if s.name == "bright"), None)
    if shot is None:
        return Row("precision", False, "no image of the bright shot", "render bright.seed0.exr and .seed1.exr of the "
                   "calibration material: it shows whether highlights clip")
    img, _ = _pair(folder, shot)
    want = analytic_lambert(shot.scene, ALBEDO)
    top, expected = float(img.max()), float(want.max())
    if top < BRIGHT_TOLERANCE * expected:
        return Row("precision", False, f"bright: the brightest pixel is {top:.3g} where it should be {expected:.3g}: "
                   "clipped or compressed", "write float EXR with no tone curve (highlights far above 1 are kept)")
    return Row("precision", True, f"bright: brightest {top:.3g} (expected {expected:.3g})")


def _seeds(folder: ImageFolder) -> Row | None:
    for shot in folder.given:
        files = folder.files(shot)
        if len(files) == 2 and np.array_equal(folder.image(shot, 0), folder.image(shot, 1)):
            return Row("seed", False, f"{shot.name}: seeds 0 and 1 gave one image", "render .seed1.exr with the "
                       "sampler's seed 1 (its noise is how far a result is judged beyond)")
    return None


SUPERSAMPLE = 4
"""The analytic image a condition is judged against is box-filtered from this many times its resolution (a
renderer's box pixel filter): a rim light's crescent is a few pixels, point-sampled 25 % off at 48 px."""


def filtered_lambert(scene: ProbeScene) -> np.ndarray:
    """The white Lambertian's analytic image as a box pixel filter makes it, silhouette included."""
    fine = analytic_lambert(scene.with_(resolution=scene.resolution * SUPERSAMPLE), ALBEDO)
    return downsampled(fine, scene.resolution, scene.name)


def _conditions(folder: ImageFolder) -> list[Row]:
    """Each shot but the probe's against its box-filtered analytic image (`filtered_lambert`, silhouette
    included): what the renderer draws of that light, and how it samples the sphere's edge."""
    out = []
    for shot in folder.given:
        if shot.name in ("probe", "bright"):
            continue
        img, noise = _pair(folder, shot)
        err = relative_rmse(filtered_lambert(shot.scene), img)
        far = beyond_noise(err, noise or 0.0)
        ok = far <= CONDITION_TOLERANCE
        out.append(Row(f"light {shot.name}", ok, f"{shot.label}: {err:.2%} from the analytic image ({far:.2%} beyond "
                       "the noise)", "" if ok else "check how the renderer places, scales and samples this light"))
    return out


def calibration_rows(folder: ImageFolder, material: ImageFolder) -> list[Row]:
    """Every row of the calibration images (`folder`) for a material's (`material`): the shots the material
    has must be in the calibration too."""
    missing = [s.name for s in material.given if s not in folder.given]
    if missing or not any(s.name == "probe" for s in folder.given):
        names = ", ".join(missing or ["probe"])
        return [Row("calibration", False, f"no calibration image of {names}", f"render {names} of the calibration "
                    f"material (the exported material.xml / the USD's own material) into {folder.folder}")]
    rows = image_rows(folder)
    if rows:
        return rows
    probe = next(s for s in folder.given if s.name == "probe")
    img, noise = _pair(folder, probe)
    want, inner = analytic_lambert(probe.scene, ALBEDO), inner_pixels(probe.scene)
    encoded = _encoding(img, want, inner)
    if encoded is not None:
        return [encoded]
    found = [_units(img, noise, want, inner), _orientation(img, want, inner)]
    # The bright shot and each other shot are judged only on images placed and scaled right: else their rows
    # repeat those causes (a 1/(4π) in the units read as clipping).
    if not all(r.passed for r in found):
        return found + [r for r in [_seeds(folder)] if r is not None]
    return [r for r in (*found, _bright(folder), _seeds(folder)) if r is not None] + _conditions(folder)


class ImagesRejected(ConfigError):
    """Images that would corrupt a fit: every failing row, one line each."""


def checked(path: str | Path) -> ImageFolder:
    """A material's folder of images, its own images and its calibration's checked before anything is
    fitted: each failing row is one line of the error (naming the folder), nothing is fitted to a wrong
    image. No calibration folder is no failure: the result says it is uncalibrated."""
    folder = ImageFolder.open(path)
    if folder.folder.name == CALIBRATION:
        raise ConfigError("is the calibration's folder (the white Lambertian as exported), not a material's: give "
                          "the folder of your material's images beside it", file=str(folder.folder))
    if not any(s.name == "probe" for s in folder.given):
        raise ConfigError(f"has no image of the probe (probe.seed0.exr){_strays(folder)}: render "
                          f"{folder.manifest_path.parent}'s probe scene with the material, as SHEET.md says",
                          file=str(folder.folder))
    rows, where = image_rows(folder) or [r for r in [_seeds(folder)] if r is not None], folder.folder
    if folder.calibration is not None and not rows:
        rows, where = calibration_rows(folder.calibration, folder), folder.calibration.folder
    failed = [r for r in rows if r.passed is False]
    if failed:
        lines = "\n".join(f"  {r.name}: {r.detail} -> {r.fix}" for r in failed)
        whose = "its images" if where == folder.folder else f"the calibration's images (for {folder.folder.name})"
        raise ImagesRejected(f"not fitted: {len(failed)} check(s) of {whose} failed:\n{lines}", file=str(where))
    return folder


def _strays(folder: ImageFolder) -> str:
    """The images in the folder no shot is named by (a misnamed render), said where the probe is missing."""
    named = {s.file(i) for s in folder.manifest.shots for i in range(2)}
    stray = sorted(p.name for p in folder.folder.iterdir() if p.suffix.lower() in (".exr", ".hdr", ".pfm", ".png")
                   and p.name not in named)
    return f"; it holds {', '.join(stray[:6])}{' …' if len(stray) > 6 else ''}, named otherwise (SHOT.seed0.exr, " \
        "SHOT.seed1.exr)" if stray else ""
