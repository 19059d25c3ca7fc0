"""Blender Cycles' models, each one object: its parameters, its reading as an `Appearance` and its
converted start, by the exporters' conventions (no bpy import here): Blender's roughness r is the
square root of the microfacet α (α = r²)."""

from __future__ import annotations

import math
from typing import ClassVar

from brdfremap.core.data.appearance import Appearance, Coat, Kind, Sheen, as_rgb, conductor_f0, dielectric_f0, ior_from_f0
from brdfremap.core.data.schemas import LobeSpec, Need, ParamSpec, Value
from brdfremap.core.host.model import Model


_DIST = {"beckmann": "beckmann", "ggx": "ggx", "multi_ggx": "ggx"}


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


class CyclesModel(Model):
    """A Cycles model: the `Model` and its shader node, which `material` builds (in the worker, with
    bpy) and writes (the Python snippet)."""

    node: ClassVar[str] = ""
    """The node's type."""
    inputs: ClassVar[dict[str, str]] = {}
    """Each numeric parameter's node input, by name."""
    props: ClassVar[dict[str, str]] = {}
    """Each choice parameter's node property."""
    fixed_props: ClassVar[dict[str, str]] = {}
    """Node properties set once, not parameters."""
    vector_inputs: ClassVar[tuple[str, ...]] = ()
    """RGB parameters on 3-float vector sockets rather than RGBA colour sockets."""

    def _alpha(self, p: dict[str, Value]) -> float:
        return max(float(p.get("roughness", 0.0)) ** 2, 1e-4)  # type: ignore[arg-type]

    def _dist(self, p: dict[str, Value]):
        return _DIST.get(str(p.get("distribution")))

    def _common(self, a: Appearance) -> dict[str, Value]:
        """Blender's roughness (√α) and the source's distribution where this model realises it."""
        out: dict[str, Value] = {}
        if a.alpha is not None:
            out["roughness"] = math.sqrt(a.alpha)
        if a.distribution is not None and a.distribution in self.choices_realised:
            out["distribution"] = a.distribution  # the source's single-scattering lobe, not multi_ggx's extra energy
        return out

    choices_realised: ClassVar[tuple[str, ...]] = ()
    """The distributions it realises that a neutral reading can name."""


class Principled(CyclesModel):
    """The Principled BSDF: a Metallic one's Base Color is its F0; Specular IOR Level scales the
    dielectric's F0 by twice itself (0.5: the IOR as given)."""

    choices_realised = ("ggx",)
    node = "ShaderNodeBsdfPrincipled"
    inputs = {
        "base_color": "Base Color", "metallic": "Metallic", "roughness": "Roughness", "ior": "IOR",
        "specular_ior_level": "Specular IOR Level", "specular_tint": "Specular Tint",
        "anisotropic": "Anisotropic", "anisotropic_rotation": "Anisotropic Rotation",
        "coat_weight": "Coat Weight", "coat_roughness": "Coat Roughness", "coat_ior": "Coat IOR",
        "coat_tint": "Coat Tint", "sheen_weight": "Sheen Weight", "sheen_roughness": "Sheen Roughness",
        "sheen_tint": "Sheen Tint", "diffuse_roughness": "Diffuse Roughness", "subsurface_weight": "Subsurface Weight",
        "subsurface_radius": "Subsurface Radius", "subsurface_scale": "Subsurface Scale",
        "subsurface_ior": "Subsurface IOR", "subsurface_anisotropy": "Subsurface Anisotropy",
        "transmission_weight": "Transmission Weight", "thin_film_thickness": "Thin Film Thickness",
        "thin_film_ior": "Thin Film IOR", "alpha": "Alpha",
    }
    props = {"distribution": "distribution", "subsurface_method": "subsurface_method"}
    vector_inputs = ("subsurface_radius",)

    def appearance(self, p: dict[str, Value]) -> Appearance:
        a = _principled(p, self._alpha(p), self._dist(p))
        return a.model_copy(update={"multiscatter": True}) if p.get("distribution") == "multi_ggx" else a

    def from_appearance(self, a: Appearance, base: dict[str, Value]) -> dict[str, Value]:
        metal = a.kind == Kind.CONDUCTOR
        out = self._common(a)
        if a.multiscatter and out.get("distribution") == "ggx":
            out["distribution"] = "multi_ggx"  # the energy of multiple scattering kept, as the source keeps it
        out.update(base_color=a.specular if metal else a.opaque_base(), metallic=1.0 if metal else 0.0)
        if a.edge_tint() is not None:
            out["specular_tint"] = a.edge_tint()  # a complex IOR's edge, as Blender's F82 tint renders it
        out.update(_layer_params(a))
        if not metal and a.transmission > 0.0:
            out["specular_ior_level"] = 0.5  # a glass's F0 is its IOR's
        elif not metal and dielectric_f0(float(base["ior"])) > 0.0:  # type: ignore[arg-type]  # IOR 1: no F0 to scale
            f0 = float(sum(a.specular)) / 3
            out["specular_ior_level"] = 0.5 * f0 / dielectric_f0(float(base["ior"]))  # type: ignore[arg-type]
        return out


