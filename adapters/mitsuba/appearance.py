"""Mitsuba's models read as and written from a renderer-neutral Appearance (the exporters'
conventions: Mitsuba's α is the microfacet α; Phong's n = 2/α² − 2; Ward's α is Beckmann's)."""

from __future__ import annotations

import math
from collections.abc import Callable

from brdfremap.core.appearance import (
    Appearance,
    as_rgb,
    conductor_f0,
    dielectric_f0,
    eta_k_from_reflectivity,
    ior_from_f0,
    reflectivity_edge_tint,
)
from brdfremap.core.schemas import Value

EXT_IOR = 1.000277  # Mitsuba's default exterior medium (air)
EtaK = tuple[tuple[float, ...], tuple[float, ...]]


def _mul(a, b) -> tuple[float, float, float]:
    return tuple(float(x) * float(y) for x, y in zip(a, b))  # type: ignore[return-value]


def _conductor(p: dict[str, Value], preset: Callable[[str], EtaK]) -> EtaK:
    if p["material"] == "reflectivity":
        n, k = eta_k_from_reflectivity(p["reflectivity"], p["edge_tint"])
        return as_rgb(n), as_rgb(k)
    return (p["eta"], p["k"]) if p["material"] == "none" else preset(str(p["material"]))  # type: ignore[return-value]


def appearance(model: str, p: dict[str, Value], preset: Callable[[str], EtaK]) -> Appearance | None:
    """How an exporter reads this Mitsuba material; None for a model without a reading."""
    if model in ("roughconductor", "ashikhmin_shirley"):
        eta, k = _conductor(p, preset)
        dist = p.get("distribution") if model == "roughconductor" else None
        return Appearance(kind="conductor", alpha=float(p["alpha"]), distribution=dist,  # type: ignore[arg-type]
                          specular=_mul(conductor_f0(eta, k), p["specular_reflectance"]), eta=tuple(eta), k=tuple(k))
    if model in ("roughplastic", "ashikhmin_shirley_plastic"):
        ior = float(p["int_ior"]) / EXT_IOR  # type: ignore[arg-type]
        dist = p.get("distribution") if model == "roughplastic" else None
        return Appearance(kind="dielectric", alpha=float(p["alpha"]), distribution=dist,  # type: ignore[arg-type]
                          specular=_mul((dielectric_f0(ior),) * 3, p["specular_reflectance"]),
                          diffuse=tuple(p["diffuse_reflectance"]), ior=ior)  # type: ignore[arg-type]
    if model == "diffuse":
        return Appearance(kind="dielectric", diffuse=tuple(p["reflectance"]))  # type: ignore[arg-type]
    if model in ("ward", "phong"):
        # Ward's α is the slope deviation, as Beckmann's; a Phong exponent n has α = √(2 / (n + 2)).
        alpha = float(p["alpha"]) if model == "ward" else math.sqrt(2.0 / (float(p["exponent"]) + 2.0))  # type: ignore
        metal = max(p["diffuse_reflectance"]) == 0.0  # type: ignore[arg-type]
        return Appearance(kind="conductor" if metal else "dielectric", alpha=alpha, distribution="beckmann",
                          specular=tuple(min(float(x), 1.0) for x in p["specular_reflectance"]),  # type: ignore
                          diffuse=tuple(p["diffuse_reflectance"]))  # type: ignore[arg-type]
    if model == "principled":
        m, base = float(p["metallic"]), as_rgb(p["base_color"])  # type: ignore[arg-type]
        alpha = max(float(p["roughness"]) ** 2, 1e-4)  # type: ignore[arg-type]
        if m >= 0.5:
            return Appearance(kind="conductor", alpha=alpha, distribution="ggx", specular=base)  # type: ignore
        f0 = 0.08 * float(p["specular"])  # type: ignore[arg-type]
        return Appearance(kind="dielectric", alpha=alpha, distribution="ggx", specular=(f0,) * 3,
                          diffuse=tuple(c * (1.0 - m) for c in base), ior=ior_from_f0(f0))  # type: ignore[arg-type]
    return None


def from_appearance(model: str, a: Appearance) -> dict[str, Value]:
    """This Mitsuba model's parameters for a neutral description, by the exporters' conventions."""
    metal = a.kind == "conductor"
    spec = a.specular if metal else (float(sum(a.specular)) / 3,) * 3
    out: dict[str, Value] = {}
    if a.distribution is not None and model in ("roughconductor", "roughplastic"):
        out["distribution"] = a.distribution
    if a.alpha is not None:
        if model == "phong":
            out["exponent"] = max(2.0 / a.alpha**2 - 2.0, 1.0)
        elif model in ("principled",):
            out["roughness"] = math.sqrt(a.alpha)
        elif model != "diffuse":
            out["alpha"] = a.alpha
    if model == "roughconductor":
        eta, k = a.conductor_ior()
        out.update(eta=eta, k=k)
    elif model == "ashikhmin_shirley":
        eta, k = a.conductor_ior()
        r, g = reflectivity_edge_tint(eta, k)
        out.update(reflectivity=as_rgb(r), edge_tint=as_rgb(g), eta=eta, k=k)
    elif model in ("roughplastic", "ashikhmin_shirley_plastic"):
        out.update(diffuse_reflectance=a.diffuse, int_ior=a.dielectric_ior() * EXT_IOR)
    elif model == "diffuse":
        out["reflectance"] = a.specular if metal else a.diffuse
    elif model in ("ward", "phong"):
        out.update(specular_reflectance=spec, diffuse_reflectance=a.diffuse)
    elif model == "principled":
        out.update(base_color=a.specular if metal else a.diffuse, metallic=1.0 if metal else 0.0,
                   specular=min(float(sum(a.specular)) / 3 / 0.08, 1.0) if not metal else 0.5)
    else:
        return {}
    return out


def model_for(a: Appearance) -> tuple[str, dict[str, Value], str]:
    """The Mitsuba model an exporter would pick: a metal is a rough conductor, a diffuse-only
    material a diffuse BSDF, anything else a rough plastic; the source's distribution is held."""
    fix: dict[str, Value] = {"distribution": a.distribution} if a.distribution in ("beckmann", "ggx") else {}
    if a.kind == "conductor":
        return "roughconductor", fix, "a metal (coloured specular, no diffuse)"
    if a.alpha is None or max(a.specular) == 0.0:
        return "diffuse", {}, "diffuse only (no specular lobe)"
    return "roughplastic", fix, "a dielectric with a diffuse base"
