"""The `gltf_pbr` model's parameters as a glTF 2.0 material and back: metallic-roughness and the
KHR_materials extensions three.js implements, each extension written only where a parameter
differs from what its absence means. `document` is the one-material glTF the adapter hands
three.js's GLTFLoader for every render, so a written `.gltf` is read by three.js exactly as the
fit was rendered."""

from __future__ import annotations

import math
from typing import Any

from brdfremap.core.data.schemas import ModelSpec, Value
from brdfremap.core.data.textures import TextureMap

from . import textures

GENERATOR = "brdf-remap"


def _rgb(v: Value) -> list[float]:
    return [float(x) for x in v]  # type: ignore[union-attr]


def _differs(p: dict[str, Value], spec: ModelSpec, *names: str) -> bool:
    return any([float(x) for x in _as_list(p[n])] != [float(x) for x in _as_list(spec.param(n).default)]
               for n in names)


def _as_list(v: Value) -> list:
    return list(v) if isinstance(v, (list, tuple)) else [v]


def _extensions(p: dict[str, Value], spec: ModelSpec) -> dict[str, dict[str, Any]]:
    """The KHR_materials extensions these parameters need: none at their defaults, and none that does
    nothing with the others (a full metal's IOR and specular: a file read back, or through a table of
    glTF's defaults, then means what it shows)."""
    ext: dict[str, dict[str, Any]] = {}
    if _differs(p, spec, "ior") and not spec.is_inert("ior", p):
        ext["KHR_materials_ior"] = {"ior": float(p["ior"])}  # type: ignore[arg-type]
    if _differs(p, spec, "specular", "specular_color") and not spec.is_inert("specular", p):
        ext["KHR_materials_specular"] = {"specularFactor": float(p["specular"]),  # type: ignore[arg-type]
                                         "specularColorFactor": _rgb(p["specular_color"])}
    if float(p["clearcoat"]) > 0.0:  # type: ignore[arg-type]
        ext["KHR_materials_clearcoat"] = {"clearcoatFactor": float(p["clearcoat"]),  # type: ignore[arg-type]
                                          "clearcoatRoughnessFactor": float(p["clearcoat_roughness"])}  # type: ignore
    if max(_rgb(p["sheen_color"])) > 0.0:
        ext["KHR_materials_sheen"] = {"sheenColorFactor": _rgb(p["sheen_color"]),
                                      "sheenRoughnessFactor": float(p["sheen_roughness"])}  # type: ignore[arg-type]
    if float(p["transmission"]) > 0.0:  # type: ignore[arg-type]
        ext["KHR_materials_transmission"] = {"transmissionFactor": float(p["transmission"])}  # type: ignore
    if float(p["anisotropy"]) > 0.0:  # type: ignore[arg-type]
        ext["KHR_materials_anisotropy"] = {
            "anisotropyStrength": float(p["anisotropy"]),  # type: ignore[arg-type]
            "anisotropyRotation": 2.0 * math.pi * float(p["anisotropy_rotation"])}  # type: ignore[arg-type]
    if float(p["iridescence"]) > 0.0:  # type: ignore[arg-type]
        ext["KHR_materials_iridescence"] = {
            "iridescenceFactor": float(p["iridescence"]), "iridescenceIor": float(p["iridescence_ior"]),  # type: ignore
            "iridescenceThicknessMinimum": 100.0,
            "iridescenceThicknessMaximum": float(p["iridescence_thickness"])}  # type: ignore[arg-type]
    return ext


def material(name: str, p: dict[str, Value], spec: ModelSpec) -> dict[str, Any]:
    """One glTF material of these (complete) parameters."""
    out: dict[str, Any] = {"name": name, "pbrMetallicRoughness": {
        "baseColorFactor": [*_rgb(p["base_color"]), 1.0], "metallicFactor": float(p["metallic"]),  # type: ignore
        "roughnessFactor": float(p["roughness"])}}  # type: ignore[arg-type]
    ext = _extensions(p, spec)
    if ext:
        out["extensions"] = ext
    return out


def extensions_used(materials: list[dict[str, Any]]) -> list[str]:
    return sorted({e for m in materials for e in m.get("extensions", {})})


def document(p: dict[str, Value], spec: ModelSpec, name: str = "material",
             maps: dict[str, TextureMap] | None = None) -> dict[str, Any]:
    """A glTF document holding this one material (no mesh): what three.js's GLTFLoader reads; with
    ``maps``, its inputs driven by them as glTF textures (embedded PNGs)."""
    mat = material(name, p, spec)
    doc: dict[str, Any] = {"asset": {"version": "2.0", "generator": GENERATOR}, "materials": [mat]}
    if maps:
        textures.embed(doc, mat, maps)
    used = extensions_used([mat])
    if used:
        doc["extensionsUsed"] = used
    return doc


