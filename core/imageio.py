"""Image files: float32 EXR for data, 8-bit PNG previews for eyes. Writes are atomic."""

from __future__ import annotations

import contextlib
import os
import sys
import tempfile
from pathlib import Path

import numpy as np

from .atomic import temp_beside
from .errors import RemapError
from .metrics import exposure


def _write(path: Path, pixels: np.ndarray, fmt: str) -> None:
    import OpenImageIO as oiio  # imported here: not needed for --help

    path = Path(path)
    tmp = temp_beside(path)
    h, w, c = pixels.shape
    spec = oiio.ImageSpec(w, h, c, fmt)
    if path.suffix == ".exr":
        spec.attribute("compression", "zip")
    out = oiio.ImageOutput.create(str(tmp))
    if out is None or not out.open(str(tmp), spec):
        tmp.unlink(missing_ok=True)
        raise RemapError(f"cannot write {path}: {oiio.geterror()}")
    ok = out.write_image(pixels)
    out.close()
    if not ok:
        tmp.unlink(missing_ok=True)
        raise RemapError(f"cannot write {path}: {oiio.geterror()}")
    os.replace(tmp, path)


def write_exr(path: Path, image: np.ndarray) -> None:
    _write(path, np.ascontiguousarray(image, dtype=np.float32), "float")


@contextlib.contextmanager
def captured_stderr():
    """Capture what native libraries print on file descriptor 2 (OpenEXR reports a corrupt
    file there) so it becomes part of an error message instead of noise on the terminal."""
    box = {"text": ""}
    sys.stderr.flush()
    saved = os.dup(2)
    with tempfile.TemporaryFile(mode="w+b") as tmp:
        os.dup2(tmp.fileno(), 2)
        try:
            yield box
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            tmp.seek(0)
            box["text"] = tmp.read().decode("utf-8", "replace").strip()


def read_rgb(path: Path) -> tuple[np.ndarray | None, str, int]:
    """(pixels H x W x 3 float32, or None; why not; channel count). Never prints."""
    import OpenImageIO as oiio

    with captured_stderr() as err:
        inp = oiio.ImageInput.open(str(path))
        if inp is None:
            pixels, nch, why = None, 0, oiio.geterror()
        else:
            nch = inp.spec().nchannels
            pixels = inp.read_image(0, 0, 0, 3, "float") if nch >= 3 else None
            why = oiio.geterror() if pixels is None and nch >= 3 else ""
            inp.close()
    if not why:
        lines = err["text"].splitlines()
        why = lines[-1] if lines else ("no RGB channels" if pixels is None else "")
    return (None if pixels is None else np.asarray(pixels, dtype=np.float32)), why, nch


def read_image(path: Path) -> np.ndarray:
    pixels, why, _ = read_rgb(path)
    if pixels is None:
        raise RemapError(f"cannot read image {path}: {why}")
    return pixels


def _srgb(x: np.ndarray) -> np.ndarray:
    x = np.clip(x, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def preview(image: np.ndarray, scale: float, compress: float = 30.0) -> np.ndarray:
    """Linear image to 8-bit sRGB. ``scale`` maps the reference's bright end to 1 (shared by
    source and target); a log curve then lifts the dim body of the sphere next to a sharp
    highlight, which a linear preview shows as black."""
    x = np.clip(np.asarray(image, np.float64) * scale, 0.0, None)
    x = np.log1p(compress * x) / np.log1p(compress)
    return (np.round(_srgb(x) * 255)).astype(np.uint8)


def error_preview(err: np.ndarray, full_scale: float = 0.1) -> np.ndarray:
    """Per-pixel error (0..full_scale) as a black-red-yellow-white ramp."""
    t = np.clip(err / full_scale, 0.0, 1.0)[..., None]
    return (np.round(np.clip(np.concatenate([3 * t, 3 * t - 1, 3 * t - 2], axis=-1), 0, 1) * 255)).astype(np.uint8)


def write_png(path: Path, pixels8: np.ndarray) -> None:
    _write(path, np.ascontiguousarray(pixels8), "uint8")


def write_previews(out_dir: Path, source: np.ndarray, target: np.ndarray, err: np.ndarray) -> None:
    k = exposure(source)
    write_png(out_dir / "source.png", preview(source, k))
    write_png(out_dir / "target.png", preview(target, k))
    write_png(out_dir / "error.png", error_preview(err))
