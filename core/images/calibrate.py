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

from ..data.metrics import beyond_noise, clipped_at, relative_rmse
from ..host import judge
from ..host.analytic import analytic_lambert, box_filtered_lambert
from ..host.check import inner_pixels
from ..host.judge import Row
from .exported import ALBEDO, CALIBRATION, Shot
from .folder import ImageFolder

UNITS_TOLERANCE = 0.02
"""The calibration's probe within this of the analytic radiance beyond its noise (Mitsuba from its exported
XML: 0.3 %; Cycles from the exported USD: see docs/images.md)."""
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
            clip, levels = clipped_at(img), judge.quantised(img)
            words = ([levels] if levels else []) + (
                [f"{clip[1]} pixels at exactly {clip[0]:.4g} (clipped)"] if clip and not levels else [])
            if words:
                return [Row("precision", False, f"{path.name}: {' and '.join(words)}", "write 32-bit or half float "
                            "EXR: no 8-bit output, no tone curve or view transform that stops at 1")]
    return out


def _bright(folder: ImageFolder) -> Row | None:
    if not any(s.name == "bright" for s in folder.manifest.shots):
        return None  # a probe of no point light: no bright shot was exported
    shot = next((s for s in folder.given if s.name == "bright"), None)
    if shot is None:
        return Row("precision", False, "no image of the bright shot", "render bright.seed0.exr and .seed1.exr of the "
                   "calibration material: it shows whether highlights clip")
    img, _ = _pair(folder, shot)
    return judge.bright(img, analytic_lambert(shot.scene, ALBEDO), where="bright: ")


def _seeds(folder: ImageFolder) -> Row | None:
    for shot in folder.given:
        files = folder.files(shot)
        if len(files) == 2 and np.array_equal(folder.image(shot, 0), folder.image(shot, 1)):
            return Row("seed", False, f"{shot.name}: seeds 0 and 1 gave one image", "render .seed1.exr with the "
                       "sampler's seed 1 (its noise is how far a result is judged beyond)")
    return None


def _conditions(folder: ImageFolder) -> list[Row]:
    """Each shot but the probe's against its box-filtered analytic image (`box_filtered_lambert`, silhouette
    included): what the renderer draws of that light, and how it samples the sphere's edge."""
    out = []
    for shot in folder.given:
        if shot.name in ("probe", "bright"):
            continue
        img, noise = _pair(folder, shot)
        err = relative_rmse(box_filtered_lambert(shot.scene, ALBEDO), img)
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
    encoded = judge.encoding(img, want, inner, "probe: ")
    if encoded.passed is False:
        return [encoded]
    found = [judge.units(img, want, inner, UNITS_TOLERANCE, noise or 0.0, "probe: "),
             judge.orientation(img, want, inner, "probe: ")]
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