READ = {
    "KHR_materials_ior": {"ior": "ior"},
    "KHR_materials_specular": {"specularFactor": "specular", "specularColorFactor": "specular_color"},
    "KHR_materials_clearcoat": {"clearcoatFactor": "clearcoat", "clearcoatRoughnessFactor": "clearcoat_roughness"},
    "KHR_materials_sheen": {"sheenColorFactor": "sheen_color", "sheenRoughnessFactor": "sheen_roughness"},
    "KHR_materials_transmission": {"transmissionFactor": "transmission"},
    "KHR_materials_anisotropy": {"anisotropyStrength": "anisotropy", "anisotropyRotation": "anisotropy_rotation"},
    "KHR_materials_iridescence": {"iridescenceFactor": "iridescence", "iridescenceIor": "iridescence_ior",
                                  "iridescenceThicknessMaximum": "iridescence_thickness"},
}
"""Each extension's factors this model reads, and the parameter each is."""

TEXTURES = {"baseColorTexture": "base_color", "metallicRoughnessTexture": "metallic and roughness",
            "normalTexture": "normals", "occlusionTexture": "occlusion", "emissiveTexture": "emission",
            "specularTexture": "specular", "specularColorTexture": "specular_color",
            "clearcoatTexture": "clearcoat", "clearcoatRoughnessTexture": "clearcoat_roughness",
            "clearcoatNormalTexture": "the clearcoat's normals", "sheenColorTexture": "sheen_color",
            "sheenRoughnessTexture": "sheen_roughness", "transmissionTexture": "transmission",
            "anisotropyTexture": "anisotropy", "iridescenceTexture": "iridescence",
            "iridescenceThicknessTexture": "iridescence_thickness", "thicknessTexture": "the volume's thickness",
            "diffuseTransmissionTexture": "diffuse transmission",
            "diffuseTransmissionColorTexture": "the diffuse transmission's colour",
            "diffuseTexture": "the specular-glossiness diffuse", "specularGlossinessTexture": "specular and glossiness"}
"""The textures a glTF material may drive its inputs with, and what each drives."""


def read_material(m: dict[str, Any]) -> tuple[dict[str, Value], list[str], list[str]]:
    """A glTF material's parameters (those it gives; the model's defaults are glTF's), notes on what
    is not read as it is (emission, extensions this model does not have), and its texture-driven
    inputs (read as their constant factors)."""
    params: dict[str, Value] = {}
    notes: list[str] = []
    pbr = m.get("pbrMetallicRoughness", {}) or {}
    if "baseColorFactor" in pbr:
        rgba = [float(x) for x in pbr["baseColorFactor"]]
        params["base_color"] = tuple(rgba[:3])  # type: ignore[assignment]
        if len(rgba) > 3 and rgba[3] < 1.0:
            notes.append(f"its base colour's alpha {rgba[3]:g} (coverage) is not read: the probe renders it opaque")
    for key, name in (("metallicFactor", "metallic"), ("roughnessFactor", "roughness")):
        if key in pbr:
            params[name] = float(pbr[key])
    exts = m.get("extensions", {}) or {}
    for ext, fields in READ.items():
        for key, name in fields.items():
            if key in exts.get(ext, {}):
                v = exts[ext][key]
                params[name] = tuple(float(x) for x in v) if isinstance(v, list) else float(v)  # type: ignore
    if "anisotropy_rotation" in params:
        params["anisotropy_rotation"] = (float(params["anisotropy_rotation"]) / (2.0 * math.pi)) % 1.0  # type: ignore
    driven = sorted({f"{what} <- texture {holder[key].get('index', '?')}" for key, what in TEXTURES.items()
                     for holder in (m, pbr, *exts.values()) if isinstance(holder, dict) and key in holder})
    if any(float(x) > 0.0 for x in m.get("emissiveFactor", [])):
        notes.append("its emission is not read (the probe measures reflection)")
    other = sorted(set(exts) - set(READ))
    if other:
        notes.append(f"extensions not read: {', '.join(other)}")
    return params, notes, driven


MAPPED = {"baseColorTexture": (("base_color", "baseColorFactor", None),),
          "metallicRoughnessTexture": (("roughness", "roughnessFactor", 1), ("metallic", "metallicFactor", 2))}
"""The core textures a table can remap texel by texel: each parameter it drives, the factor glTF
multiplies it by, and its channel (None: the image's colour)."""


def mapped_textures(m: dict[str, Any]) -> tuple[list[tuple[str, int, int | None, list[float]]], list[str]]:
    """The parameters driven by a core texture: (parameter, texture index, channel, its factor: three
    numbers for the colour, one otherwise); and notes on what of them is not carried."""
    pbr = m.get("pbrMetallicRoughness", {}) or {}
    out: list[tuple[str, int, int | None, list[float]]] = []
    notes: list[str] = []
    for key, inputs in MAPPED.items():
        ref = pbr.get(key)
        if not isinstance(ref, dict) or not isinstance(ref.get("index"), int):
            continue
        if ref.get("texCoord", 0) != 0 or "KHR_texture_transform" in (ref.get("extensions") or {}):
            notes.append(f"its {key} is read as stored: its texture coordinates' set or transform is not carried")
        for name, factor, channel in inputs:
            out.append((name, ref["index"], channel, [float(x) for x in _as_list(pbr.get(factor, 1.0))][:3]))
    return out, notes


def _listed(v: list[float]) -> str:
    return ", ".join(f"{x:g}" for x in v)
