"""Material models described as data: parameters, bounds, lobes. No renderer knowledge."""

from __future__ import annotations

import math
from pathlib import Path
from enum import Enum
from typing import Any, Literal

from pydantic import Field, ValidationError, model_validator

from .errors import ConfigError
from .model import Strict as _Strict
from .kinds import Lobe, ParamKind, Scale
from .textures import Texture

Value = float | tuple[float, float, float] | str
LOBES = ("diffuse", "specular")
TRANSMISSION_DEPTH = 12
"""The longest light path an adapter traces for a transmissive material, in segments from the
camera to the light (the camera's own included): in, through, out, and the internal reflections
that matter (each keeps a few percent). Every adapter renders opaque materials with direct light alone (a convex sphere
lights nothing of itself)."""


class Need(str, Enum):
    """Something a source's reading has that a target's default inputs do not render, so that a
    held input of the target may have to be fitted for it (`ParamSpec.fit_for`)."""

    EDGE_TINT = "edge tint"
    """A metal whose reflectance towards grazing is not Schlick's from its F0 (a complex IOR:
    aluminium's dips 0.1 below Schlick's at 82 degrees)."""
    ROUGH_DIFFUSE = "rough diffuse"
    """A diffuse base flattened as Oren-Nayar's is (Cycles' Diffuse Roughness)."""
    RETRO_DIFFUSE = "retro-reflective diffuse"
    """Burley's diffuse, brighter towards retro-reflection as it roughens (Disney's principled). No
    input of the shipped targets renders it: Principled's Diffuse Roughness, tried for it, lowered a
    Mitsuba principled banana's fit error 5.3 -> 3.5 % and raised its headlight error 4.6 -> 13.5 %
    (Oren-Nayar's flattening is another shape), so no parameter is fitted for it."""


