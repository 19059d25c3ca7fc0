"""Textures: images that drive a material's parameters texel by texel.

A `Texture` names an image file, how its pixel values become parameter values (an sRGB-encoded
colour map is decoded through OpenColorIO; a data map is read as it is), and its filtering. Read,
a texture is an array of linear values: H x W for a scalar parameter (an RGB image gives its
luminance, as renderers turn a colour into a number, or the one channel its `channel` names),
H x W x 3 for an RGB one; a colour with an alpha channel is read as stored (straight), not
multiplied by it. Written, a colour map (an RGB parameter within [0, 1]) is a 16-bit sRGB PNG, and a
data map (a roughness, an IOR) a float EXR, read as it is.

The probe sphere's texture coordinates, which every adapter that renders textures realises:
u = φ / 2π and v = θ / π of the sphere's own frame (its pole along the image's up, +y; θ = 0 at
the top pole; φ = 0 towards the image's right, +x, increasing away from the viewer, so the half the
camera sees is u from 0.5 to 1), and an image's top row at v = 0, its left column at u = 0.
`tests/adapters/test_adapter_textures.py` checks each adapter against another with a checker of colours."""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from pathlib import Path
from enum import StrEnum

import numpy as np
from pydantic import Field

from .errors import ConfigError
from .kinds import ParamKind
from .model import Strict

SRGB, LINEAR = "srgb_tx", "lin_rec709"
"""OpenColorIO's names (the configuration OpenImageIO ships) for an sRGB-encoded texture and linear Rec.709."""
LUMA = np.array([0.2126, 0.7152, 0.0722])
MAX_TEXELS = 8192 * 8192


class ColourSpace(StrEnum):
    """How a texture's values are encoded: sRGB (a colour map), or linear (a data map, an EXR)."""

    SRGB = "srgb"
    LINEAR = "linear"


class Filter(StrEnum):
    LINEAR = "linear"
    NEAREST = "nearest"


class Texture(Strict):
    """An image that drives one parameter, texel by texel."""

    file: str = Field(description="The image file (absolute).")
    colorspace: ColourSpace = Field(description="srgb: its values are sRGB-encoded (a colour map "
                                                              "read as a renderer decodes it); linear: read as "
                                                              "they are (a data map, an EXR).")
    filter: Filter = Field(Filter.LINEAR, description="How a renderer interpolates it.")
    channel: int | None = Field(None, ge=0, le=3, description="A scalar parameter read from this one channel of "
                                                            "the image (a packed map); None: its luminance.")
    sha256: str = Field("", description="The file's content (a changed image is another job).")


@dataclass(frozen=True)
class TextureMap:
    """A parameter's values texel by texel, as an adapter renders them: linear, float32, H x W (scalar)
    or H x W x 3 (RGB), row 0 the image's top; ``filter`` how to interpolate between texels."""

    values: np.ndarray
    filter: str = "linear"


MAX_FILE_BYTES = 2 << 30


def texture(path: str | Path, colorspace: str, filter: str = "linear", *, channel: int | None = None,
            where: str = "") -> Texture:
    """A texture of this file, hashed; a file that is not there, not a regular file, too large or
    unreadable is a ConfigError naming it (and ``where`` the material and input that use it)."""
    p = Path(path)
    at = f" ({where})" if where else ""
    try:
        if not p.is_file():
            raise ConfigError(f"is not an image file{at}: check the path", file=str(p))
        if p.stat().st_size > MAX_FILE_BYTES:
            raise ConfigError(f"is over {MAX_FILE_BYTES >> 30} GiB{at}: not read as a texture", file=str(p))
        digest = hashlib.sha256()
        with open(p, "rb") as f:
            for block in iter(lambda: f.read(1 << 20), b""):
                digest.update(block)
    except OSError as exc:
        raise ConfigError(f"cannot read the texture: {exc.strerror or exc}{at}", file=str(p)) from None
    return Texture(file=str(p.resolve()), colorspace=colorspace, filter=filter, channel=channel,  # type: ignore
                   sha256=digest.hexdigest())


def read_values(tex: Texture, kind: str, where: str = "") -> np.ndarray:
    """The texture's linear values: H x W (scalar; an RGB image's luminance, or its ``channel``) or
    H x W x 3 (RGB; a grey image repeated), float32, row 0 the image's top."""
    import OpenImageIO as oiio

    from .imageio import captured_stderr

    at = f" ({where})" if where else ""
    config = oiio.ImageSpec()
    config.attribute("oiio:UnassociatedAlpha", 1)  # colour as stored, not multiplied by the alpha
    with captured_stderr() as said:
        buf = oiio.ImageBuf(tex.file, 0, 0, config)
        spec = buf.spec()
        if not buf.has_error and spec.width * spec.height > MAX_TEXELS:
            raise ConfigError(f"{spec.width} x {spec.height} texels: at most {MAX_TEXELS} in one texture{at}",
                              file=tex.file)
        ok = not buf.has_error and buf.read(force=True)
        px = np.asarray(buf.get_pixels(oiio.FLOAT), np.float32) if ok else None
    if px is None or buf.has_error or spec.nchannels < 1 or px.ndim != 3:
        why = (buf.geterror() or said["text"] or "no pixels").strip().splitlines()[0]
        raise ConfigError(f"cannot read the texture: {why}{at}", file=tex.file)
    if tex.channel is not None:
        # A grey image (with or without alpha) has its grey in every colour channel, as viewers expand it.
        channel = 0 if px.shape[-1] < 3 and tex.channel < 3 else tex.channel
        if channel >= px.shape[-1]:
            raise ConfigError(f"has {px.shape[-1]} channels, and channel {tex.channel} is read{at}", file=tex.file)
        px = np.repeat(px[..., channel:channel + 1], 3, axis=-1)
    else:
        px = px[..., :3] if px.shape[-1] >= 3 else np.repeat(px[..., :1], 3, axis=-1)
    if tex.colorspace == ColourSpace.SRGB:
        px = _convert(px, SRGB, LINEAR)
    if not np.isfinite(px).all():
        bad = int((~np.isfinite(px)).any(axis=-1).sum())
        raise ConfigError(f"has {bad} texels that are not finite numbers (NaN or infinity){at}: fix the image",
                          file=tex.file)
    return np.ascontiguousarray(px @ LUMA.astype(np.float32) if kind == ParamKind.SCALAR else px)


