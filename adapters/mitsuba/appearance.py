"""Mitsuba's models read as and written from a renderer-neutral Appearance (the exporters'
conventions: Mitsuba's α is the microfacet α; Phong's n = 2/α² − 2; Ward's α is Beckmann's)."""

from __future__ import annotations

import math
from collections.abc import Callable

from brdfremap.core.data.appearance import (
    Appearance,
    Coat,
    Sheen,
    alphas_from_anisotropy,
    anisotropy_from_alphas,
    as_rgb,
    conductor_f0,
    dielectric_f0,
    eta_k_from_reflectivity,
    ior_from_f0,
    reflectivity_edge_tint,
)
from brdfremap.core.data.schemas import Value
from brdfremap.core.data.appearance import Kind

EXT_IOR = 1.000277  # Mitsuba's default exterior medium (air)
EtaK = tuple[tuple[float, ...], tuple[float, ...]]


def _mul(a, b) -> tuple[float, float, float]:
    return tuple(float(x) * float(y) for x, y in zip(a, b))  # type: ignore[return-value]


def _conductor(p: dict[str, Value], preset: Callable[[str], EtaK]) -> EtaK:
    if p["material"] == "reflectivity":
        n, k = eta_k_from_reflectivity(p["reflectivity"], p["edge_tint"])
        return as_rgb(n), as_rgb(k)
    return (p["eta"], p["k"]) if p["material"] == "none" else preset(str(p["material"]))  # type: ignore[return-value]


SMOOTH_ALPHA = 1e-4
"""The α a smooth (delta) BSDF is read with: the lowest a rough model takes."""
GLASSES = ("dielectric", "roughdielectric", "thindielectric")


def appearance(model: str, p: dict[str, Value], preset: Callable[[str], EtaK]) -> Appearance | None:
    """How an exporter reads this Mitsuba material; None for a model without a reading."""
    if model in ("roughconductor", "conductor", "ashikhmin_shirley"):
        eta, k = _conductor(p, preset)
        dist = p.get("distribution") if model == "roughconductor" else None
        alpha, aniso, rot = _alpha(p)
        return Appearance(kind="conductor", alpha=alpha, distribution=dist,  # type: ignore[arg-type]
                          specular=_mul(conductor_f0(eta, k), p["specular_reflectance"]), eta=tuple(eta), k=tuple(k),
                          anisotropy=aniso, rotation=rot)
    if model in ("roughplastic", "plastic", "ashikhmin_shirley_plastic"):
        ior = float(p["int_ior"]) / EXT_IOR  # type: ignore[arg-type]
        dist = p.get("distribution") if model == "roughplastic" else None
        return Appearance(kind="dielectric", alpha=_alpha(p)[0], distribution=dist,  # type: ignore[arg-type]
                          specular=_mul((dielectric_f0(ior),) * 3, p["specular_reflectance"]),
                          diffuse=tuple(p["diffuse_reflectance"]), ior=ior)  # type: ignore[arg-type]
    if model in GLASSES:
        ior = float(p["int_ior"]) / EXT_IOR  # type: ignore[arg-type]
        return Appearance(kind="dielectric", alpha=_alpha(p)[0], distribution=p.get("distribution"),  # type: ignore
                          specular=_mul((dielectric_f0(ior),) * 3, p["specular_reflectance"]), ior=ior,
                          transmission=1.0, transmittance=as_rgb([t * t for t in p["specular_transmittance"]]))
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
        return _principled(p)
    return None


def _alpha(p: dict[str, Value]) -> tuple[float, float, float]:
    """(α, anisotropy, rotation) of a rough model's roughness; a smooth one's lowest α."""
    if p.get("anisotropy") == "anisotropic":
        return anisotropy_from_alphas(float(p["alpha_u"]), float(p["alpha_v"]))  # type: ignore[arg-type]
    return float(p.get("alpha", SMOOTH_ALPHA)), 0.0, 0.0  # type: ignore[arg-type]


