"""Cycles' models read as and written from a renderer-neutral Appearance, by the exporters'
conventions: Blender's roughness is √α; a Metallic Principled BSDF's Base Color is its F0;
Specular IOR Level scales the dielectric's F0 by twice itself (0.5: the IOR as given)."""

from __future__ import annotations

import math

from brdfremap.core.data.appearance import Appearance, as_rgb, Coat, conductor_f0, dielectric_f0, ior_from_f0, Kind, Sheen
from brdfremap.core.data.schemas import Value

_DIST = {"beckmann": "beckmann", "ggx": "ggx", "multi_ggx": "ggx"}


def appearance(model: str, p: dict[str, Value]) -> Appearance | None:
    """How an exporter reads this Cycles material; None for a model without a reading."""
    alpha = max(float(p.get("roughness", 0.0)) ** 2, 1e-4)  # type: ignore[arg-type]
    dist = _DIST.get(str(p.get("distribution")))
    if model == "principled":
        return _principled(p, alpha, dist)
    if model == "glossy":
        return Appearance(kind="conductor", alpha=alpha, distribution=dist, specular=as_rgb(p["color"]))  # type: ignore
    if model == "metallic":
        eta, k = as_rgb(p["ior"]), as_rgb(p["extinction"])
        return Appearance(kind="conductor", alpha=alpha, distribution=dist,  # type: ignore[arg-type]
                          specular=conductor_f0(eta, k), eta=eta, k=k)
    if model == "diffuse":
        return Appearance(kind="dielectric", diffuse=as_rgb(p["color"]), diffuse_model=_shape(p, "roughness"))
    return None


def _principled(p: dict[str, Value], alpha: float, dist) -> Appearance:
    base, m = as_rgb(p["base_color"]), float(p["metallic"])  # type: ignore[arg-type]
    extra = _layers(p)
    if m >= 0.5:
        return Appearance(kind="conductor", alpha=alpha, distribution=dist, specular=base, **extra)  # type: ignore
    f0 = min(dielectric_f0(float(p["ior"])) * 2.0 * float(p["specular_ior_level"]), 1.0)  # type: ignore
    opaque = (1.0 - m) * (1.0 - extra["transmission"])  # what is neither metal nor transmitted is diffuse
    ior = float(p["ior"]) if extra["transmission"] > 0 else ior_from_f0(f0)  # type: ignore[arg-type]
    return Appearance(kind="dielectric", alpha=alpha, distribution=dist, specular=(f0,) * 3,  # type: ignore
                      diffuse=tuple(c * opaque for c in base), ior=ior,
                      diffuse_model=_shape(p, "diffuse_roughness"), **extra)  # type: ignore


def _shape(p: dict[str, Value], name: str) -> str:
    """Cycles' rough diffuse is Oren-Nayar's; none at roughness 0."""
    return "oren-nayar" if float(p.get(name, 0.0)) > 0.0 else "lambert"  # type: ignore[arg-type]


def _layers(p: dict[str, Value]) -> dict:
    """The Principled BSDF's coat, sheen, anisotropy and transmission, where it has them."""
    out: dict = {"transmission": float(p.get("transmission_weight", 0.0))}  # type: ignore[arg-type]
    if out["transmission"] > 0.0:
        out["transmittance"] = as_rgb(p["base_color"])
    if float(p.get("anisotropic", 0.0)) > 0.0:  # type: ignore[arg-type]
        out.update(anisotropy=float(p["anisotropic"]), rotation=float(p["anisotropic_rotation"]))  # type: ignore
    if float(p.get("coat_weight", 0.0)) > 0.0:  # type: ignore[arg-type]
        out["coat"] = Coat(weight=float(p["coat_weight"]), alpha=max(float(p["coat_roughness"]) ** 2, 1e-4),  # type: ignore
                           ior=max(float(p["coat_ior"]), 1.001), tint=as_rgb(p["coat_tint"]))  # type: ignore
    if float(p.get("sheen_weight", 0.0)) > 0.0:  # type: ignore[arg-type]
        out["sheen"] = Sheen(weight=float(p["sheen_weight"]), tint=as_rgb(p["sheen_tint"]),  # type: ignore
                             roughness=float(p["sheen_roughness"]))  # type: ignore[arg-type]
    return out


