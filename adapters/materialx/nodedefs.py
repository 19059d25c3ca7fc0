"""A MaterialX shader's parameters, read from its nodedef in MaterialX's standard libraries: each input
a parameter of the same name, its default the nodedef's, its bounds the nodedef's soft range where it
gives one, else its hard range (`uimin`/`uimax`), else 0 to 1 (or the default, where that is larger).
Floats are numbers, colours RGB, booleans and bounded integers choices; inputs of geometry (normals,
tangents), strings, and integers without a range (alpha modes) are not parameters."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from brdfremap.core.data.schemas import ParamSpec


@dataclass(frozen=True)
class Input:
    """One nodedef input as a parameter: its MaterialX type (for the documents written)."""

    name: str
    kind: str  # MaterialX's type: float, color3, boolean, integer


def _bound(inp, *attrs: str) -> float | None:
    for attr in attrs:
        if inp.hasAttribute(attr):
            return min(float(x) for x in inp.getAttribute(attr).split(","))
    return None


def _upper(inp) -> float | None:
    for attr in ("uisoftmax", "uimax"):
        if inp.hasAttribute(attr):
            return max(float(x) for x in inp.getAttribute(attr).split(","))
    return None


def _value(inp) -> Any:
    v = inp.getValue()
    if hasattr(v, "asTuple"):
        return tuple(float(f"{x:.7g}") for x in v.asTuple())  # 32-bit floats: 0.8 comes back as 0.800000011
    if isinstance(v, bool):
        return "true" if v else "false"
    return float(f"{float(v):.7g}") if isinstance(v, float) else v


def parameter(inp, overrides: dict[str, Any]) -> tuple[ParamSpec, Input] | None:
    """A nodedef input as a parameter (``overrides``: the model's own flags for it), or None where it is
    not one."""
    kind = inp.getType()
    if not inp.hasValueString() or kind not in ("float", "color3", "boolean", "integer"):
        return None
    default = _value(inp)
    doc = inp.getAttribute("doc") or inp.getAttribute("uiname") or inp.getName()
    common = {"name": inp.getName(), "description": f"{doc} (MaterialX input {inp.getName()!r}, {kind})."}
    if kind == "boolean":
        return ParamSpec(kind="choice", choices=("false", "true"), default=default, **common, **overrides), \
            Input(inp.getName(), kind)
    if kind == "integer":
        top = _upper(inp)
        if top is None:
            return None
        low = int(_bound(inp, "uisoftmin", "uimin") or 0)
        return ParamSpec(kind="choice", choices=tuple(str(i) for i in range(low, int(top) + 1)), default=str(default),
                         **common, **overrides), Input(inp.getName(), kind)
    values = default if isinstance(default, tuple) else (default,)
    lower = _bound(inp, "uisoftmin", "uimin")
    upper = _upper(inp)
    lower = min(0.0 if lower is None else lower, *values)
    upper = max(1.0 if upper is None else upper, *values)
    return ParamSpec(kind="rgb" if kind == "color3" else "scalar", lower=lower, upper=upper, default=default,
                     **common, **overrides), Input(inp.getName(), kind)


def parameters(nodedef, flags: dict[str, dict[str, Any]]) -> tuple[tuple[ParamSpec, ...], dict[str, Input]]:
    """Every input of ``nodedef`` that is a parameter, in the nodedef's order, each with the flags the
    model gives it (``fit``, ``fit_when_carried`` ...; held and unfitted where it gives none)."""
    specs, inputs = [], {}
    for inp in nodedef.getActiveInputs():
        got = parameter(inp, {"fit": False, **flags.get(inp.getName(), {})})
        if got is not None:
            specs.append(got[0])
            inputs[got[1].name] = got[1]
    unknown = sorted(set(flags) - set(inputs))
    if unknown:  # a model's flags for an input its nodedef lacks: the library changed under it
        raise ValueError(f"{nodedef.getName()}: no input {', '.join(unknown)}")
    return tuple(specs), inputs
