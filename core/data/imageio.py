"""Image files: float32 EXR for data, 8-bit PNG previews for eyes. Writes are atomic."""

from __future__ import annotations

import contextlib
import os
import sys
import tempfile
from pathlib import Path

import numpy as np

from .atomic import temp_beside, why
from .errors import RemapError


def _write(path: Path, pixels: np.ndarray, fmt: str) -> None:
    import OpenImageIO as oiio  # imported here: not needed for --help

    path = Path(path)
    tmp = temp_beside(path)
    try:
        h, w, c = pixels.shape
        spec = oiio.ImageSpec(w, h, c, fmt)
        if path.suffix == ".exr":
            spec.attribute("compression", "zip")
        out = oiio.ImageOutput.create(str(tmp))
        if out is None or not out.open(str(tmp), spec):
            raise RemapError(f"cannot write {path}: {_reason(tmp)}")
        ok = out.write_image(pixels)
        ok = out.close() and ok  # a full disk shows at close, when the file is flushed
        if not ok or tmp.stat().st_size == 0:
            raise RemapError(f"cannot write {path}: {_reason(tmp)} (the previous file, if any, is kept)")
        os.replace(tmp, path)
    except OSError as exc:
        raise RemapError(f"cannot write {path}: {why(exc)} (the previous file, if any, is kept)") from None
    finally:
        tmp.unlink(missing_ok=True)


def _reason(tmp: Path) -> str:
    import shutil

    import OpenImageIO as oiio

    said = oiio.geterror().strip()
    try:
        full = shutil.disk_usage(tmp.parent).free < 1 << 20
    except OSError:
        full = False
    return "no space left on the device" if full and not said else (said or "the image library gave no reason")


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


HALF_EPS = 2.0 ** -11
"""A half float's relative rounding (0.05 %): a renderer that writes only half-float EXR (POV-Ray) rounds
each pixel by at most this, far below the render noise a fit meets (0.3 % and more at 16 spp) and the
fit's finite-difference steps: `remap check` passes it, with a note, and allows the lobes' sum its
rounding."""


def _bottom_up(path: Path) -> bool:
    """A PFM (magic "PF" or "Pf") stores the image's bottom row first, and OpenImageIO 3.0 hands its
    rows back as stored: one written as the format says (every PFM writer) reads upside down unless
    flipped. (OpenImageIO opens it as "pnm", as it does the top-down PPM: hence the magic.)"""
    try:
        with open(path, "rb") as f:
            return f.read(2) in (b"PF", b"Pf")
    except OSError:
        return False


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
            if pixels is not None and _bottom_up(path):
                pixels = pixels[::-1]
            inp.close()
    if not why:
        lines = err["text"].splitlines()
        why = lines[-1] if lines else ("no RGB channels" if pixels is None else "")
    return (None if pixels is None else np.asarray(pixels, dtype=np.float32)), why, nch


def pixel_format(path: Path) -> str:
    """The stored pixel type of an image file ("half", "float", "uint8", ...), "" when unreadable."""
    import OpenImageIO as oiio

    with captured_stderr():
        inp = oiio.ImageInput.open(str(path))
        if inp is None:
            return ""
        fmt = str(inp.spec().format)
        inp.close()
    return fmt


def read_image(path: Path) -> np.ndarray:
    pixels, why, _ = read_rgb(path)
    if pixels is None:
        raise RemapError(f"cannot read image {path}: {why}")
    return pixels


DISPLAY, VIEW, LINEAR = "sRGB - Display", "ACES 1.0 - SDR Video", "Linear Rec.709 (sRGB)"
"""The display transform of previews: OpenColorIO's ACES 1.0 SDR view for an sRGB display, from
the configuration OpenImageIO ships (a filmic curve: highlights roll off instead of clipping)."""
PREVIEW_SIZE = 256
_LUMA = np.array([0.2126, 0.7152, 0.0722])


def display_exposure(source: np.ndarray) -> float:
    """The scale shared by a source and its remap: the source's lit pixels' 99th-percentile
    luminance becomes 1 (the tone curve's shoulder takes a sharp highlight above it)."""
    lum = np.asarray(source, np.float64) @ _LUMA
    lit = lum[lum > 1e-6 * max(float(lum.max()), 1e-30)]
    top = float(np.percentile(lit, 99)) if lit.size else 0.0
    return 1.0 / top if top > 0 else 1.0


