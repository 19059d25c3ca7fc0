"""Mitsuba's metals: `roughconductor`, `conductor` (a mirror) and Mitsuba 0.5's Ashikhmin-Shirley
conductor (this project's plugin). A conductor's Fresnel is a complex IOR: eta and k, a named
preset of Mitsuba's database, or (Ashikhmin-Shirley) reflectivity and edge tint."""

from __future__ import annotations

from typing import Any

from brdfremap.core.data.appearance import (
    Appearance,
    alphas_from_anisotropy,
    anisotropy_from_alphas,
    as_rgb,
    conductor_f0,
    eta_k_from_reflectivity,
    reflectivity_edge_tint,
)
from brdfremap.core.data.schemas import LobeSpec, ParamSpec, Value

from .bsdfs import conductor_preset
from .model import MitsubaModel, alpha_of, mul, rgb, rough_start
from .params import (
    ALPHA,
    AS_ALPHA,
    ANISOTROPIC,
    ANISOTROPY,
    CONDUCTOR_PRESET,
    CONDUCTOR_PRESETS,
    DISTRIBUTION,
    ETA,
    ISOTROPIC,
    K,
    SPEC_REFL,
    alpha_param,
)

EtaK = tuple[tuple[float, ...], tuple[float, ...]]


def eta_k(p: dict[str, Value]) -> EtaK:
    """A conductor's complex IOR from whichever of its forms the parameters give."""
    if p["material"] == "reflectivity":
        n, k = eta_k_from_reflectivity(p["reflectivity"], p["edge_tint"])
        return as_rgb(n), as_rgb(k)
    return (p["eta"], p["k"]) if p["material"] == "none" else conductor_preset(str(p["material"]))  # type: ignore


def _ior(p: dict[str, Value]) -> dict[str, Any]:
    """A conductor's Fresnel as Mitsuba's properties: eta and k, reflectivity and edge tint, or a preset."""
    if p["material"] == "none":
        return {"eta": rgb(p["eta"]), "k": rgb(p["k"])}
    if p["material"] == "reflectivity":
        return {"reflectivity": rgb(p["reflectivity"]), "edge_tint": rgb(p["edge_tint"])}
    return {"material": p["material"]}


class Conductor(MitsubaModel):
    """Mitsuba's smooth `conductor`; its rough forms below add a roughness."""

    def bsdf(self, p: dict[str, Value]) -> dict[str, Any]:
        return {"type": self.name, "specular_reflectance": rgb(p["specular_reflectance"]), **_ior(p)}

    def derive(self, p: dict[str, Value]) -> dict[str, Value]:
        if p["material"] == "reflectivity":
            return {"reflectivity": p["reflectivity"], "edge_tint": p["edge_tint"]}
        r, g = reflectivity_edge_tint(*eta_k(p))
        return {"reflectivity": as_rgb(r), "edge_tint": as_rgb(g)}

    def appearance(self, p: dict[str, Value]) -> Appearance:
        eta, k = eta_k(p)
        alpha, aniso, rot = self._alpha(p)
        return Appearance(kind="conductor", alpha=alpha, distribution=p.get("distribution"),  # type: ignore[arg-type]
                          specular=mul(conductor_f0(eta, k), p["specular_reflectance"]), eta=tuple(eta), k=tuple(k),
                          anisotropy=aniso, rotation=rot)

    @staticmethod
    def _alpha(p: dict[str, Value]) -> tuple[float, float, float]:
        """(α, anisotropy, rotation) of its roughness; a smooth one's lowest α."""
        if p.get("anisotropy") == "anisotropic":
            return anisotropy_from_alphas(float(p["alpha_u"]), float(p["alpha_v"]))  # type: ignore[arg-type]
        return alpha_of(p), 0.0, 0.0

    def from_appearance(self, a: Appearance, base: dict[str, Value]) -> dict[str, Value]:
        eta, k = a.conductor_ior()
        return {"eta": eta, "k": k}

    def from_file(self, params: dict[str, Any], notes: list[str]) -> dict[str, Any]:
        if params.get("material", "none") == "none":
            params.setdefault("eta", (0.0, 0.0, 0.0))  # Mitsuba's default: a perfect mirror (eta 0, k 1)
            params.setdefault("k", (1.0, 1.0, 1.0))
        return params


class RoughConductor(Conductor):
    """Mitsuba's `roughconductor`: Beckmann or GGX, isotropic or anisotropic."""

    def bsdf(self, p: dict[str, Value]) -> dict[str, Any]:
        d = {**super().bsdf(p), "distribution": p["distribution"]}
        if p["anisotropy"] == "anisotropic":
            d.update(alpha_u=p["alpha_u"], alpha_v=p["alpha_v"])
        else:
            d["alpha"] = p["alpha"]
        return d

    def from_appearance(self, a: Appearance, base: dict[str, Value]) -> dict[str, Value]:
        out = rough_start(a)
        out.update(super().from_appearance(a, base))
        if a.anisotropy > 0.0 and a.alpha is not None:
            au, av = alphas_from_anisotropy(a.alpha, a.anisotropy, a.rotation)
            out.update(anisotropy="anisotropic", alpha_u=au, alpha_v=av)
        return out