def _layer_params(a: Appearance) -> dict[str, Value]:
    """The Principled BSDF's inputs for a reading's coat, sheen, anisotropy and transmission: only
    those it has (an input the reading leaves out stays held at its default)."""
    out: dict[str, Value] = {}
    if a.anisotropy > 0.0:
        out.update(anisotropic=a.anisotropy, anisotropic_rotation=a.rotation % 1.0)
    if a.coat is not None:
        out.update(coat_weight=a.coat.weight, coat_roughness=math.sqrt(a.coat.alpha), coat_ior=a.coat.ior,
                   coat_tint=a.coat.tint)
    if a.sheen is not None:
        out.update(sheen_weight=min(a.sheen.weight, 1.0), sheen_tint=a.sheen.tint, sheen_roughness=a.sheen.roughness)
    if a.transmission > 0.0:
        out["transmission_weight"] = a.transmission
        if a.kind == Kind.DIELECTRIC and max(a.diffuse) == 0.0:
            out["base_color"] = a.transmittance  # a clear glass: Base Color tints what is transmitted
        if a.ior is not None:
            out["ior"] = a.ior
    return out


_CHOICES = {"principled": ("ggx",), "glossy": ("beckmann", "ggx"), "metallic": ("beckmann", "ggx")}
"""The distributions each model realises that a neutral reading can name."""


def from_appearance(model: str, a: Appearance, base: dict[str, Value]) -> dict[str, Value]:
    """This Cycles model's parameters for a neutral description, by the exporters' conventions."""
    metal = a.kind == Kind.CONDUCTOR
    out: dict[str, Value] = {}
    if a.alpha is not None and model != "diffuse":
        out["roughness"] = math.sqrt(a.alpha)
    if a.distribution is not None and a.distribution in _CHOICES.get(model, ()):
        out["distribution"] = a.distribution  # the source's single-scattering lobe, not multi_ggx's extra energy
    if model == "principled":
        out.update(base_color=a.specular if metal else a.opaque_base(), metallic=1.0 if metal else 0.0)
        if a.edge_tint() is not None:
            out["specular_tint"] = a.edge_tint()  # a complex IOR's edge, as Blender's F82 tint renders it
        out.update(_layer_params(a))
        if not metal and a.transmission > 0.0:
            out["specular_ior_level"] = 0.5  # a glass's F0 is its IOR's
        elif not metal:
            f0 = float(sum(a.specular)) / 3
            out["specular_ior_level"] = 0.5 * f0 / dielectric_f0(float(base["ior"]))  # type: ignore[arg-type]
    elif model == "glossy":
        out["color"] = a.specular
    elif model == "metallic":
        eta, k = a.conductor_ior()
        out.update(ior=eta, extinction=k)
    elif model == "diffuse":
        out["color"] = a.specular if metal else a.diffuse
    else:
        return {}
    return out


def model_for(a: Appearance) -> tuple[str, dict[str, Value], str]:
    """The Cycles model that reproduces a material of this kind best: a metal is the Metallic BSDF
    of its distribution (a conductor's Fresnel from its complex IOR: the Glossy BSDF has none, and
    matched the probe of Mitsuba's copper to its noise but was 15 % off under the rim light, the
    Metallic 2.7 %), a diffuse-only material a Diffuse BSDF, anything else the Principled BSDF."""
    if a.coat is not None or a.sheen is not None or a.anisotropy > 0.0 or a.transmission > 0.0:
        return "principled", {}, "coated, sheen, anisotropic or transmissive: the Principled BSDF"
    if a.kind == Kind.CONDUCTOR:
        dist = a.distribution if a.distribution in ("beckmann", "ggx") else "ggx"
        return "metallic", {"distribution": dist}, f"a metal: the Metallic BSDF ({dist}), a conductor's Fresnel"
    if a.alpha is None or max(a.specular) == 0.0:
        return "diffuse", {}, "diffuse only: the Diffuse BSDF"
    return "principled", {}, "a dielectric with a diffuse base: the Principled BSDF"


def alternatives(a: Appearance) -> list[tuple[str, dict[str, Value], str]]:
    """Cycles' other models for what `model_for` chose: for a metal read as a reflectance (no complex
    IOR: Schlick's Fresnel, a glTF's or a MaterialX metal's) the Principled BSDF, whose metal is that
    Fresnel with an F82 edge tint; for a diffuse material the Principled BSDF (Oren-Nayar roughness, a
    faint specular). A metal of known complex IOR has its own Fresnel in the Metallic BSDF: nothing
    else follows it closer."""
    first, _, _ = model_for(a)
    if first == "metallic" and a.eta is None:
        return [("principled", {}, "the Principled BSDF's metal: Schlick's Fresnel with an F82 edge tint")]
    if first == "diffuse":
        return [("principled", {}, "the Principled BSDF: a diffuse base with Oren-Nayar roughness and a faint "
                                   "specular")]
    return []