class ParamSpec(_Strict):
    """One parameter of a material model."""

    name: str = Field(description="Parameter name as the user writes it.")
    kind: ParamKind = Field(description="A number, three numbers, or one of `choices`.")
    lower: float = Field(0.0, description="Lower bound (scalar and rgb).")
    upper: float = Field(1.0, description="Upper bound (scalar and rgb).")
    default: Value = Field(description="Value used when neither the source nor --fix gives one.")
    choices: tuple[str, ...] = Field((), description="Allowed values of a choice parameter.")
    scale: Scale = Field(Scale.LINEAR, description="How the optimiser normalises it to [0, 1].")
    typical: tuple[float, float] | None = Field(
        None, description="Scalar only: where a fit's spread starts lie when the bounds reach further (a roughness "
                          "down to a mirror's: a start there renders a sub-pixel highlight, nearly black, and wins "
                          "on error while no gradient leads out of it). None: the bounds.")
    fit: bool = Field(True, description="Fitted by default when it is the target (choices never are).")
    fit_when_carried: bool = Field(False, description="Held by default (`fit` false), but fitted when the source's "
                                                      "neutral reading carries a value for it: a coat, a sheen or "
                                                      "anisotropy the source has.")
    fit_for: tuple[Need, ...] = Field((), description="Held by default (`fit` false), but tried where the source's "
                                                      "reading has one of these and the fit without it leaves more "
                                                      "than the noise; kept where it lowers the error (a metal's "
                                                      "F82 tint for a complex IOR's edge).")
    explore: bool = Field(False, description="Choice only: when the source's reading does not say which value, the "
                                             "fit tries each at the coarse level and keeps the best (a microfacet "
                                             "distribution).")
    separable: bool = Field(True, description="RGB only: each image channel depends on its own component alone "
                                              "(an albedo or tint in an RGB renderer), so one render gives "
                                              "all three Jacobian columns.")
    linear_in: tuple[Literal["full", "diffuse", "specular"], ...] = Field(
        (), description="Images that are proportional to this parameter, channel by channel (a reflectance that "
                        "multiplies a lobe): 'diffuse' or 'specular' for that lobe alone, 'full' for the whole "
                        "material. Each starting point then gets its best scale without a render.")
    active_when: dict[str, tuple[str, ...]] = Field(
        default_factory=dict, description="Only meaningful when these choice parameters take one of these values."
    )
    inert_when: dict[str, float] = Field(
        default_factory=dict, description="Has no effect on the image while these numeric parameters take these "
                                          "values (Principled's Specular IOR Level once Metallic is 1): a fit "
                                          "that has settled them there need not render this parameter's "
                                          "Jacobian column.")
    fit_when: dict[str, float] = Field(
        default_factory=dict, description="Fitted (though `fit` is false) while these numeric parameters take these "
                                          "values: a glass's IOR, which refracts what it transmits.")
    held_when: dict[str, float] = Field(
        default_factory=dict, description="Not fitted while these numeric parameters take these values (a glass's "
                                          "colour and metalness, which the probe's black background hides): held at "
                                          "the start's value.")
    description: str = Field("", description="What it does.")

    @model_validator(mode="after")
    def _check(self) -> "ParamSpec":
        if self.kind == ParamKind.CHOICE:
            if not self.choices or self.default not in self.choices:
                raise ValueError(f"choice parameter {self.name!r} needs choices that include its default")
        else:
            if self.explore:
                raise ValueError(f"parameter {self.name!r}: only a choice can be explored")
            if not self.lower < self.upper:
                raise ValueError(f"parameter {self.name!r}: lower must be below upper")
            if self.scale == Scale.LOG and self.lower <= 0:
                raise ValueError(f"parameter {self.name!r}: log scale needs a positive lower bound")
            vals = self.default if isinstance(self.default, (tuple, list)) else (self.default,)
            if isinstance(self.default, str) or not all(self.lower <= float(v) <= self.upper for v in vals):
                raise ValueError(f"parameter {self.name!r}: default {self.default} is outside [{self.lower:g}, "
                                 f"{self.upper:g}]")
        if self.typical is not None and not (self.kind == ParamKind.SCALAR and self.lower <= self.typical[0]
                                             < self.typical[1] <= self.upper):
            raise ValueError(f"parameter {self.name!r}: typical must be a scalar's range within its bounds")
        return self

    @property
    def size(self) -> int:
        return {"scalar": 1, "rgb": 3, "choice": 0}[self.kind]

    def clip(self, value: Any) -> Value:
        """A number (or RGB triple) moved into the bounds; a choice as given. TypeError or
        ValueError for a value of the wrong shape; NaN stays NaN."""
        if self.kind == ParamKind.CHOICE:
            return value
        vals = [float(x) for x in value] if self.kind == ParamKind.RGB else [float(value)]
        if len(vals) != self.size:
            raise ValueError(f"{self.name}: expected {self.size} numbers, got {len(vals)}")
        vals = [min(max(x, self.lower), self.upper) for x in vals]
        return tuple(vals) if self.kind == ParamKind.RGB else vals[0]  # type: ignore[return-value]

    def coerce(self, value: Any, where: str, file: str | None = None) -> Value:
        """Validate a user value and return it in canonical form (float, 3-tuple or str)."""
        if self.kind == ParamKind.CHOICE:
            if not isinstance(value, str) or value not in self.choices:
                shown = ", ".join(self.choices[:12]) + (" …" if len(self.choices) > 12 else "")
                raise ConfigError(f"{short(value)} is not one of: {shown}", file=file, field=where)
            return value
        if self.kind == ParamKind.SCALAR:
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise ConfigError(f"expected a number, got {short(value)}", file=file, field=where)
            values = (float(value),)
        else:
            if isinstance(value, (int, float)) and not isinstance(value, bool):
                values = (float(value),) * 3
            elif isinstance(value, (list, tuple)) and len(value) == 3 and all(
                isinstance(v, (int, float)) and not isinstance(v, bool) for v in value
            ):
                values = tuple(float(v) for v in value)
            else:
                raise ConfigError(f"expected a number or a list of 3 numbers (RGB), got {short(value)}", file=file,
                                  field=where)
        for v in values:
            if not math.isfinite(v) or not (self.lower <= v <= self.upper):
                raise ConfigError(
                    f"{v:g} is outside the bounds [{self.lower:g}, {self.upper:g}]", file=file, field=where
                )
        return values[0] if self.kind == ParamKind.SCALAR else values  # type: ignore[return-value]


class LobeSpec(_Strict):
    """How to see one lobe of a model alone, and which parameters shape it.

    ``overrides`` are parameter values that switch the other lobe off (an adapter may
    instead isolate the lobe natively, e.g. with render passes, and leave it empty).
    ``empty`` marks a lobe the model does not have: it renders black without a render."""

    params: tuple[str, ...] = Field((), description="Parameters fitted in this lobe's stage.")
    overrides: dict[str, Value] = Field(default_factory=dict, description="Values that isolate this lobe.")
    empty: bool = Field(False, description="The model has no such lobe.")