def _principled(p: dict[str, Value]) -> Appearance:
    """Disney's parameters read as layers: clearcoat is a GTR1 lobe at IOR 1.5 scaled by 1/4 (a
    quarter of a full coat), its α from 0.1 (gloss 0) to 0.001 (gloss 1); sheen tints towards the
    base colour's hue."""
    m, base = float(p["metallic"]), as_rgb(p["base_color"])  # type: ignore[arg-type]
    alpha = max(float(p["roughness"]) ** 2, 1e-4)  # type: ignore[arg-type]
    extra: dict = {"anisotropy": float(p["anisotropic"]), "transmission": float(p["spec_trans"])}  # type: ignore
    if float(p["clearcoat"]) > 0.0:  # type: ignore[arg-type]
        gloss = float(p["clearcoat_gloss"])  # type: ignore[arg-type]
        extra["coat"] = Coat(weight=0.25 * float(p["clearcoat"]), alpha=0.1 + (0.001 - 0.1) * gloss)  # type: ignore
    if float(p["sheen"]) > 0.0:  # type: ignore[arg-type]
        t = float(p["sheen_tint"])  # type: ignore[arg-type]
        extra["sheen"] = Sheen(weight=float(p["sheen"]), tint=as_rgb([1 - t + t * h for h in _hue(base)]))  # type: ignore
    if m >= 0.5:
        return Appearance(kind="conductor", alpha=alpha, distribution="ggx", specular=base, **extra)  # type: ignore
    f0 = 0.08 * float(p["specular"])  # type: ignore[arg-type]
    opaque = (1.0 - m) * (1.0 - extra["transmission"])
    return Appearance(kind="dielectric", alpha=alpha, distribution="ggx", specular=(f0,) * 3,
                      diffuse=tuple(c * opaque for c in base), ior=ior_from_f0(f0), diffuse_model="burley",
                      **extra)  # type: ignore


def _hue(c) -> tuple[float, float, float]:
    """A colour divided by its luminance (Disney's tint colour)."""
    lum = 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
    return as_rgb([x / lum for x in c]) if lum > 0 else (1.0, 1.0, 1.0)


def from_appearance(model: str, a: Appearance) -> dict[str, Value]:
    """This Mitsuba model's parameters for a neutral description, by the exporters' conventions."""
    metal = a.kind == Kind.CONDUCTOR
    spec = a.specular if metal else (float(sum(a.specular)) / 3,) * 3
    out: dict[str, Value] = {}
    if a.distribution is not None and model in ("roughconductor", "roughplastic", "roughdielectric"):
        out["distribution"] = a.distribution
    if a.alpha is not None:
        if model == "phong":
            out["exponent"] = max(2.0 / a.alpha**2 - 2.0, 1.0)
        elif model in ("principled",):
            out["roughness"] = math.sqrt(a.alpha)
        elif model not in ("diffuse", "conductor", "plastic", "dielectric", "thindielectric"):
            out["alpha"] = a.alpha
    if model in ("roughconductor", "conductor"):
        eta, k = a.conductor_ior()
        out.update(eta=eta, k=k)
        if model == "roughconductor" and a.anisotropy > 0.0 and a.alpha is not None:
            au, av = alphas_from_anisotropy(a.alpha, a.anisotropy, a.rotation)
            out.update(anisotropy="anisotropic", alpha_u=au, alpha_v=av)
    elif model == "ashikhmin_shirley":
        eta, k = a.conductor_ior()
        r, g = reflectivity_edge_tint(eta, k)
        out.update(reflectivity=as_rgb(r), edge_tint=as_rgb(g), eta=eta, k=k)
    elif model in ("roughplastic", "plastic", "ashikhmin_shirley_plastic"):
        out.update(diffuse_reflectance=a.diffuse, int_ior=a.dielectric_ior() * EXT_IOR)
    elif model in GLASSES:
        # Mitsuba's glasses tint each crossing: in and out, the square of their transmittance.
        out.update(int_ior=a.dielectric_ior() * EXT_IOR, specular_transmittance=as_rgb([math.sqrt(max(t, 0.0))
                                                                                        for t in a.transmittance]))
    elif model == "diffuse":
        out["reflectance"] = a.specular if metal else a.diffuse
    elif model in ("ward", "phong"):
        out.update(specular_reflectance=spec, diffuse_reflectance=a.diffuse)
    elif model == "principled":
        out.update(_principled_params(a, metal))
    else:
        return {}
    return out


