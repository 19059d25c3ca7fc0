"""Which Cycles model a renderer-neutral `Appearance` converts to (an exporter's choice, and the
second choice `remap convert` tries). How each model reads as an Appearance, and its parameters
for one, are the model's own (`models`)."""

from __future__ import annotations

from brdfremap.core.data.appearance import Appearance, Kind
from brdfremap.core.data.schemas import Value


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