class Glossy(CyclesModel):
    """The Glossy BSDF: a constant colour, no Fresnel."""

    choices_realised = ("beckmann", "ggx")
    node = "ShaderNodeBsdfGlossy"
    inputs = {"color": "Color", "roughness": "Roughness"}
    props = {"distribution": "distribution"}

    def appearance(self, p: dict[str, Value]) -> Appearance:
        return Appearance(kind="conductor", alpha=self._alpha(p), distribution=self._dist(p),  # type: ignore
                          specular=as_rgb(p["color"]))

    def from_appearance(self, a: Appearance, base: dict[str, Value]) -> dict[str, Value]:
        return {**self._common(a), "color": a.specular}


class Metallic(CyclesModel):
    """The Metallic BSDF with the physical conductor Fresnel of a complex IOR."""

    choices_realised = ("beckmann", "ggx")
    node = "ShaderNodeBsdfMetallic"
    inputs = {"ior": "IOR", "extinction": "Extinction", "roughness": "Roughness"}
    props = {"distribution": "distribution"}
    fixed_props = {"fresnel_type": "PHYSICAL_CONDUCTOR"}
    vector_inputs = ("ior", "extinction")

    def appearance(self, p: dict[str, Value]) -> Appearance:
        eta, k = as_rgb(p["ior"]), as_rgb(p["extinction"])
        return Appearance(kind="conductor", alpha=self._alpha(p), distribution=self._dist(p),  # type: ignore[arg-type]
                          specular=conductor_f0(eta, k), eta=eta, k=k)

    def from_appearance(self, a: Appearance, base: dict[str, Value]) -> dict[str, Value]:
        eta, k = a.conductor_ior()
        return {**self._common(a), "ior": eta, "extinction": k}


class Diffuse(CyclesModel):
    """The Diffuse BSDF: Lambertian at roughness 0, Oren-Nayar's above."""

    node = "ShaderNodeBsdfDiffuse"
    inputs = {"color": "Color", "roughness": "Roughness"}

    def appearance(self, p: dict[str, Value]) -> Appearance:
        return Appearance(kind="dielectric", diffuse=as_rgb(p["color"]), diffuse_model=_shape(p, "roughness"))

    def from_appearance(self, a: Appearance, base: dict[str, Value]) -> dict[str, Value]:
        return {"color": a.specular if a.kind == Kind.CONDUCTOR else a.diffuse}


# Lobes are isolated natively by render passes (Diffuse Direct x Diffuse Color, Glossy
# Direct x Glossy Color), so no overrides: editing the material to hide a lobe changes the
# other one (Specular IOR Level 0 shifts the diffuse term by about 10 %). Base Color shapes
# both lobes: it is the diffuse albedo and, through Metallic, the metal's specular colour;
# Metallic too: it fades the diffuse lobe out. The engine refits shared parameters on the
# full image in the second stage.
PASS_LOBES_PRINCIPLED = {
    "diffuse": LobeSpec(params=("base_color", "metallic", "sheen_weight", "sheen_roughness")),  # Sheen: a diffuse closure
    "specular": LobeSpec(params=("base_color", "metallic", "roughness", "ior", "specular_ior_level", "specular_tint",
                                 "anisotropic", "anisotropic_rotation", "coat_weight", "coat_roughness")),
}


def _unit(name, default, fit=True, desc="", upper=1.0, **kw):
    return ParamSpec(name=name, kind="scalar", lower=0.0, upper=upper, default=default, fit=fit, description=desc, **kw)


# A fully metallic Principled BSDF is the F82-tint conductor of Base Color and Specular Tint:
# the dielectric's IOR and Specular IOR Level no longer reach the image (checked: identical
# renders in Blender 5.0; tests/test_cycles.py keeps checking it).
METAL = {"metallic": 1.0}
ISOTROPIC = {"anisotropic": 0.0}
GLASS = {"transmission_weight": 1.0}
NO_COAT, NO_SHEEN, NO_SSS, NO_FILM = ({"coat_weight": 0.0}, {"sheen_weight": 0.0}, {"subsurface_weight": 0.0},
                                      {"thin_film_thickness": 0.0})