class ModelSpec(_Strict):
    """A material model of one adapter."""

    name: str
    description: str = ""
    parameters: tuple[ParamSpec, ...]
    lobes: dict[Lobe, LobeSpec] = Field(
        default_factory=dict, description="Empty when the adapter cannot isolate lobes (two-stage then falls back)."
    )
    smooth: bool = Field(False, description="Its reflection is perfectly smooth (a mirror, a smooth glass): a point "
                                            "light shows in it as a point at most, so it is seen, and fitted, "
                                            "under an environment.")
    smooth_when: dict[str, float] = Field(default_factory=dict, description="Numeric parameters whose values make "
                                                                          "it perfectly smooth, as `smooth` is (a "
                                                                          "Principled BSDF of roughness 0).")
    transmits: bool = Field(False, description="Light passes through it (a glass): adapters render it with paths "
                                               "deep enough to enter the sphere and leave it (`TRANSMISSION_DEPTH`).")
    transmits_with: str | None = Field(None, description="The parameter whose positive value lets light through "
                                                         "(a transmission weight): the model transmits then.")
    complex_ior: tuple[str, str] | None = Field(None, description="A conductor's complex IOR: the names of its "
                                                                  "real and imaginary parts (eta, k), which tables "
                                                                  "map as reflectivity and edge tint.")
    texturable: tuple[str, ...] = Field((), description="Parameters the renderer takes as an image, texel by "
                                                        "texel (`Adapter.render_textured`, native files).")
    derived: tuple[str, ...] = Field((), description="Quantities the adapter derives from the parameters "
                                                     "(Model.derive: a conductor's reflectivity), for reports and "
                                                     "experiment plots.")

    @model_validator(mode="after")
    def _check(self) -> "ModelSpec":
        names = [p.name for p in self.parameters]
        if len(set(names)) != len(names):
            raise ValueError(f"model {self.name!r} has duplicate parameter names")
        for lobe in self.lobes.values():
            for n in (*lobe.params, *lobe.overrides):
                if n not in names:
                    raise ValueError(f"model {self.name!r}: lobe refers to unknown parameter {n!r}")
        for n in self.texturable:
            if n not in names or self.param(n).kind == ParamKind.CHOICE:
                raise ValueError(f"model {self.name!r}: texturable {n!r} is not a numeric parameter")
        for n in self.smooth_when:
            if n not in names or self.param(n).kind != ParamKind.SCALAR:
                raise ValueError(f"model {self.name!r}: smooth_when {n!r} is not a scalar parameter")
        if self.transmits_with is not None and (self.transmits_with not in names
                                                or self.param(self.transmits_with).kind != ParamKind.SCALAR):
            raise ValueError(f"model {self.name!r}: transmits_with {self.transmits_with!r} is not a scalar parameter")
        for n in self.complex_ior or ():
            if n not in names or self.param(n).kind != ParamKind.RGB:
                raise ValueError(f"model {self.name!r}: complex_ior {n!r} is not an RGB parameter")
        for p in self.parameters:
            for n in p.inert_when:
                if n not in names or n == p.name:
                    raise ValueError(f"model {self.name!r}: {p.name}.inert_when refers to {n!r}, not another parameter")
        return self

    def is_smooth(self, params: dict[str, Value]) -> bool:
        """Whether its reflection is perfectly smooth with these parameters (`smooth`, `smooth_when`)."""
        return self.smooth or (bool(self.smooth_when) and all(
            float(params.get(k, math.nan)) == v for k, v in self.smooth_when.items()))  # type: ignore[arg-type]

    def transmissive(self, params: dict[str, Value]) -> bool:
        """Whether light passes through a sphere of this material with these parameters."""
        return self.transmits or (self.transmits_with is not None
                                  and float(params.get(self.transmits_with, 0.0)) > 0.0)  # type: ignore[arg-type]

    def param(self, name: str) -> ParamSpec:
        for p in self.parameters:
            if p.name == name:
                return p
        raise KeyError(name)

    @property
    def names(self) -> list[str]:
        return [p.name for p in self.parameters]

    @property
    def has_lobes(self) -> bool:
        return all(lobe in self.lobes for lobe in LOBES)

    def complete(self, given: dict[str, Any], *, file: str | None = None, prefix: str = "params") -> dict[str, Value]:
        """Validate ``given`` and fill the rest with defaults. Errors name the field."""
        unknown = [k for k in given if k not in self.names]
        if unknown:
            raise ConfigError(
                f"unknown parameter {unknown[0]!r} for model {self.name!r} (known: {', '.join(self.names)})",
                file=file,
                field=f"{prefix}.{unknown[0]}",
            )
        out: dict[str, Value] = {}
        for p in self.parameters:
            out[p.name] = p.coerce(given[p.name], f"{prefix}.{p.name}", file) if p.name in given else p.default
        return out

    def settle(self, given: dict[str, Any], *, file: str | None = None, prefix: str = "params") -> dict[str, Any]:
        """``given`` with the choices its values imply: a value away from its default that counts only
        with one value of a choice the file leaves unsaid sets that choice (an anisotropic roughness
        along and across means anisotropic); one whose choice the file sets otherwise, or two
        that need different values of one choice, is a ConfigError naming both. Nothing given is
        dropped without a word."""
        out = dict(given)
        needs: dict[str, tuple[tuple[str, ...], str]] = {}  # choice -> (values it may take, the value needing it)
        for name, value in given.items():
            if name not in self.names or _same(self.param(name).default, value):
                continue
            for choice, allowed in self.param(name).active_when.items():
                where = f"{prefix}.{name}"
                if choice in given and given[choice] not in allowed:
                    raise ConfigError(f"{name} counts only with {choice}: {' or '.join(allowed)}, and {choice} is "
                                      f"{given[choice]!r}: remove {name}, or set {choice}", file=file, field=where)
                if choice in needs and not set(allowed) & set(needs[choice][0]):
                    other = needs[choice][1]
                    raise ConfigError(f"{name} and {other} need different {choice} ({' or '.join(allowed)}, "
                                      f"{' or '.join(needs[choice][0])}): give one of them", file=file, field=where)
                needs[choice] = (tuple(a for a in allowed if a in needs.get(choice, (allowed, ""))[0]), name)
        for choice, (allowed, name) in needs.items():
            if choice not in given and self.param(choice).default not in allowed:
                if len(allowed) != 1:
                    raise ConfigError(f"{name} counts only with {choice}: {' or '.join(allowed)}: set {choice}",
                                      file=file, field=f"{prefix}.{name}")
                out[choice] = allowed[0]
        return out

    def is_active(self, name: str, params: dict[str, Value]) -> bool:
        spec = self.param(name)
        return all(params.get(k) in allowed for k, allowed in spec.active_when.items())

    def is_inert(self, name: str, params: dict[str, Value]) -> bool:
        """Whether this parameter cannot change the image with these values of the others."""
        spec = self.param(name)
        return bool(spec.inert_when) and all(params.get(k) == v for k, v in spec.inert_when.items())

    def active(self, params: dict[str, Value]) -> dict[str, Value]:
        """The parameters that mean something with these choices (eta and k only without a preset)."""
        return {k: v for k, v in params.items() if self.is_active(k, params)}

    def fittable(self, params: dict[str, Value], fixed: set[str] = frozenset()) -> list[str]:
        """Parameters the optimiser varies by default: numeric, active, marked `fit`, not fixed."""
        return [
            p.name
            for p in self.parameters
            if p.kind != ParamKind.CHOICE and (p.fit or _holds(p.fit_when, params)) and p.name not in fixed
            and self.is_active(p.name, params) and not _holds(p.held_when, params)
        ]

    def with_lobe(self, params: dict[str, Value], lobe: str | None) -> dict[str, Value]:
        """Apply a lobe's overrides (for adapters that isolate lobes by parameters)."""
        if lobe is None:
            return params
        return {**params, **self.lobes[lobe].overrides}