def _sheen_tint(tint, base) -> float:
    """Disney's sheen_tint t whose colour 1 - t + t·hue(base) is nearest a sheen colour (least squares)."""
    hue = _hue(base)
    den = sum((h - 1.0) ** 2 for h in hue)
    if den == 0.0:
        return 0.0
    return min(max(sum((c - 1.0) * (h - 1.0) for c, h in zip(tint, hue)) / den, 0.0), 1.0)


def _principled_params(a: Appearance, metal: bool) -> dict[str, Value]:
    out: dict[str, Value] = {
        "base_color": a.specular if metal else (a.transmittance if a.transmission > 0 and max(a.diffuse) == 0
                                                else a.opaque_base()),
        "metallic": 1.0 if metal else 0.0,
        "specular": min(float(sum(a.specular)) / 3 / 0.08, 1.0) if not metal else 0.5}
    if a.anisotropy > 0.0:
        out["anisotropic"] = a.anisotropy
    if a.transmission > 0.0:
        out["spec_trans"] = a.transmission
    if a.coat is not None:
        out.update(clearcoat=min(4.0 * a.coat.weight, 1.0),
                   clearcoat_gloss=min(max((0.1 - a.coat.alpha) / 0.099, 0.0), 1.0))
    if a.sheen is not None:
        out.update(sheen=a.sheen.weight, sheen_tint=_sheen_tint(a.sheen.tint, out["base_color"]))
    return out


def model_for(a: Appearance) -> tuple[str, dict[str, Value], str]:
    """The Mitsuba model an exporter would pick: a metal is a rough conductor, a diffuse-only
    material a diffuse BSDF, anything else a rough plastic; the source's distribution is held."""
    fix: dict[str, Value] = {"distribution": a.distribution} if a.distribution in ("beckmann", "ggx") else {}
    if a.transmission >= 0.5 and a.kind == Kind.DIELECTRIC and max(a.diffuse) == 0.0:
        return "roughdielectric", fix, "a glass (transmissive, no diffuse base)"
    if a.coat is not None or a.sheen is not None or (a.anisotropy > 0.0 and a.kind != Kind.CONDUCTOR) \
            or a.transmission > 0.0:
        return "principled", {}, "coated, sheen or partly transmissive: Mitsuba's principled BSDF"
    if a.kind == Kind.CONDUCTOR and a.anisotropy > 0.0:
        return "roughconductor", {**fix, "anisotropy": "anisotropic"}, "an anisotropic metal"
    if a.kind == Kind.CONDUCTOR:
        return "roughconductor", fix, "a metal (coloured specular, no diffuse)"
    if a.alpha is None or max(a.specular) == 0.0:
        return "diffuse", {}, "diffuse only (no specular lobe)"
    return "roughplastic", fix, "a dielectric with a diffuse base"


def alternatives(a: Appearance) -> list[tuple[str, dict[str, Value], str]]:
    """Mitsuba's other model for what `model_for` sends to a rough plastic or a rough conductor: its
    principled BSDF, whose Schlick Fresnel, GGX lobe and plain diffuse base are a Principled material's
    own (a rough plastic's diffuse is seen through its coat, darker and more saturated; a conductor's
    Fresnel is a complex IOR's). The other distribution is not offered: where the source names none,
    the first fit's informed start already tries both."""
    first, _, _ = model_for(a)
    if first in ("roughplastic", "roughconductor") and a.transmission == 0.0:
        return [("principled", {}, "Mitsuba's principled BSDF: Schlick's Fresnel and a diffuse base under no coat, "
                                   "as a Principled material has")]
    return []
