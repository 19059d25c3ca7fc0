"""Cycles' models read as and written from a renderer-neutral Appearance, by the exporters'
conventions: Blender's roughness is √α; a Metallic Principled BSDF's Base Color is its F0;
Specular IOR Level scales the dielectric's F0 by twice itself (0.5: the IOR as given)."""

from __future__ import annotations

import math

from brdfremap.core.appearance import (
    Appearance,
    as_rgb,
    conductor_f0,
    dielectric_f0,
    ior_from_f0,
)
from brdfremap.core.schemas import Value

_DIST = {"beckmann": "beckmann", "ggx": "ggx", "multi_ggx": "ggx"}


def appearance(model: str, p: dict[str, Value]) -> Appearance | None:
    """How an exporter reads this Cycles material; None for a model without a reading."""
    alpha = max(float(p.get("roughness", 0.0)) ** 2, 1e-4)  # type: ignore[arg-type]
    dist = _DIST.get(str(p.get("distribution")))
    if model == "principled":
        base, m = as_rgb(p["base_color"]), float(p["metallic"])  # type: ignore[arg-type]
        if m >= 0.5:
            return Appearance(kind="conductor", alpha=alpha, distribution=dist, specular=base)  # type: ignore
        f0 = min(dielectric_f0(float(p["ior"])) * 2.0 * float(p["specular_ior_level"]), 1.0)  # type: ignore
        return Appearance(kind="dielectric", alpha=alpha, distribution=dist, specular=(f0,) * 3,  # type: ignore
                          diffuse=tuple(c * (1.0 - m) for c in base), ior=ior_from_f0(f0))  # type: ignore[arg-type]
    if model == "glossy":
        return Appearance(kind="conductor", alpha=alpha, distribution=dist, specular=as_rgb(p["color"]))  # type: ignore
    if model == "metallic":
        eta, k = as_rgb(p["ior"]), as_rgb(p["extinction"])
        return Appearance(kind="conductor", alpha=alpha, distribution=dist,  # type: ignore[arg-type]
                          specular=conductor_f0(eta, k), eta=eta, k=k)
    if model == "diffuse":
        return Appearance(kind="dielectric", diffuse=as_rgb(p["color"]))
    return None


_CHOICES = {"principled": ("ggx",), "glossy": ("beckmann", "ggx"), "metallic": ("beckmann", "ggx")}
"""The distributions each model realises that a neutral reading can name."""


def from_appearance(model: str, a: Appearance, base: dict[str, Value]) -> dict[str, Value]:
    """This Cycles model's parameters for a neutral description, by the exporters' conventions."""
    metal = a.kind == "conductor"
    out: dict[str, Value] = {}
    if a.alpha is not None and model != "diffuse":
        out["roughness"] = math.sqrt(a.alpha)
    if a.distribution is not None and a.distribution in _CHOICES.get(model, ()):
        out["distribution"] = a.distribution  # the source's single-scattering lobe, not multi_ggx's extra energy
    if model == "principled":
        out.update(base_color=a.specular if metal else a.diffuse, metallic=1.0 if metal else 0.0)
        if not metal:
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
    if a.kind == "conductor":
        dist = a.distribution if a.distribution in ("beckmann", "ggx") else "ggx"
        return "metallic", {"distribution": dist}, f"a metal: the Metallic BSDF ({dist}), a conductor's Fresnel"
    if a.alpha is None or max(a.specular) == 0.0:
        return "diffuse", {}, "diffuse only: the Diffuse BSDF"
    return "principled", {}, "a dielectric with a diffuse base: the Principled BSDF"