class Native(_Strict):
    """A material as its own file holds it (a node tree in a .blend): its renderer renders it from the
    file (`Adapter.render_native`), whatever a reader could make of it. The material's `model` and
    `params` are then only its reading, which chooses the target model and the fit's start; an empty
    `model` is a material with no reading (`core.host.model.AS_WRITTEN`)."""

    file: str = Field(description="The file that holds it (absolute); not in a job's key.")
    name: str = Field(description="The material's name in that file.")
    sha256: str = Field(description="The file's content: a changed file is another job.")
    driven: tuple[str, ...] = Field((), description="Its inputs driven by an image or a node graph, in words "
                                                    "(\"base_color <- image 'wood.png'\"): a uniform target cannot "
                                                    "follow them, and its result says so.")
    transmits: bool = Field(False, description="Light may pass through it (a glass, a translucent or subsurface "
                                               "node): rendered with the paths through the sphere.")
    element: str = Field("", description="The material's own text where its renderer loads it from text (a Mitsuba "
                                         "`<bsdf>` element, its files made absolute); '' where the adapter reads "
                                         "`file` itself.")


class Material(_Strict):
    """A material file: which adapter and model, and its parameters."""

    adapter: str = Field(description="Adapter that renders it (see `remap adapters`).")
    model: str = Field(description="Material model of that adapter.")
    params: dict[str, Any] = Field(default_factory=dict, description="Parameter values; others take defaults.")
    name: str = Field("", description="Optional label.")
    textures: dict[str, Texture] = Field(default_factory=dict, description="Parameters driven by an image, texel by "
                                                                            "texel (its `params` value is the one "
                                                                            "used without the texture).")
    native: Native | None = Field(None, description="The material rendered from its own file as written; its "
                                                    "`params` are then its reading (see `Native`).")


