"""Mitsuba 3's `principled`: Disney's principled BSDF, read as layers (a metal or a dielectric
with a diffuse base, a clear coat, a sheen, specular transmission)."""

from __future__ import annotations

import math
from typing import Any

from brdfremap.core.data.appearance import Appearance, Coat, Kind, Sheen, as_rgb, ior_from_f0
from brdfremap.core.data.schemas import ParamSpec, Value

from .model import MitsubaModel, rgb


def _hue(c) -> tuple[float, float, float]:
    """A colour divided by its luminance (Disney's tint colour)."""
    lum = 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
    return as_rgb([x / lum for x in c]) if lum > 0 else (1.0, 1.0, 1.0)


def _sheen_tint(tint, base) -> float:
    """Disney's sheen_tint t whose colour 1 - t + t·hue(base) is nearest a sheen colour (least squares)."""
    hue = _hue(base)
    den = sum((h - 1.0) ** 2 for h in hue)
    if den == 0.0:
        return 0.0
    return min(max(sum((c - 1.0) * (h - 1.0) for c, h in zip(tint, hue)) / den, 0.0), 1.0)


class Principled(MitsubaModel):
    """Disney's parameters: clearcoat is a GTR1 lobe at IOR 1.5 scaled by 1/4 (a quarter of a full
    coat), its α from 0.1 (gloss 0) to 0.001 (gloss 1); sheen tints towards the base colour's hue."""

    def bsdf(self, p: dict[str, Value]) -> dict[str, Any]:
        d: dict[str, Any] = {"type": "principled", "base_color": rgb(p["base_color"])}
        d.update({ps.name: p[ps.name] for ps in self.parameters if ps.name != "base_color"})
        return d

    def wrapped(self, p: dict[str, Value]) -> bool:
        """Only without `spec_trans`: Mitsuba nests no transmissive BSDF in a `twosided`."""
        return not float(p.get("spec_trans", 0.0)) > 0.0  # type: ignore[arg-type]

    def from_file(self, params: dict[str, Any], notes: list[str]) -> dict[str, Any]:
        """Mitsuba's principled takes eta or specular, one thing: a file's eta is read as specular."""
        if "eta" in params:
            eta = float(params.pop("eta"))
            params["specular"] = min(((eta - 1.0) / (eta + 1.0)) ** 2 / 0.08, 1.0)
            notes.append(f"eta {eta:g} read as specular {params['specular']:.4g} (F0 = 0.08 x specular)")
        return params

    def appearance(self, p: dict[str, Value]) -> Appearance:
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

    def from_appearance(self, a: Appearance, base: dict[str, Value]) -> dict[str, Value]:
        metal = a.kind == Kind.CONDUCTOR
        out: dict[str, Value] = {"roughness": math.sqrt(a.alpha)} if a.alpha is not None else {}
        out.update({
            "base_color": a.specular if metal else (a.transmittance if a.transmission > 0 and max(a.diffuse) == 0
                                                    else a.opaque_base()),
            "metallic": 1.0 if metal else 0.0,
            "specular": min(float(sum(a.specular)) / 3 / 0.08, 1.0) if not metal else 0.5})
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


def _unit(name, default, fit=True, desc="", **kw):
    return ParamSpec(name=name, kind="scalar", default=default, fit=fit, description=desc, **kw)


def _carried(name, default, desc, **kw):
    return ParamSpec(name=name, kind="scalar", default=default, fit=False, fit_when_carried=True, description=desc,
                     **kw)


PRINCIPLED = Principled(
    name="principled",
    smooth_when={"roughness": 0.0},
    transmits_with="spec_trans",
    description="Disney principled BSDF (Mitsuba 3's `principled`); lobes are not separable by parameters.",
    parameters=(
        ParamSpec(name="base_color", kind="rgb", default=(0.5, 0.5, 0.5), held_when={"spec_trans": 1.0},
                  description="Base colour (a glass's tint: held, carried from the source)."),
        _unit("metallic", 0.0, desc="Metalness.", held_when={"spec_trans": 1.0}),
        _unit("roughness", 0.5, desc="Roughness (α = roughness²)."),
        _unit("specular", 0.5, desc="Dielectric specular amount: F0 = 0.08 × specular (0.5 ≈ IOR 1.5). Mitsuba's "
              "`eta` is the same thing (one or the other): a file's eta is read as this."),
        _unit("spec_tint", 0.0, fit=False, desc="Tint of the dielectric specular towards the base colour."),
        _carried("anisotropic", 0.0, "Anisotropy: α along the tangent r²/√(1 − 0.9 a), across r²·√(1 − 0.9 a) (the "
                 "probe's tangent runs along the sphere's latitudes; Mitsuba has no rotation)."),
        _carried("sheen", 0.0, "Sheen amount."),
        _unit("sheen_tint", 0.0, fit=False, desc="Sheen tint towards the base colour.", inert_when={"sheen": 0.0}),
        _carried("clearcoat", 0.0, "Clear-coat amount (a GTR1 lobe at a fixed IOR 1.5, scaled by 1/4)."),
        _carried("clearcoat_gloss", 0.0, "Clear-coat glossiness (α from 0.1 at 0 to 0.001 at 1).",
                 inert_when={"clearcoat": 0.0}),
        _unit("spec_trans", 0.0, fit=False, desc="Specular transmission (tinted by the base colour, in and out)."),
        _unit("flatness", 0.0, fit=False, desc="Flatness: the diffuse lobe blended towards Hanrahan-Krueger's "
              "subsurface approximation (Disney)."),
    ),
    # Mitsuba 3 takes every input as an image but specular (and eta, which it replaces).
    texturable=("base_color", "metallic", "roughness", "spec_tint", "anisotropic", "sheen", "sheen_tint", "clearcoat",
                "clearcoat_gloss", "spec_trans", "flatness"),
)
