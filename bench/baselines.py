"""Today's exporters: fixed-formula conversions between material models (no renders).

Each returns the target parameters an exporter would write. Two roughness conventions are
common: copying the number ("identity α": Blender roughness = α) and α = roughness²
(Blender roughness = √α). Conductor colours use the normal-incidence Fresnel reflectance
F0 of the source's complex IOR, as exporters do for a metal's base colour."""

from __future__ import annotations

import math
from functools import lru_cache

from brdfremap.core.data.appearance import conductor_f0


@lru_cache(maxsize=None)
def preset_eta_k(material: str) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """RGB eta and k of one of Mitsuba's conductor presets, as the adapter reads them."""
    from brdfremap.adapters.mitsuba.adapter import MitsubaAdapter
    from brdfremap.adapters.mitsuba.bsdfs import conductor_preset

    MitsubaAdapter()  # selects the variant
    return conductor_preset(material)


def _conductor(src):
    if src["material"] != "none":
        return preset_eta_k(src["material"])
    return tuple(src["eta"]), tuple(src["k"])


def convert(source_model: str, src: dict, target: str, convention: str) -> dict | None:
    """Target parameters from a fixed formula; None where the pair has no such formula.

    ``target`` is 'adapter:model[:distribution]'; ``convention`` is 'identity' or 'squared'."""
    alpha = src.get("alpha")
    rough = alpha if convention == "identity" else math.sqrt(alpha) if alpha is not None else None
    adapter, model, *dist = target.split(":")
    if source_model == "roughconductor":
        eta, k = _conductor(src)
        colour = tuple(min(c, 1.0) for c in conductor_f0(eta, k))
        if target.startswith("cycles:principled"):
            return {"base_color": colour, "metallic": 1.0, "roughness": min(rough, 1.0)}
        if target.startswith("cycles:glossy"):
            return {"distribution": dist[0], "color": colour, "roughness": min(rough, 1.0)}
        if target.startswith("mitsuba:roughconductor"):
            return {"distribution": dist[0], "material": src["material"], "alpha": alpha} \
                if convention == "identity" else None
    if source_model == "roughplastic":
        if target.startswith("cycles:principled"):
            return {"base_color": tuple(src["diffuse_reflectance"]), "metallic": 0.0, "roughness": min(rough, 1.0),
                    "ior": src["int_ior"]}
        if target.startswith("mitsuba:roughplastic"):
            return {"distribution": dist[0], "diffuse_reflectance": tuple(src["diffuse_reflectance"]),
                    "alpha": alpha, "int_ior": src["int_ior"]} if convention == "identity" else None
    return None
