"""glTF files: a converted library written as `library.gltf` (every material under its source's
name, each on a sphere of its own in a row, so any viewer shows them), and a reader of `.gltf` and
`.glb` materials (through pygltflib) as `threejs:gltf_pbr` sources."""

from __future__ import annotations

import base64
import json
import math
import urllib.parse
from pathlib import Path
from typing import Any

import numpy as np

from brdfremap.core.data.atomic import write_text_atomic
from brdfremap.core.data.errors import ConfigError
from brdfremap.core.data.schemas import Material, ModelSpec, Value
from brdfremap.core.library.entries import Converted, Entry

from brdfremap.core.data.textures import ColourSpace, Filter, Texture, TextureMap, mean_value, read_values, texture

from . import gltf, images, textures
from .models import MODELS

RINGS, SEGMENTS = 64, 128
SPACING = 2.5
"""Spheres of radius 1, this far apart along +x."""


def sphere_mesh(rings: int = RINGS, segments: int = SEGMENTS) -> dict[str, np.ndarray]:
    """A UV sphere of radius 1, its pole along +y: positions, normals, the probe's texture coordinates
    (`core.data.textures`: u = φ / 2π from +x, increasing away from a viewer on +z; v = θ / π from the
    top pole), tangents along the latitudes (the probe's: anisotropy turns from them) and triangle
    indices, counter-clockwise seen from outside."""
    theta, phi = np.meshgrid(np.linspace(0.0, math.pi, rings + 1), np.linspace(0.0, 2.0 * math.pi, segments + 1),
                             indexing="ij")
    s, c = np.sin(theta), np.cos(theta)
    pos = np.stack([s * np.cos(phi), c, -s * np.sin(phi)], axis=-1).reshape(-1, 3)
    tangent = np.stack([-np.sin(phi), np.zeros_like(phi), -np.cos(phi)], axis=-1).reshape(-1, 3)  # d(pos)/d(phi)
    uv = np.stack([phi / (2 * math.pi), theta / math.pi], axis=-1).reshape(-1, 2)
    idx = []
    for i in range(rings):
        for j in range(segments):
            a, b = i * (segments + 1) + j, (i + 1) * (segments + 1) + j
            if i > 0:
                idx += [a, b, a + 1]
            if i < rings - 1:
                idx += [a + 1, b, b + 1]
    return {"POSITION": pos.astype(np.float32), "NORMAL": pos.astype(np.float32),
            "TANGENT": np.concatenate([tangent, np.ones((pos.shape[0], 1))], axis=1).astype(np.float32),
            "TEXCOORD_0": uv.astype(np.float32), "indices": np.asarray(idx, np.uint16)}


def _mesh_parts(mesh: dict[str, np.ndarray]) -> tuple[bytes, list[dict], list[dict], dict[str, int], int]:
    """The buffer's bytes, its views and accessors, each attribute's accessor, and the indices'."""
    blob, views, accessors, attrs = b"", [], [], {}
    kinds = {1: "SCALAR", 2: "VEC2", 3: "VEC3", 4: "VEC4"}
    for name, arr in mesh.items():
        data = arr.tobytes()
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(data),
                      "target": 34963 if name == "indices" else 34962})
        acc: dict[str, Any] = {"bufferView": len(views) - 1, "componentType": 5123 if name == "indices" else 5126,
                               "count": int(arr.shape[0]), "type": kinds[1 if arr.ndim == 1 else arr.shape[1]]}
        if name == "POSITION":
            acc.update(min=[float(x) for x in arr.min(axis=0)], max=[float(x) for x in arr.max(axis=0)])
        accessors.append(acc)
        attrs[name] = len(accessors) - 1
        blob += data + b"\0" * (-len(data) % 4)
    return blob, views, accessors, {k: v for k, v in attrs.items() if k != "indices"}, attrs["indices"]


