"""UsdPreviewSurface as a model (`usd_preview_surface.yaml`): its reading in renderer-neutral terms by
its specification, and the inputs of a neutral description (the exporters' conventions: roughness is
√α, a metal's diffuseColor is its F0, a dielectric's F0 its IOR's). No USD import here."""

from __future__ import annotations

import math
from pathlib import Path

from brdfremap.core.data.appearance import Appearance, Coat, Kind, as_rgb, dielectric_f0, ior_from_f0
from brdfremap.core.data.configio import load_yaml_model
from brdfremap.core.data.schemas import Value
from brdfremap.core.host.model import Model

IOR_RANGE = (1.0, 2.333)
"""three.js clamps a material's IOR to this range (its MeshPhysicalMaterial)."""

INPUTS = {"diffuse_color": "diffuseColor", "use_specular_workflow": "useSpecularWorkflow",
          "specular_color": "specularColor", "metallic": "metallic", "roughness": "roughness",
          "clearcoat": "clearcoat", "clearcoat_roughness": "clearcoatRoughness", "opacity": "opacity", "ior": "ior"}
"""Each parameter's UsdPreviewSurface input."""
WORKFLOWS = ("metallic", "specular")
"""useSpecularWorkflow 0 and 1."""


class UsdPreviewSurface(Model):
    """UsdPreviewSurface's inputs; how a renderer draws them is its adapter's (three.js's USDLoader)."""

    def appearance(self, params: dict[str, Value]) -> Appearance:
        """The specification's BRDF read as exporters read it (GGX, α = roughness²): the metallic
        workflow as glTF's metallic-roughness; the specular workflow a dielectric of F0 specularColor.
        Opacity below 1 lets the rest through (read as transmission at the IOR)."""
        alpha = max(float(params["roughness"]) ** 2, 1e-4)  # type: ignore[arg-type]
        base, m = as_rgb(params["diffuse_color"]), float(params["metallic"])  # type: ignore[arg-type]
        extra = _layers(params)
        if params["use_specular_workflow"] == "specular":
            f0 = as_rgb(params["specular_color"])
            return Appearance(kind=Kind.DIELECTRIC, alpha=alpha, distribution="ggx", specular=f0,
                              diffuse=tuple(c * (1.0 - extra["transmission"]) for c in base),  # type: ignore[arg-type]
                              ior=ior_from_f0(min(sum(f0) / 3, 0.99)), **extra)
        if m >= 0.5:
            return Appearance(kind=Kind.CONDUCTOR, alpha=alpha, distribution="ggx", specular=base, **extra)
        f0 = dielectric_f0(float(params["ior"]))  # type: ignore[arg-type]
        opaque = (1.0 - m) * (1.0 - extra["transmission"])
        return Appearance(kind=Kind.DIELECTRIC, alpha=alpha, distribution="ggx", specular=(f0,) * 3,
                          diffuse=tuple(c * opaque for c in base), ior=float(params["ior"]), **extra)  # type: ignore

    def from_appearance(self, appearance: Appearance, base: dict[str, Value]) -> dict[str, Value]:
        """The UsdPreviewSurface an exporter writes for a neutral description (the metallic workflow)."""
        a = appearance
        metal = a.kind == Kind.CONDUCTOR
        out: dict[str, Value] = {"use_specular_workflow": "metallic", "metallic": 1.0 if metal else 0.0,
                                 "diffuse_color": a.specular if metal else a.opaque_base()}
        if a.alpha is not None:
            out["roughness"] = min(math.sqrt(a.alpha), 1.0)
        if not metal:
            f0 = float(sum(a.specular)) / 3
            ior = a.ior if a.transmission > 0.0 and a.ior is not None else (ior_from_f0(f0) if f0 > 0.0 else 1.0)
            out["ior"] = min(max(ior, IOR_RANGE[0]), IOR_RANGE[1])
        if a.coat is not None:
            out.update(clearcoat=a.coat.weight, clearcoat_roughness=min(math.sqrt(a.coat.alpha), 1.0))
        if a.transmission > 0.0:
            out["opacity"] = 1.0 - a.transmission
            if not metal and max(a.diffuse) == 0.0:
                out["diffuse_color"] = a.transmittance
        return out


def _layers(p: dict[str, Value]) -> dict:
    out: dict = {"transmission": 1.0 - float(p["opacity"])}  # type: ignore[arg-type]
    if out["transmission"] > 0.0:
        out["transmittance"] = as_rgb(p["diffuse_color"])
    if float(p["clearcoat"]) > 0.0:  # type: ignore[arg-type]
        out["coat"] = Coat(weight=float(p["clearcoat"]),  # type: ignore[arg-type]
                           alpha=max(float(p["clearcoat_roughness"]) ** 2, 1e-4), ior=1.5)  # type: ignore[arg-type]
    return out


def load(cls: type[UsdPreviewSurface] = UsdPreviewSurface) -> UsdPreviewSurface:
    """The model from its data file, as ``cls`` (an adapter's subclass adds its renderer's form)."""
    return load_yaml_model(Path(__file__).with_name("usd_preview_surface.yaml"), cls, "a model")
