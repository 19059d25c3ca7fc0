"""Mitsuba's dielectric-coated and plain diffuse models: `roughplastic`, `plastic` (a smooth coat),
Mitsuba 0.5's Ashikhmin-Shirley plastic (this project's plugin) and `diffuse`."""

from __future__ import annotations

from typing import Any

from brdfremap.core.data.appearance import Appearance, Kind, dielectric_f0
from brdfremap.core.data.schemas import LobeSpec, ParamSpec, Value

from .legacy import trim_notes
from .model import EXT_IOR, MitsubaModel, alpha_of, mul, rgb, rough_start
from .params import ALPHA, AS_ALPHA, BASE_COLOUR, DISTRIBUTION, INT_IOR, SPEC_REFL, lobes


class Plastic(MitsubaModel):
    """Mitsuba's smooth `plastic`: a diffuse base under a dielectric coat of IOR `int_ior`."""

    relative_ior = True

    def bsdf(self, p: dict[str, Value]) -> dict[str, Any]:
        return {"type": self.name, "int_ior": p["int_ior"], "ext_ior": EXT_IOR, "nonlinear": False,
                "diffuse_reflectance": rgb(p["diffuse_reflectance"]),
                "specular_reflectance": rgb(p["specular_reflectance"])}

    def derive(self, p: dict[str, Value]) -> dict[str, Value]:
        return {"specular_f0": dielectric_f0(float(p["int_ior"]) / EXT_IOR)}  # type: ignore[arg-type]

    def appearance(self, p: dict[str, Value]) -> Appearance:
        ior = float(p["int_ior"]) / EXT_IOR  # type: ignore[arg-type]
        return Appearance(kind="dielectric", alpha=alpha_of(p), distribution=p.get("distribution"),  # type: ignore
                          specular=mul((dielectric_f0(ior),) * 3, p["specular_reflectance"]),
                          diffuse=tuple(p["diffuse_reflectance"]), ior=ior)  # type: ignore[arg-type]

    def from_appearance(self, a: Appearance, base: dict[str, Value]) -> dict[str, Value]:
        return {"diffuse_reflectance": a.diffuse, "int_ior": a.dielectric_ior() * EXT_IOR}


class RoughPlastic(Plastic):
    """Mitsuba's `roughplastic`: the coat rough, Beckmann or GGX."""

    def bsdf(self, p: dict[str, Value]) -> dict[str, Any]:
        return {**super().bsdf(p), "distribution": p["distribution"], "alpha": p["alpha"]}

    def from_appearance(self, a: Appearance, base: dict[str, Value]) -> dict[str, Value]:
        out = rough_start(a)
        return {**out, **super().from_appearance(a, base)}


class AshikhminShirleyPlastic(Plastic):
    """Mitsuba 0.5's plastic with the Ashikhmin-Shirley distribution (this project's plugin), whose
    reflectances its energy-conservation safeguard trims; its `int_ior` is traversed as given."""

    plugin = True
    relative_ior = False

    def bsdf(self, p: dict[str, Value]) -> dict[str, Any]:
        return {"type": "ashikhmin_shirley", "form": "plastic", "alpha": p["alpha"], "int_ior": p["int_ior"],
                "ext_ior": EXT_IOR, "diffuse_reflectance": rgb(p["diffuse_reflectance"]),
                "specular_reflectance": rgb(p["specular_reflectance"])}

    def notes(self, p: dict[str, Value]) -> list[str]:
        return trim_notes(self.name, [("specular_reflectance", p["specular_reflectance"], (0.0,) * 3),
                                      ("diffuse_reflectance", p["diffuse_reflectance"], (0.0,) * 3)])

    def from_appearance(self, a: Appearance, base: dict[str, Value]) -> dict[str, Value]:
        out: dict[str, Value] = {"alpha": a.alpha} if a.alpha is not None else {}
        return {**out, **super().from_appearance(a, base)}


class Diffuse(MitsubaModel):
    """Mitsuba's Lambertian `diffuse`."""

    def bsdf(self, p: dict[str, Value]) -> dict[str, Any]:
        return {"type": "diffuse", "reflectance": rgb(p["reflectance"])}

    def appearance(self, p: dict[str, Value]) -> Appearance:
        return Appearance(kind="dielectric", diffuse=tuple(p["reflectance"]))  # type: ignore[arg-type]

    def from_appearance(self, a: Appearance, base: dict[str, Value]) -> dict[str, Value]:
        return {"reflectance": a.specular if a.kind == Kind.CONDUCTOR else a.diffuse}


ROUGHPLASTIC = RoughPlastic(
    name="roughplastic",
    derived=('specular_f0',),
    description="Diffuse base under a rough dielectric coating (Mitsuba's roughplastic).",
    parameters=(DISTRIBUTION, BASE_COLOUR, ALPHA, INT_IOR, SPEC_REFL),
    lobes=lobes("alpha", "int_ior", "specular_reflectance"),
    texturable=("diffuse_reflectance", "specular_reflectance"),  # Mitsuba 3 takes alpha and int_ior as numbers only
)

DIFFUSE = Diffuse(
    name="diffuse",
    description="Lambertian reflector.",
    parameters=(ParamSpec(name="reflectance", kind="rgb", default=(0.5, 0.5, 0.5), linear_in=("full", "diffuse"),
                          description="Albedo."),),
    lobes={"diffuse": LobeSpec(params=("reflectance",)), "specular": LobeSpec(empty=True)},
    texturable=("reflectance",),
)

PLASTIC = Plastic(
    name="plastic",
    derived=('specular_f0',),
    description="Diffuse base under a smooth dielectric coating: under the probe's point light only the diffuse "
                "part and the coating's Fresnel loss show; the mirror reflection needs an environment.",
    smooth=True,
    parameters=(BASE_COLOUR, INT_IOR, SPEC_REFL),
    lobes=lobes("int_ior", "specular_reflectance"),
    texturable=("diffuse_reflectance", "specular_reflectance"),
)

AS_PLASTIC = AshikhminShirleyPlastic(
    name="ashikhmin_shirley_plastic",
    derived=('specular_f0',),
    description="Diffuse base under a rough dielectric with Mitsuba 0.5's Ashikhmin-Shirley distribution.",
    parameters=(BASE_COLOUR, AS_ALPHA, INT_IOR, SPEC_REFL),
    lobes=lobes("alpha", "int_ior", "specular_reflectance"),
)