PRINCIPLED = Principled(
    name="principled",
    smooth_when={"roughness": 0.0},
    transmits_with="transmission_weight",
    description="Principled BSDF (multiscatter GGX by default). Lobes by render passes.",
    parameters=(
        ParamSpec(name="distribution", kind="choice", default="multi_ggx", choices=("multi_ggx", "ggx"), explore=True,
                  description="Microfacet distribution of the Principled BSDF."),
        ParamSpec(name="base_color", kind="rgb", default=(0.8, 0.8, 0.8), held_when=GLASS,
                  description="Base Color (a glass's tint, in and out: held, carried from the source)."),
        _unit("metallic", 0.0, desc="Metallic.", held_when=GLASS),
        _unit("roughness", 0.5, desc="Roughness (α = roughness²)."),
        ParamSpec(name="ior", kind="scalar", lower=1.0, upper=3.0, default=1.5, fit=False, inert_when=METAL,
                  fit_when=GLASS, description="IOR of the dielectric specular (use Specular IOR Level to fit F0; "
                                              "a glass's is fitted: it refracts what the glass transmits)."),
        _unit("specular_ior_level", 0.5, upper=1.0, desc="Specular IOR Level (0.5 = the IOR as given; a glass "
              "ignores it).", inert_when=METAL, held_when=GLASS),
        ParamSpec(name="specular_tint", kind="rgb", default=(1.0, 1.0, 1.0), fit=False, fit_for=(Need.EDGE_TINT,),
                  description="Specular Tint (a metal's: its F82 tint, the colour of its edge)."),
        _unit("anisotropic", 0.0, fit=False, fit_when_carried=True, desc="Anisotropic (the probe's tangent runs "
              "along the sphere's latitudes, its pole at the image's top)."),
        _unit("anisotropic_rotation", 0.0, fit=False, fit_when_carried=True, inert_when=ISOTROPIC,
              desc="Anisotropic Rotation (a fraction of a turn of the tangent about the normal)."),
        _unit("coat_weight", 0.0, fit=False, fit_when_carried=True, desc="Coat Weight."),
        _unit("coat_roughness", 0.03, fit=False, fit_when_carried=True, desc="Coat Roughness.", inert_when=NO_COAT),
        ParamSpec(name="coat_ior", kind="scalar", lower=1.0, upper=4.0, default=1.5, fit=False, inert_when=NO_COAT,
                  description="Coat IOR."),
        ParamSpec(name="coat_tint", kind="rgb", default=(1.0, 1.0, 1.0), fit=False, inert_when=NO_COAT,
                  description="Coat Tint (the colour light takes through the coat)."),
        _unit("sheen_weight", 0.0, fit=False, fit_when_carried=True, desc="Sheen Weight."),
        _unit("sheen_roughness", 0.5, fit=False, fit_when_carried=True, desc="Sheen Roughness.", inert_when=NO_SHEEN),
        ParamSpec(name="sheen_tint", kind="rgb", default=(1.0, 1.0, 1.0), fit=False, inert_when=NO_SHEEN,
                  description="Sheen Tint."),
        _unit("diffuse_roughness", 0.0, fit=False, fit_for=(Need.ROUGH_DIFFUSE,),
              desc="Diffuse Roughness (0: Lambertian)."),
        _unit("subsurface_weight", 0.0, fit=False, desc="Subsurface Weight (the probe sphere is 2 units across: "
              "radii well below it look like a softened diffuse)."),
        ParamSpec(name="subsurface_radius", kind="rgb", lower=0.0, upper=100.0, default=(1.0, 0.2, 0.1), fit=False,
                  inert_when=NO_SSS, description="Subsurface Radius per channel (times Subsurface Scale)."),
        ParamSpec(name="subsurface_scale", kind="scalar", lower=0.0, upper=100.0, default=0.05, fit=False,
                  inert_when=NO_SSS, description="Subsurface Scale (scene units)."),
        ParamSpec(name="subsurface_method", kind="choice", default="random_walk", inert_when=NO_SSS,
                  choices=("random_walk", "random_walk_skin", "burley"),
                  description="Subsurface Method (Blender's default: Random Walk; its IOR only the skin variant "
                              "reads)."),
        ParamSpec(name="subsurface_ior", kind="scalar", lower=1.01, upper=3.8, default=1.4, fit=False,
                  inert_when=NO_SSS, active_when={"subsurface_method": ("random_walk_skin",)},
                  description="Subsurface IOR (the Random Walk (Skin) method's)."),
        _unit("subsurface_anisotropy", 0.0, fit=False, desc="Subsurface Anisotropy (the random walks').",
              inert_when=NO_SSS, active_when={"subsurface_method": ("random_walk", "random_walk_skin")}),
        _unit("transmission_weight", 0.0, fit=False, desc="Transmission Weight (what is seen through the sphere is "
              "what surrounds it: an environment, or the black background)."),
        ParamSpec(name="thin_film_thickness", kind="scalar", lower=0.0, upper=100000.0, default=0.0, fit=False,
                  description="Thin Film Thickness (nm)."),
        ParamSpec(name="thin_film_ior", kind="scalar", lower=1.0, upper=3.0, default=1.33, fit=False,
                  inert_when=NO_FILM, description="Thin Film IOR."),
        _unit("alpha", 1.0, fit=False, desc="Alpha (coverage: below 1 the black background shows through)."),
    ),
    lobes=PASS_LOBES_PRINCIPLED,
    texturable=("base_color", "metallic", "roughness", "ior", "specular_ior_level", "specular_tint", "anisotropic",
                "anisotropic_rotation", "coat_weight", "coat_roughness", "coat_ior", "coat_tint", "sheen_weight",
                "sheen_roughness", "sheen_tint", "diffuse_roughness", "subsurface_weight", "subsurface_radius",
                "subsurface_scale", "subsurface_ior", "subsurface_anisotropy", "transmission_weight",
                "thin_film_thickness", "thin_film_ior", "alpha"),
)
"""Every reflection input of Blender 5.0's Principled BSDF but Emission (the probe measures
reflection) and Tangent (the probe's own: along the latitudes). Past the first nine they are held
(`--fix` them), and a value a source carries is rendered; the coat's, sheen's and anisotropy's
weight and roughness are fitted when the source has that lobe (`fit_when_carried`)."""

