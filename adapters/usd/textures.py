"""A UsdPreviewSurface input driven by a UsdUVTexture: the image's mean in the texture's colour space
(sourceColorSpace: sRGB, raw, or auto, which USD reads by the file's own type) through its scale and
bias, the constant it converts with. The maps are not remapped texel by texel: the model is rendered
untextured (said in `textured`)."""

from __future__ import annotations

from pathlib import Path

from brdfremap.core.data.errors import ConfigError
from brdfremap.core.data.textures import mean_value, read_values, texture

CHANNELS = {"r": 0, "g": 1, "b": 2, "a": 3}
"""A UsdUVTexture's outputs: one channel each, or its colour (rgb)."""
EIGHT_BIT_SRGB = {".png", ".jpg", ".jpeg", ".bmp", ".tga"}
"""Files `auto` reads as sRGB (8-bit images, as USD's own image readers do); others as raw."""


def read_texture(inp, source, name: str, iname: str, notes: list[str], textured: list[str]):
    """The input's constant from the texture that drives it, or None (its default) where the image
    cannot be read, with a note either way."""
    from pxr import UsdShade

    node = UsdShade.Shader(source.source.GetPrim())
    node_id = node.GetIdAttr().Get() or ""
    if node_id != "UsdUVTexture":
        textured.append(f"{iname} <- {node_id or 'a shader'} {node.GetPath()}")
        notes.append(f"inputs:{iname} is driven by {node_id or 'a shader'}: read at its default")
        return None
    asset = _get(node, "file")
    shown = asset.path if asset is not None else ""
    textured.append(f"{iname} <- UsdUVTexture {shown!r}")
    try:
        mean = _mean(node, asset, source.sourceName, f"{name}: inputs:{iname}")
    except ConfigError as exc:
        notes.append(f"inputs:{iname}: {exc}: read at its default")
        return None
    notes.append(f"inputs:{iname} <- {shown!r}: converted with the image's mean (the maps are not remapped texel by "
                 "texel for this model)")
    return mean


def _get(node, name: str):
    inp = node.GetInput(name)
    return inp.Get() if inp else None


def _mean(node, asset, output: str, where: str):
    """The texture's mean through its scale and bias, in linear values."""
    from pxr import Ar

    resolved = asset.resolvedPath if asset is not None else ""
    if resolved and Ar.IsPackageRelativePath(resolved):
        raise ConfigError(f"its image {asset.path!r} is inside the .usdz package (not read here: unzip the "
                          "package and convert its .usdc)")
    if not resolved or not Path(resolved).is_file():
        raise ConfigError(f"its image {asset.path if asset is not None else ''!r} is not found beside the stage")
    if output == "a":
        raise ConfigError("it reads the image's alpha (not read here)")
    space = str(_get(node, "sourceColorSpace") or "auto")
    srgb = space == "sRGB" or (space == "auto" and Path(resolved).suffix.lower() in EIGHT_BIT_SRGB)
    channel = CHANNELS.get(output)
    tex = texture(resolved, "srgb" if srgb else "linear", channel=channel, where=where)
    values = read_values(tex, "scalar" if channel is not None else "rgb", where=where)
    mean = mean_value(values)
    scale = [float(x) for x in (_get(node, "scale") or (1, 1, 1, 1))]
    bias = [float(x) for x in (_get(node, "bias") or (0, 0, 0, 0))]
    if channel is not None:
        return float(mean) * scale[channel] + bias[channel]  # type: ignore[arg-type]
    return tuple(float(m) * s + b for m, s, b in zip(mean, scale, bias))  # type: ignore[arg-type]
