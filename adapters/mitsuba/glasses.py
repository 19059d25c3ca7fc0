"""Mitsuba's glasses: `dielectric` (smooth), `roughdielectric` and `thindielectric` (a pane).
Rendered with paths that pass through the sphere (`integrator`), and two-sided by nature."""

from __future__ import annotations

import math
from typing import Any

from brdfremap.core.data.appearance import Appearance, as_rgb, dielectric_f0
from brdfremap.core.data.schemas import LobeSpec, ParamSpec, Value

from .model import EXT_IOR, MitsubaModel, alpha_of, mul, rgb, rough_start
from .params import ALPHA, DISTRIBUTION, INT_IOR, SPEC_REFL


class Dielectric(MitsubaModel):
    """A glass of IOR `int_ior`; its `specular_transmittance` tints each crossing."""

    one_sided = False
    relative_ior = True

    def bsdf(self, p: dict[str, Value]) -> dict[str, Any]:
        return {"type": self.name, "int_ior": p["int_ior"], "ext_ior": EXT_IOR,
                "specular_reflectance": rgb(p["specular_reflectance"]),
                "specular_transmittance": rgb(p["specular_transmittance"])}

    def appearance(self, p: dict[str, Value]) -> Appearance:
        ior = float(p["int_ior"]) / EXT_IOR  # type: ignore[arg-type]
        return Appearance(kind="dielectric", alpha=alpha_of(p), distribution=p.get("distribution"),  # type: ignore
                          specular=mul((dielectric_f0(ior),) * 3, p["specular_reflectance"]), ior=ior,
                          transmission=1.0, transmittance=as_rgb([t * t for t in p["specular_transmittance"]]))

    def from_appearance(self, a: Appearance, base: dict[str, Value]) -> dict[str, Value]:
        # Mitsuba's glasses tint each crossing: in and out, the square of their transmittance.
        return {"int_ior": a.dielectric_ior() * EXT_IOR,
                "specular_transmittance": as_rgb([math.sqrt(max(t, 0.0)) for t in a.transmittance])}


class RoughDielectric(Dielectric):
    """Mitsuba's `roughdielectric`: Beckmann or GGX."""

    def bsdf(self, p: dict[str, Value]) -> dict[str, Any]:
        return {**super().bsdf(p), "distribution": p["distribution"], "alpha": p["alpha"]}

    def from_appearance(self, a: Appearance, base: dict[str, Value]) -> dict[str, Value]:
        out = rough_start(a)
        return {**out, **super().from_appearance(a, base)}


SPEC_TRANS = ParamSpec(name="specular_transmittance", kind="rgb", default=(1.0, 1.0, 1.0), fit=False,
                       description="Multiplier on the transmitted light at each crossing (physically 1; a tint: "
                                   "through the sphere, in and out, its square). Carried from the source, not "
                                   "fitted.")
GLASS_IOR = INT_IOR.model_copy(update={"default": 1.5046, "description": "Interior index of refraction (exterior: "
                                                                         "air)."})
GLASS_NOTE = ("Glass: rendered with paths that pass through the sphere; what is seen through it is what surrounds "
              "it (an environment, or the black background).")

DIELECTRIC = Dielectric(
    transmits=True,
    name="dielectric",
    description="Smooth glass. " + GLASS_NOTE + " Under a point light a smooth reflection is a point: fit "
                "under an environment.",
    smooth=True,
    parameters=(GLASS_IOR, SPEC_REFL, SPEC_TRANS),
    lobes={"diffuse": LobeSpec(empty=True), "specular": LobeSpec(params=("int_ior", "specular_reflectance"))},
)

ROUGHDIELECTRIC = RoughDielectric(
    transmits=True,
    name="roughdielectric",
    description="Rough glass. " + GLASS_NOTE,
    parameters=(DISTRIBUTION, ALPHA, GLASS_IOR, SPEC_REFL, SPEC_TRANS),
    lobes={"diffuse": LobeSpec(empty=True), "specular": LobeSpec(params=("alpha", "int_ior", "specular_reflectance"))},
)

THINDIELECTRIC = Dielectric(
    transmits=True,
    name="thindielectric",
    description="A thin glass sheet (a window pane) on the probe sphere. " + GLASS_NOTE,
    smooth=True,
    parameters=(GLASS_IOR, SPEC_REFL, SPEC_TRANS),
    lobes={"diffuse": LobeSpec(empty=True), "specular": LobeSpec(params=("int_ior", "specular_reflectance"))},
)