def _holds(when: dict[str, float], params: dict[str, Any]) -> bool:
    """Whether every parameter named takes its value (False for an empty condition)."""
    return bool(when) and all(params.get(k) == v for k, v in when.items())


def _same(a: Any, b: Any) -> bool:
    """Whether a given value is a parameter's default (numbers compared as numbers)."""
    try:
        x = [float(v) for v in (a if isinstance(a, (list, tuple)) else [a])]
        y = [float(v) for v in (b if isinstance(b, (list, tuple)) else [b])]
    except (TypeError, ValueError):
        return a == b
    return x == y or (len(x) == 3 and len(y) == 1 and x == y * 3)


def load_material(path: str | Path) -> Material:
    """A material file; its textures' files are relative to it, and are read (hashed) here."""
    from .configio import load_yaml_model
    from .textures import texture

    m = load_yaml_model(path, Material, "a material")
    if m.native is not None:  # a digest a file could claim, and a file it could name: the readers' alone
        raise ConfigError("is set by the readers of .blend, Mitsuba and MaterialX files, not written in a material "
                          "file: give the file itself to `remap convert`", file=str(path), field="native")
    if not m.textures:
        return m
    here = Path(path).resolve().parent
    return m.model_copy(update={"textures": {
        k: texture(here / t.file, t.colorspace, t.filter, where=f"{path}: textures.{k}") for k, t in m.textures.items()}})


def short(value: Any, n: int = 80) -> str:
    """A value's repr for an error message, cut to ``n`` characters (a pasted blob stays one line)."""
    text = repr(value)
    return text if len(text) <= n else text[:n] + "…"


def format_value(v: Value) -> str:
    if isinstance(v, str):
        return v
    if isinstance(v, tuple):
        return "[" + ", ".join(f"{x:.4g}" for x in v) + "]"
    return f"{v:.4g}"


def parse_fix(text: str, spec: ModelSpec, flag: str = "--fix") -> tuple[str, Value]:
    """Parse ``name=value`` from the command line against the target model."""
    if "=" not in text:
        raise ConfigError(f"expected name=value, got {text!r}", field=flag)
    name, raw = (s.strip() for s in text.split("=", 1))
    if name not in spec.names:
        raise ConfigError(
            f"unknown parameter {name!r} for model {spec.name!r} (known: {', '.join(spec.names)})", field=f"{flag} {name}"
        )
    p = spec.param(name)
    value: Any = raw
    if p.kind != ParamKind.CHOICE:
        try:
            parts = [float(x) for x in raw.replace(" ", "").strip("[]").split(",")]
        except ValueError:
            raise ConfigError(f"expected a number or r,g,b, got {raw!r}", field=f"{flag} {name}") from None
        value = parts[0] if len(parts) == 1 else parts
    return name, p.coerce(value, f"{flag} {name}")


__all__ = [
    "ParamSpec",
    "LobeSpec",
    "ModelSpec",
    "Material",
    "load_material",
    "parse_fix",
    "format_value",
    "ValidationError",
    "LOBES",
]
