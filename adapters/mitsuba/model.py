"""What every Mitsuba model is: a `Model` with Mitsuba's own form of the material, its BSDF
dictionary (rendered by `mi.load_dict`, written as XML), and the values `mi.traverse` updates
between renders. Each model's class lives with its family (`conductors`, `plastics`, `glasses`,
`principled`, `legacy`, `blend`); no mitsuba import here."""

from __future__ import annotations

from typing import Any, ClassVar

from brdfremap.core.data.schemas import ParamKind, Value
from brdfremap.core.host.model import Model

EXT_IOR = 1.000277
"""Mitsuba's default exterior medium (air)."""
SMOOTH_ALPHA = 1e-4
"""The α a smooth (delta) BSDF is read with: the lowest a rough model takes."""


def rgb(v: Value) -> dict:
    return {"type": "rgb", "value": list(v)}  # type: ignore[arg-type]


def mul(a, b) -> tuple[float, float, float]:
    return tuple(float(x) * float(y) for x, y in zip(a, b))  # type: ignore[return-value]


def rough_start(a) -> dict[str, Value]:
    """A rough model's distribution and α for a neutral reading (`Appearance`), where it has them."""
    out: dict[str, Value] = {}
    if a.distribution is not None:
        out["distribution"] = a.distribution
    if a.alpha is not None:
        out["alpha"] = a.alpha
    return out


def alpha_of(p: dict[str, Value]) -> float:
    """A rough model's α; a smooth one's lowest (`SMOOTH_ALPHA`)."""
    return float(p.get("alpha", SMOOTH_ALPHA))  # type: ignore[arg-type]


class MitsubaModel(Model):
    """A Mitsuba model: the `Model` and its BSDF dictionary."""

    one_sided: ClassVar[bool] = True
    """Mitsuba shades it on the front side only: written inside a `twosided` (Blender's and
    MaterialX's surfaces are two-sided; the probe sees front faces only, so the fit is the same)."""
    plugin: ClassVar[bool] = False
    """A Python plugin of this project (`bsdfs.register_bsdfs`), not a Mitsuba 3 built-in."""
    relative_ior: ClassVar[bool] = False
    """Its `int_ior` is traversed as eta = int_ior / ext_ior (Mitsuba's plastics and glasses)."""

    def bsdf(self, p: dict[str, Value]) -> dict[str, Any]:
        """The BSDF dictionary of complete parameters ``p``."""
        raise NotImplementedError(self.name)

    def traverse(self, p: dict[str, Value]) -> dict[str, Any]:
        """The BSDF's traverse keys (relative to the BSDF) and values for the active numeric parameters."""
        out: dict[str, Any] = {}
        for ps in self.parameters:
            if ps.kind == ParamKind.CHOICE or not self.is_active(ps.name, p):
                continue
            v = p[ps.name]
            out[ps.name] = list(v) if isinstance(v, tuple) else float(v)  # type: ignore[arg-type]
        if "int_ior" in out and self.relative_ior:
            out["eta"] = out.pop("int_ior") / EXT_IOR
        return out

    def shared(self, p: dict[str, Value]) -> bool:
        """Whether Mitsuba loads two of its parts as one object (a blend of two equal BSDFs), whose
        parameters `mi.traverse` then shows under the first's name."""
        return False

    def wrapped(self, p: dict[str, Value]) -> bool:
        """Whether a file holds it inside a `twosided` (`one_sided`)."""
        return self.one_sided

    def from_file(self, params: dict[str, Any], notes: list[str]) -> dict[str, Any]:
        """A Mitsuba file's properties as this model's parameters, where Mitsuba takes one the model
        does not (``notes`` says what was read as what). The default: as they are."""
        return params
