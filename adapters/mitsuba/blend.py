"""Mitsuba's `blendbsdf` of two models as one model: its parameters are the weight, each slot's
model (`bsdf_0`, `bsdf_1`: a choice) and each slot's parameters under the slot's name
(`bsdf_1.alpha`), the names Mitsuba's own `traverse` gives them. No mitsuba import here."""

from __future__ import annotations

from typing import Any

from brdfremap.core.data.appearance import Appearance, Kind
from brdfremap.core.data.schemas import ParamSpec, Value

from .conductors import ROUGHCONDUCTOR
from .model import MitsubaModel
from .plastics import DIFFUSE, ROUGHPLASTIC

SLOTS = ("bsdf_0", "bsdf_1")
PARTS: dict[str, MitsubaModel] = {m.name: m for m in (DIFFUSE, ROUGHCONDUCTOR, ROUGHPLASTIC)}
"""The models a blend's slot may hold."""
COMPONENTS = tuple(PARTS)


def _slotted(slot: str, model: str, p: ParamSpec) -> ParamSpec:
    return p.model_copy(update={
        "name": f"{slot}.{p.name}", "explore": False, "linear_in": (), "fit_when_carried": False,
        "active_when": {slot: (model,), **{f"{slot}.{k}": v for k, v in p.active_when.items()}},
        "inert_when": {f"{slot}.{k}": v for k, v in p.inert_when.items()},
        "description": f"{p.description} ({slot}, when it is {model})"})


def _slot_params(slot: str, default: str) -> list[ParamSpec]:
    out: dict[str, ParamSpec] = {}
    for model in COMPONENTS:
        for p in PARTS[model].parameters:
            q = _slotted(slot, model, p)
            if q.name in out:  # shared by two models (alpha, distribution): active for both
                seen = out[q.name]
                when = dict(seen.active_when)
                when[slot] = (*when[slot], model)
                out[q.name] = seen.model_copy(update={"active_when": when,
                                                      "description": p.description + f" ({slot})"})
            else:
                out[q.name] = q
    choice = ParamSpec(name=slot, kind="choice", default=default, choices=COMPONENTS,
                       description=f"The model in Mitsuba's {slot} (weight 0 shows it alone)" if slot == "bsdf_0"
                       else f"The model in Mitsuba's {slot} (weight 1 shows it alone)")
    return [choice, *out.values()]


def component(slot: str, p: dict[str, Value]) -> tuple[str, dict[str, Value]]:
    """A slot's model and its own parameters (names without the slot)."""
    own = ((k.partition("."), v) for k, v in p.items())
    return str(p[slot]), {name: v for (head, dot, name), v in own if dot and head == slot}


class Blend(MitsubaModel):
    """Mitsuba's `blendbsdf` of two of `PARTS`; each slot's parameters under the slot's name."""

    def bsdf(self, p: dict[str, Value]) -> dict[str, Any]:
        d: dict[str, Any] = {"type": "blendbsdf", "weight": p["weight"]}
        for slot in SLOTS:
            model, sub = component(slot, p)
            d[slot] = PARTS[model].bsdf(sub)
        return d

    def traverse(self, p: dict[str, Value]) -> dict[str, Any]:
        out: dict[str, Any] = {"weight": float(p["weight"])}  # type: ignore[arg-type]
        for slot in SLOTS:
            model, sub = component(slot, p)
            out.update({f"{slot}.{k}": v for k, v in PARTS[model].traverse(sub).items()})
        return out

    def shared(self, p: dict[str, Value]) -> bool:
        """Whether its two BSDFs are the same model with the same values (Mitsuba loads them as one)."""
        (m0, s0), (m1, s1) = (component(slot, p) for slot in SLOTS)
        return PARTS[m0].bsdf(s0) == PARTS[m1].bsdf(s1)

    def appearance(self, p: dict[str, Value]) -> Appearance | None:
        """An exporter's reading of a blend: each slot's reading, mixed by the weight (specular and
        diffuse reflectances in proportion, the α of the slot with the stronger specular lobe, the
        kind of the heavier slot unless the blend has a diffuse part: then a dielectric)."""
        w = float(p["weight"])  # type: ignore[arg-type]
        looks = [PARTS[m].appearance(sub) for m, sub in (component(s, p) for s in SLOTS)]
        if any(a is None for a in looks):
            return None
        a, b = looks

        def mix(x, y):
            return tuple((1 - w) * u + w * v for u, v in zip(x, y))

        glossy = max((a, 1 - w), (b, w), key=lambda t: max(t[0].specular) * t[1] if t[0].alpha else -1.0)[0]
        heavier = a if w < 0.5 else b
        diffuse = mix(a.diffuse, b.diffuse)
        return Appearance(kind="dielectric" if max(diffuse) > 0 else heavier.kind, alpha=glossy.alpha,
                          distribution=glossy.distribution, specular=mix(a.specular, b.specular), diffuse=diffuse,  # type: ignore
                          ior=glossy.ior if heavier.kind == Kind.DIELECTRIC else None, anisotropy=glossy.anisotropy,
                          rotation=glossy.rotation)


BLEND = Blend(
    name="blendbsdf",
    description="Mitsuba's blendbsdf: (1 − weight) × bsdf_0 + weight × bsdf_1, each a diffuse, roughconductor "
                "or roughplastic; a source (as a target, its choices are yours to --fix).",
    parameters=(
        ParamSpec(name="weight", kind="scalar", default=0.5, description="The blend's weight of bsdf_1."),
        *_slot_params("bsdf_0", "diffuse"),
        *_slot_params("bsdf_1", "roughconductor"),
    ),
)
