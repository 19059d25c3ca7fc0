"""A YAML renderer's conversions, declared as data: its informed start and its neutral reading.

A model's `start:` maps each of its parameters it names to a quantity of the neutral reading
(`core.data.appearance.Appearance`: `QUANTITIES`), as it is or through named conversions
(`CONVERSIONS`): what an exporter writes for this renderer, which the fit starts from. Its
`reading:` maps Appearance fields (`FIELDS`) to its parameters the same way, so that a material of
this renderer can be a remap's source with an informed start for its target. Both are names, a
fixed list of conversions and numbers, never an expression: a definition file cannot make the
tool run anything of its own. A model declaring either is a `DeclaredModel`."""

from __future__ import annotations

import math
from typing import Any, Callable

from brdfremap.core.data.appearance import Appearance, Kind, conductor_f0, dielectric_f0, ior_from_f0
from brdfremap.core.data.schemas import ParamKind, ParamSpec, Value
from brdfremap.core.host.model import Model
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

NUMBER, COLOUR, TEXT = "a number", "a colour", "text"
_OF_PARAM = {ParamKind.SCALAR: NUMBER, ParamKind.RGB: COLOUR, ParamKind.CHOICE: TEXT}


def _layer(layer: str, field: str) -> Callable[[Appearance], Any]:
    return lambda a: None if getattr(a, layer) is None else getattr(getattr(a, layer), field)


QUANTITIES: dict[str, tuple[str, Callable[[Appearance], Any], str]] = {
    "kind": (TEXT, lambda a: str(a.kind), "conductor or dielectric"),
    "metallic": (NUMBER, lambda a: 1.0 if a.kind == Kind.CONDUCTOR else 0.0, "1 for a conductor, 0 for a dielectric"),
    "alpha": (NUMBER, lambda a: a.alpha, "the specular lobe's microfacet α (none: no specular lobe)"),
    "distribution": (TEXT, lambda a: a.distribution, "beckmann or ggx (none where the source names none)"),
    "specular": (COLOUR, lambda a: a.specular, "the specular lobe's normal-incidence reflectance F0"),
    "diffuse": (COLOUR, lambda a: a.diffuse, "the diffuse albedo"),
    "base_color": (COLOUR, lambda a: a.base_color(),
                   "a metal's F0, else the diffuse albedo before transmission (glTF's and Blender's Base Color)"),
    "ior": (NUMBER, lambda a: a.dielectric_ior(), "a dielectric's IOR: as read, else the one of its mean F0"),
    "eta": (COLOUR, lambda a: a.conductor_ior()[0], "a conductor's complex IOR, real part: as read, else one "
                                                   "with its F0 (Gulbrandsen, edge tint 0.5)"),
    "k": (COLOUR, lambda a: a.conductor_ior()[1], "its imaginary part, alike"),
    "anisotropy": (NUMBER, lambda a: a.anisotropy, "Disney's anisotropy, 0 to 1"),
    "rotation": (NUMBER, lambda a: a.rotation, "the anisotropy's tangent turned, in turns"),
    "transmission": (NUMBER, lambda a: a.transmission, "the fraction transmitted (glass: 1)"),
    "transmittance": (COLOUR, lambda a: a.transmittance, "the colour light takes through the sphere"),
    "coat_weight": (NUMBER, _layer("coat", "weight"), "a clear coat's weight (none without a coat)"),
    "coat_alpha": (NUMBER, _layer("coat", "alpha"), "its α"),
    "coat_ior": (NUMBER, _layer("coat", "ior"), "its IOR"),
    "coat_tint": (COLOUR, _layer("coat", "tint"), "its colour"),
    "sheen_weight": (NUMBER, _layer("sheen", "weight"), "a sheen's weight (none without a sheen)"),
    "sheen_roughness": (NUMBER, _layer("sheen", "roughness"), "its roughness, 0 to 1"),
    "sheen_tint": (COLOUR, _layer("sheen", "tint"), "its colour"),
}
"""What `start:` takes from the neutral reading, by name: (type, getter, one line of docs)."""