def preview(image: np.ndarray, scale: float) -> np.ndarray:
    """Linear RGB, scaled, through the display transform: 8-bit sRGB, at least PREVIEW_SIZE
    pixels across (each rendered pixel repeated: nothing interpolated)."""
    import OpenImageIO as oiio

    buf = oiio.ImageBuf(np.ascontiguousarray(np.clip(np.asarray(image, np.float32) * scale, 0.0, None)))
    shown = oiio.ImageBufAlgo.ociodisplay(buf, DISPLAY, VIEW, LINEAR)
    if shown.has_error:
        raise RemapError(f"display transform failed: {shown.geterror()}")
    px = np.clip(shown.get_pixels(oiio.FLOAT)[..., :3], 0.0, 1.0)
    return _enlarge(np.round(px * 255).astype(np.uint8))


def _enlarge(px: np.ndarray) -> np.ndarray:
    k = -(-PREVIEW_SIZE // px.shape[1])  # by the width: a fit scene's views stack below each other
    return np.repeat(np.repeat(px, k, axis=0), k, axis=1) if k > 1 else px


def error_scale(err: np.ndarray) -> float:
    """The error map's full scale: its 99th percentile where there is error, rounded up to 1, 2
    or 5 times a power of ten (and at least 1 %)."""
    e = err[err > 0]
    top = max(float(np.percentile(e, 99)) if e.size else 0.0, 0.01)
    mag = 10 ** np.floor(np.log10(top))
    return float(next(m * mag for m in (1, 2, 5, 10) if m * mag >= top - 1e-12))


def error_preview(err: np.ndarray, full_scale: float) -> np.ndarray:
    """Per-pixel error (0..full_scale) as a black-red-yellow-white ramp, with a colour bar on the
    right and its scale written on it."""
    t = np.clip(err / full_scale, 0.0, 1.0)[..., None]
    ramp = lambda t: np.clip(np.concatenate([3 * t, 3 * t - 1, 3 * t - 2], axis=-1), 0, 1)  # noqa: E731
    img = _enlarge(np.round(ramp(t) * 255).astype(np.uint8))
    h = img.shape[0]
    bar = np.zeros((h, 64, 3), np.uint8)
    column = ramp(np.linspace(1.0, 0.0, h)[:, None, None])[:, 0, :]
    bar[8:h - 8, 6:22] = np.round(column[8:h - 8, None, :] * 255).astype(np.uint8)
    return _label(np.concatenate([img, bar], axis=1), [(img.shape[1] + 24, 18, f"{100 * full_scale:.3g}%"),
                                                       (img.shape[1] + 24, h - 8, "0")])


def _label(px: np.ndarray, texts: list[tuple[int, int, str]]) -> np.ndarray:
    import OpenImageIO as oiio

    buf = oiio.ImageBuf(np.ascontiguousarray(px.astype(np.float32) / 255.0))
    for x, y, text in texts:
        oiio.ImageBufAlgo.render_text(buf, x, y, text, 14, "", (1.0, 1.0, 1.0))
    return np.round(np.clip(buf.get_pixels(oiio.FLOAT)[..., :3], 0, 1) * 255).astype(np.uint8)


def write_png(path: Path, pixels8: np.ndarray) -> None:
    _write(path, np.ascontiguousarray(pixels8), "uint8")


def write_previews(out_dir: Path, source: np.ndarray, target: np.ndarray, prefix: str = "") -> float:
    """source.png, target.png (one exposure, from the source) and error.png (each name after
    ``prefix``); returns the error map's full scale (a fraction of the source's bright end)."""
    k = display_exposure(source)
    write_png(out_dir / f"{prefix}source.png", preview(source, k))
    write_png(out_dir / f"{prefix}target.png", preview(target, k))
    err = np.abs((np.asarray(target, np.float64) - np.asarray(source, np.float64)) @ _LUMA) * k
    scale = error_scale(err)
    write_png(out_dir / f"{prefix}error.png", error_preview(err, scale))
    return scale