class AshikhminShirley(Conductor):
    """Mitsuba 0.5's conductor with the Ashikhmin-Shirley distribution (this project's plugin), which
    takes reflectivity and edge tint as well as eta and k."""

    plugin = True

    def bsdf(self, p: dict[str, Value]) -> dict[str, Any]:
        return {"type": "ashikhmin_shirley", "form": "conductor", "alpha": p["alpha"],
                "specular_reflectance": rgb(p["specular_reflectance"]), **_ior(p)}

    def traverse(self, p: dict[str, Value]) -> dict[str, Any]:
        out = super().traverse(p)
        if "reflectivity" in out:
            eta, k = eta_k_from_reflectivity(out.pop("reflectivity"), out.pop("edge_tint"))
            out["eta"], out["k"] = [float(x) for x in eta], [float(x) for x in k]
        return out

    def from_file(self, params: dict[str, Any], notes: list[str]) -> dict[str, Any]:
        return params

    def from_appearance(self, a: Appearance, base: dict[str, Value]) -> dict[str, Value]:
        eta, k = a.conductor_ior()
        r, g = reflectivity_edge_tint(eta, k)
        out: dict[str, Value] = {"alpha": a.alpha} if a.alpha is not None else {}
        return {**out, "reflectivity": as_rgb(r), "edge_tint": as_rgb(g), "eta": eta, "k": k}


ROUGHCONDUCTOR = RoughConductor(
    name="roughconductor",
    derived=('reflectivity', 'edge_tint'),
    description="Rough metal: microfacet conductor with Fresnel from a named IOR preset or eta/k; isotropic or "
                "anisotropic.",
    parameters=(
        DISTRIBUTION,
        CONDUCTOR_PRESET,
        ETA,
        K,
        ANISOTROPY,
        alpha_param("alpha", ALPHA.description, ISOTROPIC),
        alpha_param("alpha_u", "Microfacet α along the tangent (the sphere's latitudes).", ANISOTROPIC),
        alpha_param("alpha_v", "Microfacet α across the tangent (the sphere's meridians).", ANISOTROPIC),
        SPEC_REFL,
    ),
    lobes={
        "diffuse": LobeSpec(empty=True),
        "specular": LobeSpec(params=("alpha", "alpha_u", "alpha_v", "eta", "k", "specular_reflectance")),
    },
    texturable=("eta", "k", "alpha", "alpha_u", "alpha_v", "specular_reflectance"),
    complex_ior=("eta", "k"),
)

CONDUCTOR = Conductor(
    name="conductor",
    derived=('reflectivity', 'edge_tint'),
    description="Smooth metal (a mirror): under the probe's point light it shows nothing but a point; fit it "
                "under an environment (--fit-scene).",
    smooth=True,
    parameters=(CONDUCTOR_PRESET, ETA, K, SPEC_REFL),
    lobes={"diffuse": LobeSpec(empty=True), "specular": LobeSpec(params=("eta", "k", "specular_reflectance"))},
    texturable=("eta", "k", "specular_reflectance"),
    complex_ior=("eta", "k"),
)

AS_CONDUCTOR = AshikhminShirley(
    name="ashikhmin_shirley",
    derived=('reflectivity', 'edge_tint'),
    description="Conductor with Mitsuba 0.5's Ashikhmin-Shirley (anisotropic Phong) microfacet distribution.",
    parameters=(
        ParamSpec(name="material", kind="choice", default="reflectivity",
                  choices=("reflectivity",) + CONDUCTOR_PRESETS,
                  description="Named conductor from Mitsuba's IOR database; 'none' uses eta and k; "
                              "'reflectivity' uses reflectivity and edge_tint."),
        ParamSpec(name="reflectivity", kind="rgb", default=(0.9, 0.9, 0.9), upper=0.999,
                  active_when={"material": ("reflectivity",)},
                  description="Normal-incidence reflectance; with edge_tint an exact reparameterisation of "
                              "eta/k (Gulbrandsen 2014)."),
        ParamSpec(name="edge_tint", kind="rgb", default=(0.5, 0.5, 0.5), active_when={"material": ("reflectivity",)},
                  description="Where eta lies between its extremes for this reflectivity (1: metal-like)."),
        ETA,
        K,
        AS_ALPHA,
        SPEC_REFL,
    ),
    lobes={
        "diffuse": LobeSpec(empty=True),
        "specular": LobeSpec(params=("reflectivity", "edge_tint", "eta", "k", "alpha", "specular_reflectance")),
    },
    complex_ior=("eta", "k"),
)
