"""`gltf_pbr` read as and written from a renderer-neutral Appearance, by glTF's own conventions
(the ones every exporter uses): roughness is √α; a metal's base colour is its F0; a dielectric's F0
is its IOR's, scaled by the specular factor; the diffuse albedo is the base colour of what is
neither metal nor transmitted."""

from __future__ import annotations

import math

from brdfremap.core.data.appearance import Appearance, Coat, Kind, Sheen, as_rgb, dielectric_f0, ior_from_f0
from brdfremap.core.data.schemas import Value

IOR_RANGE = (1.0, 2.333)
"""three.js clamps a material's IOR to this range."""


def gltf_alphas(roughness: float, strength: float) -> tuple[float, float]:
    """KHR_materials_anisotropy's α along the tangent and across it: the along one raised towards 1
    by the strength squared, the across one the roughness's (three.js does the same)."""
    across = max(roughness ** 2, 1e-4)
    return across + (1.0 - across) * strength ** 2, across


def disney_anisotropy(roughness: float, strength: float) -> float:
    """The Disney anisotropy whose two α have the same ratio as glTF's (`Appearance`'s convention:
    α along = α / √(1 − 0.9 a), across = α · √(1 − 0.9 a))."""
    along, across = gltf_alphas(roughness, strength)
    return min(max((1.0 - across / along) / 0.9, 0.0), 1.0)


def gltf_anisotropy(alpha: float, a: float) -> tuple[float, float]:
    """glTF's roughness and anisotropy strength for a Disney α and anisotropy: the across α is the
    roughness's, the along one reached by the strength."""
    aspect = math.sqrt(1.0 - 0.9 * a)
    along, across = alpha / aspect, alpha * aspect
    strength = math.sqrt(max(0.0, min(1.0, (along - across) / (1.0 - across)))) if across < 1.0 else 0.0
    return math.sqrt(min(across, 1.0)), strength


def appearance(p: dict[str, Value]) -> Appearance:
    """How an exporter reads this glTF material (GGX, as glTF's BRDF is, with the energy of multiple
    scattering three.js's MeshPhysicalMaterial compensates): an anisotropic one's α is the geometric
    mean of its two."""
    along, across = gltf_alphas(float(p["roughness"]), float(p["anisotropy"]))  # type: ignore[arg-type]
    alpha = max(math.sqrt(along * across), 1e-4)
    base, m = as_rgb(p["base_color"]), float(p["metallic"])  # type: ignore[arg-type]
    extra = _layers(p)
    if m >= 0.5:
        return Appearance(kind=Kind.CONDUCTOR, alpha=alpha, distribution="ggx", multiscatter=True, specular=base,
                          **extra)
    f0 = min(dielectric_f0(float(p["ior"])) * float(p["specular"]), 1.0)  # type: ignore[arg-type]
    opaque = (1.0 - m) * (1.0 - extra["transmission"])
    return Appearance(kind=Kind.DIELECTRIC, alpha=alpha, distribution="ggx", multiscatter=True, specular=(f0,) * 3,
                      diffuse=tuple(c * opaque for c in base), ior=float(p["ior"]) if extra["transmission"] > 0  # type: ignore
                      else ior_from_f0(f0), **extra)


def _layers(p: dict[str, Value]) -> dict:
    out: dict = {"transmission": float(p["transmission"])}  # type: ignore[arg-type]
    if out["transmission"] > 0.0:
        out["transmittance"] = as_rgb(p["base_color"])
    if float(p["anisotropy"]) > 0.0:  # type: ignore[arg-type]
        out.update(anisotropy=disney_anisotropy(float(p["roughness"]), float(p["anisotropy"])),  # type: ignore
                   rotation=float(p["anisotropy_rotation"]))  # type: ignore[arg-type]
    if float(p["clearcoat"]) > 0.0:  # type: ignore[arg-type]
        out["coat"] = Coat(weight=float(p["clearcoat"]), alpha=max(float(p["clearcoat_roughness"]) ** 2, 1e-4),  # type: ignore
                           ior=1.5)
    sheen = as_rgb(p["sheen_color"])
    if max(sheen) > 0.0:
        weight = max(sheen)
        out["sheen"] = Sheen(weight=weight, tint=tuple(c / weight for c in sheen),  # type: ignore[arg-type]
                             roughness=float(p["sheen_roughness"]))  # type: ignore[arg-type]
    return out


def from_appearance(a: Appearance, base: dict[str, Value]) -> dict[str, Value]:
    """The glTF material an exporter writes for a neutral description."""
    metal = a.kind == Kind.CONDUCTOR
    out: dict[str, Value] = {"base_color": a.specular if metal else a.opaque_base(), "metallic": 1.0 if metal else 0.0}
    if a.alpha is not None:
        out["roughness"] = math.sqrt(a.alpha)
    if not metal:
        f0 = float(sum(a.specular)) / 3
        ior = a.ior if a.transmission > 0.0 and a.ior is not None else (ior_from_f0(f0) if f0 > 0.0 else 1.0)
        out["ior"] = min(max(ior, IOR_RANGE[0]), IOR_RANGE[1])
        if f0 == 0.0:
            out["specular"] = 0.0
    if a.anisotropy > 0.0 and a.alpha is not None:
        roughness, strength = gltf_anisotropy(a.alpha, a.anisotropy)
        out.update(roughness=roughness, anisotropy=strength, anisotropy_rotation=a.rotation % 1.0)
    if a.coat is not None:
        out.update(clearcoat=a.coat.weight, clearcoat_roughness=math.sqrt(a.coat.alpha))
    if a.sheen is not None:
        out.update(sheen_color=tuple(min(a.sheen.weight, 1.0) * c for c in a.sheen.tint),
                   sheen_roughness=a.sheen.roughness)
    if a.transmission > 0.0:
        out["transmission"] = a.transmission
        if not metal and max(a.diffuse) == 0.0:
            out["base_color"] = a.transmittance
    return out