def sphere_document(materials: list[tuple[str, dict[str, Value]]], spec: ModelSpec,
                    maps: list[dict[str, TextureMap]] | None = None) -> dict[str, Any]:
    """A glTF document: each material (name, complete parameters) on a unit sphere of its own; with
    ``maps`` (one dict a material, in their order), its inputs driven by them as glTF textures."""
    maps = maps or [{} for _ in materials]
    mats = [gltf.material(name, spec.complete(params), spec) for name, params in materials]
    turned = [bool(m.get("extensions", {}).get("KHR_materials_anisotropy")) for m in mats]
    mesh = {k: v for k, v in sphere_mesh().items()
            if (k != "TEXCOORD_0" or any(maps)) and (k != "TANGENT" or any(turned))}
    blob, views, accessors, attributes, indices = _mesh_parts(mesh)
    def used(i: int) -> dict[str, int]:  # tangents only where anisotropy turns from them, UVs where a texture is
        return {k: v for k, v in attributes.items() if (k != "TANGENT" or turned[i]) and (k != "TEXCOORD_0" or maps[i])}

    doc: dict[str, Any] = {
        "asset": {"version": "2.0", "generator": gltf.GENERATOR},
        "scene": 0, "scenes": [{"nodes": list(range(len(mats)))}],
        "nodes": [{"name": m["name"], "mesh": i, "translation": [SPACING * i, 0.0, 0.0]} for i, m in enumerate(mats)],
        "meshes": [{"name": m["name"], "primitives": [{"attributes": used(i), "indices": indices, "material": i}]}
                   for i, m in enumerate(mats)],
        "materials": mats, "accessors": accessors, "bufferViews": views,
        "buffers": [{"byteLength": len(blob),
                     "uri": "data:application/octet-stream;base64," + base64.b64encode(blob).decode()}]}
    for mat, m in zip(mats, maps):
        if m:
            textures.embed(doc, mat, m)
    used = gltf.extensions_used(mats)
    if used:
        doc["extensionsUsed"] = used
    return doc


def material_document(doc: dict[str, Any], index: int) -> dict[str, Any]:
    """One material of a glTF document, alone in a document of its own (as the adapter renders one),
    with the textures, images and samplers it reads, numbered anew. Its images must be embedded as
    data URIs (as this tool writes them): the page reads nothing else."""
    mat = json.loads(json.dumps(doc["materials"][index]))
    out: dict[str, Any] = {"asset": {"version": "2.0"}, "materials": [mat]}
    refs = _texture_refs(mat)
    if refs:
        imgs, samplers, texs = [], [], []
        for ref in refs:
            tex = dict(doc["textures"][ref["index"]])
            for key, pool, into in (("source", doc.get("images", []), imgs),
                                    ("sampler", doc.get("samplers", []), samplers)):
                if key in tex:
                    item = pool[tex[key]]
                    if key == "source" and urllib.parse.urlparse(str(item.get("uri", ""))).scheme != "data":
                        raise ConfigError(f"images[{tex[key]}] is not embedded as a data URI: render the file's "
                                          "materials as this tool writes them")
                    if item not in into:
                        into.append(item)
                    tex[key] = into.index(item)
            if tex not in texs:
                texs.append(tex)
            ref["index"] = texs.index(tex)
        out.update(textures=texs, images=imgs, samplers=samplers)
    used = sorted(mat.get("extensions", {}))
    if used:
        out["extensionsUsed"] = used
    return out


def _texture_refs(node: Any) -> list[dict[str, Any]]:
    """Every texture reference ({"index": n, ...} under a glTF `...Texture` key) in a material."""
    if not isinstance(node, dict):
        return []
    found = [v for k, v in node.items() if k in gltf.TEXTURES and isinstance(v, dict) and "index" in v]
    return found + [r for k, v in node.items() if k not in gltf.TEXTURES for r in _texture_refs(v)]


class GltfLibraryWriter:
    name = "glTF 2.0 library (library.gltf)"
    adapter = "threejs"
    models: tuple[str, ...] = ()

    def write(self, folder: Path, items: list[Converted]) -> list[Path]:
        spec = MODELS["gltf_pbr"]
        kinds = textures.kinds(spec)
        maps = [textures.maps_from_files(folder, i.textures, kinds) for i in items]
        doc = sphere_document([(i.name, i.params) for i in items], spec, maps)
        return [write_text_atomic(Path(folder) / "library.gltf", json.dumps(doc, indent=1) + "\n")]


def read_document(path: Path) -> tuple[dict[str, Any], bytes | None]:
    """A .gltf or .glb file's JSON (pygltflib reads both), and a .glb's binary chunk."""
    from pygltflib import GLTF2

    try:
        g = GLTF2.load(str(path))
    except Exception as exc:  # pygltflib raises what its parser meets: JSON, struct and key errors alike
        raise ConfigError(f"cannot read it as glTF (is the file whole?): "
                          f"{str(exc).splitlines()[0] if str(exc) else type(exc).__name__}", file=str(path)) from None
    if g is None:
        raise ConfigError("cannot read it as glTF (not a .gltf or .glb file)", file=str(path))
    return json.loads(g.to_json()), g.binary_blob()


