"""Which Mitsuba model a renderer-neutral `Appearance` converts to (an exporter's choice, and the
second choice `remap convert` tries). How each model reads as an Appearance, and its parameters
for one, are the model's own (`models`)."""

from __future__ import annotations

from brdfremap.core.data.appearance import Appearance, Kind
from brdfremap.core.data.schemas import Value


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