FIELDS: dict[str, str] = {"alpha": NUMBER, "distribution": TEXT, "specular": COLOUR, "diffuse": COLOUR,
                          "ior": NUMBER, "eta": COLOUR, "k": COLOUR, "anisotropy": NUMBER, "rotation": NUMBER,
                          "transmission": NUMBER, "transmittance": COLOUR}
"""The Appearance fields `reading:` gives (besides `kind`), by type."""

CONVERSIONS: dict[str, tuple[Callable[[float], float] | None, str]] = {
    "identity": (lambda x: x, "the value as it is"),
    "sqrt": (math.sqrt, "√x: Blender's, glTF's and Disney's roughness from an α"),
    "square": (lambda x: x * x, "x²: an α from such a roughness"),
    "one_minus": (lambda x: 1.0 - x, "1 − x: a glossiness or smoothness from a roughness, and back"),
    "phong_exponent": (lambda x: 2.0 / (x * x) - 2.0, "2/x² − 2: a Phong exponent from an α"),
    "phong_alpha": (lambda x: math.sqrt(2.0 / (x + 2.0)), "√(2/(x + 2)): an α from a Phong exponent"),
    "ior_to_f0": (dielectric_f0, "((x − 1)/(x + 1))²: the normal-incidence reflectance of an IOR"),
    "f0_to_ior": (ior_from_f0, "(1 + √x)/(1 − √x): the IOR of a normal-incidence reflectance"),
    "mean": (None, "a colour's mean: one number"),
    "max": (None, "a colour's largest channel: one number"),
}
"""The named conversions, by name: (per-number function, or None for a colour's reduction; docs)."""

MIN_ALPHA = 1e-4
"""A reading's α below this (a roughness of 0) is read as this: a smooth lobe, not none."""


class Source(BaseModel):
    """One value: a name (`from`) as it is, or through `as` (conversions, in order) and `scale`; or a
    constant (`value`). Written short as the name alone, or the constant alone."""

    model_config = ConfigDict(extra="forbid", populate_by_name=True)

    from_: str | None = Field(None, alias="from", description="A quantity of the neutral reading (start:) or a "
                                                              "parameter (reading:).")
    as_: list[str] = Field(default_factory=list, alias="as", description="Conversions applied in order: "
                           + "; ".join(f"{k}: {doc}" for k, (_, doc) in CONVERSIONS.items()) + ".")
    scale: float = Field(1.0, description="Then multiplied by this number.")
    value: float | tuple[float, float, float] | str | None = Field(None, description="A constant instead of `from`.")

    @classmethod
    def __get_pydantic_json_schema__(cls, core_schema: Any, handler: Any) -> dict[str, Any]:
        """The short forms too: a name, a number, three numbers; `as` one conversion or a list."""
        full = handler.resolve_ref_schema(handler(core_schema))
        conv = full.get("properties", {}).get("as")
        if conv is not None:
            full["properties"]["as"] = {**{k: v for k, v in conv.items() if k not in ("type", "items")},
                                        "anyOf": [{"type": "string"}, {"type": "array", "items": {"type": "string"}}]}
        return {"anyOf": [{"type": "string"}, {"type": "number"},
                          {"type": "array", "items": {"type": "number"}, "minItems": 3, "maxItems": 3}, full]}

    @model_validator(mode="before")
    @classmethod
    def _short(cls, data: Any) -> Any:
        if isinstance(data, str):
            return {"from": data}
        if isinstance(data, (int, float, list)) and not isinstance(data, bool):
            return {"value": data}
        if isinstance(data, dict) and isinstance(data.get("as"), str):
            return {**data, "as": [data["as"]]}
        return data

    @field_validator("as_")
    @classmethod
    def _known(cls, names: list[str]) -> list[str]:
        for name in names:
            if name not in CONVERSIONS:
                raise ValueError(f"unknown conversion {name!r} (known: {', '.join(CONVERSIONS)})")
        return names

    @model_validator(mode="after")
    def _one(self) -> "Source":
        if (self.from_ is None) == (self.value is None):
            raise ValueError("give `from` (a name) or `value` (a constant), one of the two")
        return self

    def type_from(self, named: str | None) -> str:
        """Its value's type, given the type of what `from` names (None for a constant)."""
        kind = named if self.value is None else (
            TEXT if isinstance(self.value, str) else COLOUR if isinstance(self.value, tuple) else NUMBER)
        for name in self.as_:
            if name == "identity":
                continue
            if kind == TEXT:
                raise ValueError(f"{name} converts numbers, and this is text")
            if CONVERSIONS[name][0] is None:
                kind = NUMBER
        return kind  # type: ignore[return-value]

    def evaluate(self, get: Callable[[str], Any]) -> Any:
        """Its value, from ``get(name)`` for what `from` names; None when that is missing (none)."""
        v = self.value if self.value is not None else get(self.from_)  # type: ignore[arg-type]
        if v is None:
            return None
        for name in self.as_:
            v = _convert(name, v)
        if self.scale != 1.0 and not isinstance(v, str):
            v = tuple(x * self.scale for x in v) if isinstance(v, tuple) else v * self.scale
        return v


