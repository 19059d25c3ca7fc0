"""A MaterialX shader's parameters, read from its nodedef in MaterialX's standard libraries: each input
a parameter of the same name and default. Floats are numbers, colours RGB, booleans and bounded
integers choices; inputs of geometry (normals, tangents), strings, and integers without a range (alpha
modes) are not parameters.

Bounds: an input a fit may vary (the model flags it) takes the nodedef's soft range where it gives one
(`uisoftmin`/`uisoftmax`: where a fit should search), else its hard range (`uimin`/`uimax`), else 0 to 1;
an input only ever held takes the hard range, unbounded above where the nodedef sets no maximum
(`HELD_CEILING`), so that a document's value, rendered as MaterialX renders it, is read as written (a
light bulb's emission of 10000 nits, a honey's transmission depth of 2)."""

from __future__ import annotations

from typing import Any

from brdfremap.core.data.schemas import ParamSpec

HELD_CEILING = 1e6
"""The upper bound of a held input whose nodedef sets no hard maximum."""
FITTED = ("fit", "fit_when", "fit_when_carried", "fit_for")
"""The flags that let a fit vary an input."""


def seven_digits(x: Any) -> float:
    """A MaterialX float as written: it keeps 32-bit floats, so 0.8 comes back as 0.800000011."""
    return float(f"{float(x):.7g}")


def _attr(inp, attr: str, pick) -> float | None:
    return pick(float(x) for x in inp.getAttribute(attr).split(",")) if inp.hasAttribute(attr) else None


def _value(inp) -> Any:
    v = inp.getValue()
    if hasattr(v, "asTuple"):
        return tuple(seven_digits(x) for x in v.asTuple())
    if isinstance(v, bool):
        return "true" if v else "false"
    return seven_digits(v) if isinstance(v, float) else v


def _bounds(inp, fitted: bool, values: tuple[float, ...]) -> tuple[float, float]:
    hard_low, hard_high = _attr(inp, "uimin", min), _attr(inp, "uimax", max)
    if fitted:
        low = next((x for x in (_attr(inp, "uisoftmin", min), hard_low) if x is not None), 0.0)
        high = next((x for x in (_attr(inp, "uisoftmax", max), hard_high) if x is not None), 1.0)
    else:
        low, high = (0.0 if hard_low is None else hard_low), (HELD_CEILING if hard_high is None else hard_high)
    return min(low, *values), max(high, *values)


def parameter(inp, overrides: dict[str, Any]) -> ParamSpec | None:
    """A nodedef input as a parameter (``overrides``: the model's own flags for it), or None where it is
    not one."""
    kind = inp.getType()
    if not inp.hasValueString() or kind not in ("float", "color3", "boolean", "integer"):
        return None
    default = _value(inp)
    doc = inp.getAttribute("doc") or inp.getAttribute("uiname") or inp.getName()
    common = {"name": inp.getName(), "description": f"{doc} (MaterialX input {inp.getName()!r}, {kind})."}
    if kind == "boolean":
        return ParamSpec(kind="choice", choices=("false", "true"), default=default, **common, **overrides)
    if kind == "integer":
        top = _attr(inp, "uimax", max)
        if top is None:
            return None
        low = int(_attr(inp, "uimin", min) or 0)
        return ParamSpec(kind="choice", choices=tuple(str(i) for i in range(low, int(top) + 1)), default=str(default),
                         **common, **overrides)
    lower, upper = _bounds(inp, any(overrides.get(f) for f in FITTED),
                           default if isinstance(default, tuple) else (default,))
    return ParamSpec(kind="rgb" if kind == "color3" else "scalar", lower=lower, upper=upper, default=default,
                     **common, **overrides)


def parameters(nodedef, flags: dict[str, dict[str, Any]]) -> tuple[ParamSpec, ...]:
    """Every input of ``nodedef`` that is a parameter, in the nodedef's order, each with the flags the
    model gives it (``fit``, ``fit_when_carried`` ...; held and unfitted where it gives none)."""
    specs = []
    for inp in nodedef.getActiveInputs():
        got = parameter(inp, {"fit": False, **flags.get(inp.getName(), {})})
        if got is not None:
            specs.append(got)
    unknown = sorted(set(flags) - {p.name for p in specs})
    if unknown:  # a model's flags for an input its nodedef lacks: the library changed under it
        raise ValueError(f"{nodedef.getName()}: no input {', '.join(unknown)}")
    return tuple(specs)