class GltfReader:
    """glTF materials as `threejs:gltf_pbr` sources. A base colour, metallic or roughness driven by its
    core texture is read as its factor times the image's mean, and (of factor 1) as that texture,
    which a table of `gltf_pbr` remaps texel by texel; every other texture-driven input is listed and
    read as its factor."""

    name = "glTF 2.0 (.gltf, .glb)"
    suffixes = (".gltf", ".glb")

    def accepts(self, path: Path) -> bool:
        return True

    def read(self, path: Path) -> list[Entry]:
        doc, blob = read_document(path)
        version = str((doc.get("asset") or {}).get("version", ""))
        if version.partition(".")[0] != "2":
            raise ConfigError(f"is glTF {version or 'of no version'}: this reads glTF 2.0", file=str(path),
                              field="asset.version")
        return [self._entry(m, i, Path(path), doc, blob) for i, m in enumerate(doc.get("materials") or [])]

    @staticmethod
    def _entry(m: Any, i: int, path: Path, doc: dict[str, Any], blob: bytes | None) -> Entry:
        """One material's entry; a malformed one (a factor that is not a number ...) is an entry that
        cannot be converted, saying which and why, so the file's other materials still are."""
        name = m.get("name") if isinstance(m, dict) and isinstance(m.get("name"), str) and m["name"] else \
            f"material {i}"
        try:
            return GltfReader._read_entry(m, name, path, doc, blob)
        except (TypeError, ValueError, AttributeError) as exc:
            return Entry(name=name, file=str(path), problem=f"materials[{i}] is malformed glTF ({_first_line(exc)}): "
                                                            "check it with the Khronos glTF validator")

    @staticmethod
    def _read_entry(m: dict[str, Any], name: str, path: Path, doc: dict[str, Any], blob: bytes | None) -> Entry:
        params, notes, textured = gltf.read_material(m)
        maps, constants, said = _maps(m, doc, blob, path, name)
        params.update(constants)
        spec = MODELS["gltf_pbr"]
        clipped = {k: spec.param(k).clip(tuple(v) if isinstance(v, (list, tuple)) else v) for k, v in params.items()}
        notes += [f"{k} {_shown(params[k])} is outside the model's bounds: read as {_shown(v)}"
                  for k, v in clipped.items() if _shown(v) != _shown(params[k])]
        return Entry(name=name, file=str(path), notes=notes + said, textured=textured,
                     material=Material(adapter="threejs", model="gltf_pbr", name=name, params=clipped,
                                       textures=maps))


def _maps(m: dict[str, Any], doc: dict[str, Any], blob: bytes | None, path: Path,
          name: str) -> tuple[dict[str, Texture], dict[str, Value], list[str]]:
    """The material's core textures: those of factor 1 as textures of their parameters (a table remaps
    them texel by texel); each one's constant, its factor times its image's mean (what a material
    without the texture would be on average, as a Mitsuba bitmap's constant is its mean); and notes."""
    wanted, notes = gltf.mapped_textures(m)
    kinds = textures.kinds(MODELS["gltf_pbr"])
    out: dict[str, Texture] = {}
    constants: dict[str, Value] = {}
    for param, index, channel, factor in wanted:
        try:
            tex = _map(doc, blob, path, index, channel, f"{name}: {param}")
            mean = mean_value(read_values(tex, kinds[param], where=f"{name}: {param}"))
        except ConfigError as exc:
            notes.append(f"{param}: {exc}: read as its factor")
            continue
        constants[param] = tuple(f * v for f, v in zip(factor, mean)) if isinstance(mean, tuple) else factor[0] * mean
        if all(f == 1.0 for f in factor):
            out[param] = tex
        else:
            notes.append(f"{param}: its texture is scaled by a factor of {_shown(tuple(factor))}: read as the "
                         f"factor times the image's mean, {_shown(constants[param])}, not texel by texel")
    return out, constants, notes


def _map(doc: dict[str, Any], blob: bytes | None, path: Path, index: int, channel: int | None,
         where: str) -> Texture:
    """Texture ``index`` as a texture of one parameter: its image's file, its sampler's filter (a grey
    image's channel is its grey: `read_values`)."""
    tex = images.item(doc, "textures", index)
    file = images.image_file(doc, blob, path.parent, tex.get("source"))
    which = tex.get("sampler")
    sampler = images.item(doc, "samplers", which) if which is not None else {}
    filt = Filter.NEAREST if sampler.get("magFilter") == textures.NEAREST else Filter.LINEAR
    space = ColourSpace.SRGB if channel is None else ColourSpace.LINEAR
    return texture(file, space, filt, channel=channel, where=where)


def _first_line(exc: BaseException) -> str:
    return (str(exc).strip().splitlines() or [type(exc).__name__])[0]


def _shown(v: Value) -> str:
    return ", ".join(f"{float(x):.4g}" for x in (v if isinstance(v, (list, tuple)) else [v]))