GLOSSY = Glossy(
    name="glossy",
    smooth_when={"roughness": 0.0},
    description="Glossy BSDF: a microfacet lobe with a constant colour (no Fresnel).",
    parameters=(
        ParamSpec(name="distribution", kind="choice", default="ggx", explore=True,
                  choices=("beckmann", "ggx", "ashikhmin_shirley", "multi_ggx"), description="Distribution."),
        ParamSpec(name="color", kind="rgb", default=(0.8, 0.8, 0.8), linear_in=("full", "specular"), description="Color."),
        _unit("roughness", 0.3, desc="Roughness (α = roughness²)."),
    ),
    lobes={"diffuse": LobeSpec(empty=True), "specular": LobeSpec(params=("color", "roughness"))},
    texturable=("color", "roughness"),
)

DIFFUSE = Diffuse(
    name="diffuse",
    description="Diffuse BSDF (Lambertian at roughness 0).",
    parameters=(
        ParamSpec(name="color", kind="rgb", default=(0.8, 0.8, 0.8), linear_in=("full", "diffuse"), description="Color."),
        _unit("roughness", 0.0, fit=False, fit_for=(Need.ROUGH_DIFFUSE,), desc="Oren-Nayar roughness."),
    ),
    lobes={"diffuse": LobeSpec(params=("color", "roughness")), "specular": LobeSpec(empty=True)},
    texturable=("color", "roughness"),
)

METALLIC = Metallic(
    name="metallic",
    smooth_when={"roughness": 0.0},
    description="Metallic BSDF with the physical conductor Fresnel (complex IOR per channel).",
    parameters=(
        ParamSpec(name="distribution", kind="choice", default="multi_ggx", choices=("beckmann", "ggx", "multi_ggx"),
                  explore=True, description="Distribution."),
        ParamSpec(name="ior", kind="rgb", lower=0.0, upper=8.0, default=(0.2, 0.4, 1.4), description="IOR (eta)."),
        ParamSpec(name="extinction", kind="rgb", lower=0.0, upper=10.0, default=(3.9, 2.4, 1.6),
                  description="Extinction (k)."),
        _unit("roughness", 0.3, desc="Roughness (α = roughness²)."),
    ),
    lobes={"diffuse": LobeSpec(empty=True), "specular": LobeSpec(params=("ior", "extinction", "roughness"))},
    texturable=("ior", "extinction", "roughness"),
    complex_ior=("ior", "extinction"),
)

MODELS: dict[str, CyclesModel] = {m.name: m for m in (PRINCIPLED, GLOSSY, DIFFUSE, METALLIC)}