def mean_value(values: np.ndarray) -> float | tuple[float, ...]:
    """A map's mean (float64): a number for H x W values, a colour for H x W x 3."""
    m = values.reshape(-1, values.shape[-1]).mean(axis=0, dtype=np.float64) if values.ndim == 3 else \
        values.mean(dtype=np.float64)
    return tuple(float(x) for x in m) if np.ndim(m) else float(m)


def colour_to_linear(rgb: tuple[float, float, float], space: str, where: str = "") -> tuple[float, float, float]:
    """One colour from a named colour space (OpenColorIO's built-in configuration knows MaterialX's
    names: acescg, srgb_texture, lin_displayp3 ...) to linear Rec.709; an unknown space is a
    ConfigError naming it."""
    import OpenImageIO as oiio

    if not oiio.ColorConfig("ocio://default").getColorSpaceIndex(space) >= 0:
        raise ConfigError(f"{where + ': ' if where else ''}colour space {space!r} is not known to OpenColorIO's "
                          "built-in configuration (use one of MaterialX's: lin_rec709, srgb_texture, acescg ...)")
    px = _convert(np.array([[rgb]], np.float32), space, LINEAR)
    return tuple(float(x) for x in px[0, 0, :3])  # type: ignore[return-value]


def _convert(px: np.ndarray, src: str, dst: str) -> np.ndarray:
    import OpenImageIO as oiio

    out = oiio.ImageBufAlgo.colorconvert(oiio.ImageBuf(np.ascontiguousarray(px, np.float32)), src, dst)
    if out.has_error:
        raise ConfigError(f"colour conversion {src} -> {dst} failed: {out.geterror()}")
    return np.asarray(out.get_pixels(oiio.FLOAT), np.float32)[..., :3]


def resized(values: np.ndarray, width: int, height: int) -> np.ndarray:
    """Values resampled to width x height (OpenImageIO's filtered resize)."""
    import OpenImageIO as oiio

    arr = values[..., None] if values.ndim == 2 else values
    buf = oiio.ImageBufAlgo.resize(oiio.ImageBuf(np.ascontiguousarray(arr, np.float32)),
                                   roi=oiio.ROI(0, width, 0, height, 0, 1, 0, arr.shape[-1]))
    out = np.asarray(buf.get_pixels(oiio.FLOAT), np.float32)
    return out[..., 0] if values.ndim == 2 else out


PNG_COMPRESSION = 3
"""zlib's level for the 16-bit PNGs of colour maps: a 2048² map writes in about half level 6's time,
about 17 % larger."""


def kind_of_file(lower: float, upper: float, rgb: bool) -> tuple[str, str]:
    """How a target map of values in [lower, upper] is written: (extension, colorspace). A colour map
    (RGB within [0, 1]) as a 16-bit sRGB PNG; a data map as a float EXR, read as it is."""
    if rgb and lower >= 0.0 and upper <= 1.0:
        return ".png", "srgb"
    return ".exr", "linear"


def encode(values: np.ndarray, suffix: str, colorspace: str, *, bits: int = 16) -> bytes:
    """A map's file as bytes: a PNG of ``bits`` (16, or 8 for formats that take only 8-bit images: glTF;
    sRGB-encoded for a colour map) or a float EXR. The channels are as given (1, 3 or 4)."""
    import tempfile

    import OpenImageIO as oiio

    if bits not in (8, 16):
        raise ValueError(f"a PNG map is written in 8 or 16 bits, not {bits}")
    arr = values[..., None] if values.ndim == 2 else values
    arr = np.ascontiguousarray(arr, np.float32)
    if colorspace == ColourSpace.SRGB:
        arr = _convert(arr, LINEAR, SRGB)
    fmt = ("uint16" if bits == 16 else "uint8") if suffix == ".png" else "float"
    with tempfile.TemporaryDirectory(prefix="brdfremap-") as tmp:
        path = Path(tmp) / f"map{suffix}"
        spec = oiio.ImageSpec(arr.shape[1], arr.shape[0], arr.shape[2], fmt)
        if suffix == ".exr":
            spec.attribute("compression", "zip")
        else:
            spec.attribute("png:compressionLevel", PNG_COMPRESSION)
        out = oiio.ImageOutput.create(str(path))
        if out is None or not out.open(str(path), spec):
            raise ConfigError(f"cannot write a texture: {oiio.geterror()}")
        data = np.clip(arr, 0.0, 1.0) if suffix == ".png" else arr
        ok = out.write_image(data)
        if not (out.close() and ok):
            raise ConfigError(f"cannot write a texture: {oiio.geterror()}")
        return path.read_bytes()


def decode(data: bytes, suffix: str, colorspace: str, kind: str) -> np.ndarray:
    """A map's file, as `encode` wrote it, read back to its linear values (as a renderer reads the file)."""
    import tempfile

    with tempfile.TemporaryDirectory(prefix="brdfremap-") as tmp:
        path = Path(tmp) / f"map{suffix}"
        path.write_bytes(data)
        return read_values(Texture(file=str(path), colorspace=colorspace), kind)  # type: ignore[arg-type]