def _convert(name: str, v: Any) -> Any:
    f = CONVERSIONS[name][0]
    if isinstance(v, str) or name == "identity":
        return v
    if f is None:  # mean, max: a colour's one number
        xs = tuple(v) if isinstance(v, tuple) else (v,)
        return sum(xs) / len(xs) if name == "mean" else max(xs)
    return tuple(_safe(f, x) for x in v) if isinstance(v, tuple) else _safe(f, v)


def _safe(f: Callable[[float], float], x: float) -> float:
    """f(x), or NaN where it is undefined (the start leaves a value that is not finite out)."""
    try:
        return float(f(float(x)))
    except (ValueError, ZeroDivisionError, OverflowError):
        return math.nan


class Reading(BaseModel):
    """How an exporter reads a material of this model in neutral terms: its kind, and the Appearance
    fields its parameters give (each a `Source` whose `from` names a parameter)."""

    model_config = ConfigDict(extra="forbid")

    kind: Kind = Field(description="conductor or dielectric.")
    alpha: Source | None = None
    distribution: Source | None = None
    specular: Source | None = Field(None, description="Left out: a conductor's from its eta and k, a "
                                                      "dielectric's from its ior, where given.")
    diffuse: Source | None = None
    ior: Source | None = None
    eta: Source | None = None
    k: Source | None = None
    anisotropy: Source | None = None
    rotation: Source | None = None
    transmission: Source | None = None
    transmittance: Source | None = None

    def sources(self) -> dict[str, Source]:
        return {name: s for name in FIELDS if (s := getattr(self, name)) is not None}


def problem(model: str, parameters: tuple[ParamSpec, ...] | list[ParamSpec], start: dict[str, Source],
            reading: Reading | None) -> str | None:
    """The first name or type that does not fit in a model's `start:` and `reading:`, as
    "models.M.start.P: what to change", or None."""
    params = {p.name: p for p in parameters}
    known = f"(its parameters: {', '.join(params)})"
    for name, src in start.items():
        where = f"models.{model}.start.{name}"
        if name not in params:
            return f"{where}: not a parameter of {model} {known}"
        if src.value is None and src.from_ not in QUANTITIES:
            return f"{where}: {src.from_!r} is not a quantity of the neutral reading (known: {', '.join(QUANTITIES)})"
        named = QUANTITIES[src.from_][0] if src.value is None else None  # type: ignore[index]
        why = _mismatch(src, named, _OF_PARAM[params[name].kind], f"{src.from_ or 'the value'}", name)
        if why:
            return f"{where}: {why}"
    for field, src in (reading.sources() if reading is not None else {}).items():
        where = f"models.{model}.reading.{field}"
        if src.value is None and src.from_ not in params:
            return f"{where}: {src.from_!r} is not a parameter of {model} {known}"
        named = _OF_PARAM[params[src.from_].kind] if src.value is None else None  # type: ignore[index]
        why = _mismatch(src, named, FIELDS[field], f"{src.from_ or 'the value'}", field)
        if why:
            return f"{where}: {why}"
    return None


