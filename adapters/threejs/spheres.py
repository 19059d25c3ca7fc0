"""glTF documents of materials on spheres (a written library, one material's `material.gltf`): the
mesh in one embedded buffer, the materials as glTF writes them, their maps as glTF textures."""

from __future__ import annotations

import base64
from typing import Any

import numpy as np

from brdfremap.core.data.schemas import ModelSpec, Value
from brdfremap.core.data.sphere import sphere_mesh
from brdfremap.core.data.textures import TextureMap

from . import gltf, textures

SPACING = 2.5
"""Spheres of radius 1, this far apart along +x."""


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
