"""A `gltf_pbr` material's maps as glTF textures: the base colour as an sRGB PNG (`baseColorTexture`),
metallic and roughness packed in one linear PNG (`metallicRoughnessTexture`: roughness in green,
metallic in blue, as glTF reads them), both 8-bit (glTF viewers decode 8-bit images) and embedded in
the document as data URIs, so a `.gltf` is one file. A textured factor is written as 1 (glTF
multiplies the texture by it); a constant beside a textured one keeps its factor over a channel of 1.

The texture coordinates are the probe's (`core.data.textures`): a glTF image's top row is at v = 0,
as the project's is."""

from __future__ import annotations

import base64
from pathlib import Path
from typing import Any

import numpy as np

from brdfremap.core.data.errors import ConfigError
from brdfremap.core.data.kinds import ParamKind
from brdfremap.core.data.textures import ColourSpace, Filter, Texture, TextureMap, encode, read_values, resized

NEAREST, LINEAR, LINEAR_MIPMAP_LINEAR = 9728, 9729, 9987
REPEAT, CLAMP_TO_EDGE = 10497, 33071
SAMPLERS = {Filter.NEAREST: {"magFilter": NEAREST, "minFilter": NEAREST, "wrapS": REPEAT, "wrapT": CLAMP_TO_EDGE},
            Filter.LINEAR: {"magFilter": LINEAR, "minFilter": LINEAR_MIPMAP_LINEAR, "wrapS": REPEAT,
                            "wrapT": CLAMP_TO_EDGE}}
"""Around the sphere (u) the image repeats; from pole to pole (v) it ends at its edges. A linear map
is mipmapped, as an app's textures are."""
PACKED = ("roughness", "metallic")
"""The parameters glTF reads from one image's green and blue channels (metallicRoughnessTexture)."""


def maps_from_files(folder: Path, textures: dict[str, Texture], kinds: dict[str, str]) -> dict[str, TextureMap]:
    """The maps a result (or a library) has beside its native material, as values: each file relative
    to ``folder``."""
    out = {}
    for name, tex in textures.items():
        absolute = tex.model_copy(update={"file": str((Path(folder) / tex.file).resolve())})
        out[name] = TextureMap(read_values(absolute, kinds[name], where=f"the map of {name}"), tex.filter)
    return out


def embed(doc: dict[str, Any], material: dict[str, Any], maps: dict[str, TextureMap]) -> None:
    """Add these maps to ``doc`` as images, textures and samplers, and drive ``material``'s inputs by
    them. Only `base_color`, `metallic` and `roughness` (the model's `texturable`) are taken."""
    loose = sorted(set(maps) - {"base_color", *PACKED})
    if loose:
        raise ConfigError(f"threejs gltf_pbr: {', '.join(loose)} cannot be a glTF texture here "
                          "(base_color, metallic and roughness can)")
    pbr = material["pbrMetallicRoughness"]
    if "base_color" in maps:
        m = maps["base_color"]
        pbr["baseColorTexture"] = {"index": _texture(doc, encode(m.values, ".png", ColourSpace.SRGB, bits=8),
                                                     m.filter)}
        pbr["baseColorFactor"] = [1.0, 1.0, 1.0, 1.0]
    packed = [n for n in PACKED if n in maps]
    if packed:
        values, filt = _packed(maps, pbr)
        pbr["metallicRoughnessTexture"] = {"index": _texture(doc, encode(values, ".png", ColourSpace.LINEAR, bits=8),
                                                             filt)}


def _packed(maps: dict[str, TextureMap], pbr: dict[str, Any]) -> tuple[np.ndarray, str]:
    """One H x W x 3 image: red 1 (glTF's occlusion channel, unread here), green the roughness, blue
    the metallic; a constant one's channel 1 (its factor stays). One image has one sampler: nearest
    when either map is (a map of distinct texels stays so), else linear."""
    given = [maps[n] for n in PACKED if n in maps]
    h = max(m.values.shape[0] for m in given)
    w = max(m.values.shape[1] for m in given)
    out = np.ones((h, w, 3), np.float32)
    for channel, (name, factor) in enumerate(zip(PACKED, ("roughnessFactor", "metallicFactor")), start=1):
        if name in maps:
            v = maps[name].values
            out[..., channel] = v if v.shape[:2] == (h, w) else resized(v, w, h)
            pbr[factor] = 1.0
    return out, Filter.NEAREST if any(m.filter == Filter.NEAREST for m in given) else Filter.LINEAR


def _texture(doc: dict[str, Any], png: bytes, filt: str) -> int:
    images, textures, samplers = (doc.setdefault(k, []) for k in ("images", "textures", "samplers"))
    sampler = SAMPLERS[Filter(filt)]
    if sampler not in samplers:
        samplers.append(dict(sampler))
    images.append({"mimeType": "image/png", "uri": "data:image/png;base64," + base64.b64encode(png).decode()})
    textures.append({"sampler": samplers.index(sampler), "source": len(images) - 1})
    return len(textures) - 1


def kinds(spec) -> dict[str, ParamKind]:
    """Each texturable parameter's kind (rgb or scalar), as its texture is read."""
    return {n: spec.param(n).kind for n in spec.texturable}