def _mismatch(src: Source, named: str | None, want: str, what: str, target: str) -> str | None:
    """Why ``src`` cannot give ``target`` (of type ``want``), or None: a number serves where a colour
    is wanted (grey); a colour where a number is wanted needs `mean` or `max`."""
    try:
        got = src.type_from(named)
    except ValueError as exc:
        return f"{what}: {exc}"
    if got == want or (got == NUMBER and want == COLOUR):
        return None
    hint = ": add `as: mean` (or max)" if (got, want) == (COLOUR, NUMBER) else ""
    return f"{what} gives {got}, and {target} takes {want}{hint}"


class DeclaredModel(Model):
    """A YAML renderer's model with a declared start and, optionally, a reading."""

    start: dict[str, Source] = Field(default_factory=dict, description="Parameter: its source in the reading.")
    reading: Reading | None = Field(None, description="Appearance field: its source among the parameters.")

    def from_appearance(self, appearance: Appearance, base: dict[str, Value]) -> dict[str, Value]:
        """The declared start; a quantity the reading lacks (no α, no coat), or a choice it names
        that the parameter does not have, left out."""
        out: dict[str, Value] = {}
        for name, src in self.start.items():
            v = src.evaluate(lambda q: QUANTITIES[q][1](appearance))
            p = self.param(name)
            if v is None or (p.kind == ParamKind.CHOICE and v not in p.choices):
                continue
            out[name] = (float(v),) * 3 if p.kind == ParamKind.RGB and not isinstance(v, tuple) else v
        return out

    def appearance(self, params: dict[str, Value]) -> Appearance | None:
        """The declared reading, or None without one. A field whose value the Appearance refuses is
        left out; what the reading leaves out follows from what it gives (`complete`)."""
        if self.reading is None:
            return None
        fields: dict[str, Any] = {}
        for field, src in self.reading.sources().items():
            v = src.evaluate(params.get)
            if v is None or not _finite(v):
                continue
            fields[field] = (float(v),) * 3 if FIELDS[field] == COLOUR and not isinstance(v, tuple) else v
        fields = complete(self.reading.kind, fields)
        for _ in range(2):
            try:
                return Appearance(kind=self.reading.kind, **fields)
            except ValidationError as exc:
                bad = {str(e["loc"][0]) for e in exc.errors() if e["loc"]}
                fields = {k: v for k, v in fields.items() if k not in bad}
        return None


def _finite(v: Any) -> bool:
    return isinstance(v, str) or all(map(math.isfinite, v if isinstance(v, tuple) else (v,)))


def complete(kind: Kind, fields: dict[str, Any]) -> dict[str, Any]:
    """A reading's fields with what follows from them: α at least `MIN_ALPHA`; a conductor's F0 from
    its complex IOR, a dielectric's from its IOR, where the reading gives no `specular`."""
    out = dict(fields)
    if isinstance(out.get("alpha"), (int, float)):
        out["alpha"] = max(out["alpha"], MIN_ALPHA)
    if "specular" not in out:
        if kind == Kind.CONDUCTOR and "eta" in out and "k" in out:
            out["specular"] = conductor_f0(out["eta"], out["k"])
        elif kind == Kind.DIELECTRIC and isinstance(out.get("ior"), (int, float)):
            out["specular"] = (dielectric_f0(out["ior"]),) * 3
    return out
