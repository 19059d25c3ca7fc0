"""The YAML description of an external renderer (no Python needed to plug one in)."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any, Literal

from brdfremap.core.data.configio import load_yaml_model
from brdfremap.core.data.schemas import Lobe, LobeSpec, ParamKind, ParamSpec
from brdfremap.core.host.model import Model
from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

from .declared import DeclaredModel, Reading, Source, problem

FORMAT = 2
"""The definition format this version writes and reads strictly. 1 (a definition without `format:`)
gave a fitted parameter that neither short-form lobe switches off to the specular stage; 2 asks for
the long form there (the first new user's model reached 57.8 % that way)."""
PLACEHOLDERS = ("scene_json", "params_json", "output", "model", "width", "height", "spp", "spp_sqrt", "spp_log2",
                "seed", "scene_file", "python", "here", "defines")


class Native(BaseModel):
    model_config = ConfigDict(extra="forbid")

    file: str = Field(description="The file name written beside result.json, e.g. material.xml.")
    text: str = Field(description="Its text: {p_<parameter>} (RGB through rgb_format) and {model} are filled.")

    @field_validator("file")
    @classmethod
    def _plain(cls, name: str) -> str:
        from brdfremap.core.job.execute import IMAGES
        from brdfremap.core.run.store import RESULT

        reserved = (RESULT, *IMAGES)
        # Compared without case: on a case-insensitive disk Result.json is result.json.
        if not re.fullmatch(r"[A-Za-z0-9][A-Za-z0-9._-]*", name) or name.lower() in reserved or ".." in name:
            raise ValueError(f"{name!r} must be a plain file name (letters, digits, . _ -), not one of "
                             f"{', '.join(reserved)}")
        return name


class ModelDef(BaseModel):
    model_config = ConfigDict(extra="forbid")

    description: str = ""
    parameters: list[ParamSpec] = Field(description="The model's parameters.")
    lobes: dict[Lobe, Any] = Field(
        default_factory=dict,
        description="Per lobe, the parameter values that isolate it ({specular: 0}); or the long form "
                    "{overrides: {...}, params: [...]}; or 'empty'.")
    native: "Native | None" = Field(None, description="The material in the renderer's own form, written beside "
                                                       "each result with the fitted values.")
    template_vars: dict[str, str] = Field(default_factory=dict,
                                          description="Extra text substituted into the scene template for this "
                                                      "model, e.g. its <bsdf> element; it may use the scene's "
                                                      "placeholders and {p_<parameter>} (RGB through rgb_format).")
    start: dict[str, Source] = Field(
        default_factory=dict,
        description="The exporters' conversion of a neutral reading into this model, which a remap to it starts "
                    "from: per parameter, a quantity of the reading (alpha, diffuse, base_color, ior, ...), as it is "
                    "or {from: QUANTITY, as: CONVERSION or [CONVERSIONS], scale: NUMBER}, or {value: CONSTANT}. "
                    "What the reading lacks (no alpha, no coat) is left out.")
    reading: Reading | None = Field(
        None, description="How an exporter reads a material of this model in neutral terms, so that a remap from it "
                          "starts informed: kind (conductor or dielectric) and Appearance fields, each a parameter, "
                          "as it is or {from: PARAMETER, as: ..., scale: ...}, or {value: CONSTANT}.")


class Calibration(BaseModel):
    model_config = ConfigDict(extra="forbid")

    model: str
    params: dict[str, Any] = Field(default_factory=dict)


class RendererDef(BaseModel):
    """An external renderer run as a command: one process per render, or one persistent process."""

    model_config = ConfigDict(extra="forbid")

    name: str = Field(description="Adapter name shown by `remap adapters`.")
    format: int = Field(1, ge=1, description=f"The definition format it was written for: {FORMAT} (this version's; "
                                              "write it in a new definition), or 1 (the first; a definition "
                                              "without it): read as it was meant, with a note where the current "
                                              "form differs.")
    description: str = ""
    command: list[str] = Field(min_length=1, description="argv; placeholders are substituted per argument.")
    mode: Literal["oneshot", "persistent"] = Field("oneshot", description="persistent: JSON lines on stdin/stdout.")
    timeout: float = Field(60.0, gt=0, description="Seconds per render (the process group is killed after).")
    start_timeout: float = Field(120.0, gt=0, description="Seconds for a persistent renderer to greet.")
    output_format: Literal["exr", "pfm", "hdr", "png"] = Field(
        "exr", description="What the renderer writes at {output}: float EXR, PFM or Radiance HDR (linear), or an "
                           "8-bit sRGB PNG (clips at 1: for tests only).")
    define: list[str] = Field(["-D", "{key}={value}"],
                              description="How `{defines}` expands for each parameter, e.g. ['-D', '{key}={value}'].")
    rgb_format: str = Field("{r}, {g}, {b}", description="How an RGB value is written into a define or a template.")
    scene_template: str | None = Field(None, description="A file (relative to this YAML) whose placeholders are "
                                       "filled per render and passed as {scene_file}.")
    env: dict[str, str] = Field(default_factory=dict, description="Extra environment variables.")
    jobs: int | None = Field(None, ge=1, le=256, description="One-shot renders run at once (a Jacobian's, the "
                                                              "validation's); default: this machine's cores.")
    requires: list[str] = Field(default_factory=list,
                                description="Executables or Python modules that must exist (`py:module`).")
    models: dict[str, ModelDef]
    calibration: "Calibration | None" = Field(None, description="A white diffuse material of albedo 0.8, which "
                                                                "`remap check` renders against the analytic radiance.")

    @field_validator("command")
    @classmethod
    def _known_placeholders(cls, argv: list[str]) -> list[str]:
        from .template import placeholders

        for arg in argv:
            for name, _ in placeholders(arg):
                if name not in PLACEHOLDERS:
                    raise ValueError(f"unknown placeholder {{{name}}} in {arg!r} (known: {', '.join(PLACEHOLDERS)})")
        if any("{defines}" in a and a != "{defines}" for a in argv):
            raise ValueError("{defines} must be an argument of its own")
        return argv

    @field_validator("rgb_format")
    @classmethod
    def _rgb(cls, text: str) -> str:
        try:
            text.format(r="1", g="2", b="3")
        except (KeyError, IndexError, ValueError) as exc:
            raise ValueError(f"{text!r} cannot be filled ({type(exc).__name__}: {exc}): use {{r}}, {{g}} and {{b}}, "
                             "e.g. '{r}, {g}, {b}'") from None
        return text

    @field_validator("define")
    @classmethod
    def _define(cls, items: list[str]) -> list[str]:
        from .template import placeholders

        for item in items:
            for name, _ in placeholders(item):
                if name not in ("key", "value"):
                    raise ValueError(f"unknown placeholder {{{name}}} in {item!r}: a define knows {{key}} and {{value}}")
        return items

    @model_validator(mode="before")
    @classmethod
    def _format(cls, data: Any) -> Any:
        """A newer format first: its fields this version does not know are not the user's mistake."""
        v = data.get("format") if isinstance(data, dict) else None
        if isinstance(v, int) and v > FORMAT:
            raise ValueError(f"format: written for a newer brdf-remap (definition format {v}; this one reads 1 to "
                             f"{FORMAT}): upgrade brdf-remap, or write it in format {FORMAT}")
        return data

    @model_validator(mode="after")
    def _modes(self) -> "RendererDef":
        if self.calibration is not None and self.calibration.model not in self.models:
            raise ValueError(f"calibration: model {self.calibration.model!r} is not one of models "
                             f"({', '.join(self.models)})")
        from .template import placeholders

        used = {name for a in self.command for name, _ in placeholders(a)}
        if self.mode == "oneshot" and "output" not in used:
            raise ValueError("command: a oneshot command must say where to write the image: use {output}")
        if "scene_file" in used and not self.scene_template:
            raise ValueError("command: {scene_file} is the filled scene template: give scene_template (a file "
                             "beside this one) too")
        return self

    @model_validator(mode="after")
    def _declared(self) -> "RendererDef":
        """Each model's `start:` and `reading:` name its parameters and the reading's quantities, types fitting."""
        for name, m in self.models.items():
            msg = problem(name, m.parameters, m.start, m.reading)
            if msg:
                raise ValueError(msg)
        return self

    def format_notes(self) -> list[str]:
        """What a definition of an older format says that the current format says otherwise: each a
        line naming the model and what to write instead ([] for a current one)."""
        if self.format >= FORMAT:
            return []
        return [f"{msg}; read as format 1 gave them to the specular stage, as it is read now (add `format: "
                f"{FORMAT}` once changed)" for msg in map(_ambiguous, self.models, self.models.values()) if msg]

    def model_specs(self) -> dict[str, Model]:
        specs = {}
        for name, m in self.models.items():
            numeric = [p.name for p in m.parameters if p.kind != ParamKind.CHOICE]
            lobes: dict[str, LobeSpec] = {}
            raw = {k: v for k, v in m.lobes.items()}
            short = _short(m)
            ambiguous = _ambiguous(name, m)
            if ambiguous and self.format >= FORMAT:
                raise ValueError(ambiguous)
            for lobe, v in raw.items():
                if v == "empty":
                    lobes[lobe] = LobeSpec(empty=True)
                elif lobe in short:
                    # Short form: the params of a lobe are those the *other* lobe switches off.
                    other = Lobe.SPECULAR if lobe == Lobe.DIFFUSE else Lobe.DIFFUSE
                    mine = list(short.get(other, {}))
                    if lobe == Lobe.SPECULAR:
                        mine += [p for p in numeric if p not in mine and p not in short.get("specular", {})]
                    lobes[lobe] = LobeSpec(overrides=v, params=tuple(dict.fromkeys(mine)))
                else:
                    lobes[lobe] = LobeSpec(**v)
            spec = dict(name=name, description=m.description, parameters=tuple(m.parameters), lobes=lobes)
            declared = m.start or m.reading is not None
            specs[name] = DeclaredModel(**spec, start=m.start, reading=m.reading) if declared else Model(**spec)
        return specs


def _short(m: ModelDef) -> dict[str, dict]:
    """The lobes given in the short form ({specular: 0}), by lobe."""
    return {k: v for k, v in m.lobes.items() if isinstance(v, dict) and "overrides" not in v and "params" not in v}


def _ambiguous(model: str, m: ModelDef) -> str | None:
    """Both lobes in the short form, and fitted parameters neither switches off: the short form would
    give them all to the specular stage, a colour both lobes share included (the first new user's model
    reached 57.8 % that way). The long form says which lobe each belongs to. Held parameters (fit:
    false) are set, never fitted: no stage needs them, so no lobe. None where nothing is left over."""
    short = _short(m)
    if set(short) != {"diffuse", "specular"}:
        return None
    numeric = [p.name for p in m.parameters if p.kind != ParamKind.CHOICE and (p.fit or p.fit_when or p.fit_when_carried
                                                                       or p.fit_for)]
    left = [p for p in numeric if p not in short["diffuse"] and p not in short["specular"]]
    if not left:
        return None
    return (
        f"{model}.lobes: the short form leaves {', '.join(left)} to neither lobe; write the long form and put each "
        f"in the params of the lobe whose stage should fit it, or in neither when both lobes share it (a colour), "
        f"e.g. diffuse: {{overrides: {_flow(short['diffuse'])}, params: [{', '.join(short['specular'])}]}}, "
        f"specular: {{overrides: {_flow(short['specular'])}, params: [{', '.join(short['diffuse'])}, ...]}}")


def _flow(values: dict) -> str:
    return "{" + ", ".join(f"{k}: {v}" for k, v in values.items()) + "}"


def load_definition(path: str | Path) -> RendererDef:
    from .template import check_definition

    definition = load_yaml_model(path, RendererDef, "a renderer definition")
    check_definition(Path(path), definition)
    try:
        definition.model_specs()
    except ValueError as exc:
        from brdfremap.core.data.configio import validation_message
        from brdfremap.core.data.errors import ConfigError
        from pydantic import ValidationError

        msg = validation_message(exc)[1] if isinstance(exc, ValidationError) else str(exc).splitlines()[0]
        raise ConfigError(msg, file=str(path), field="models") from None
    _say_once(Path(path), definition.format_notes())
    return definition


_SAID: set[str] = set()


def _say_once(path: Path, notes: list[str]) -> None:
    """An older definition's notes, once for each file, by the process the user started (a worker
    process loads the definition again, and says nothing)."""
    import multiprocessing
    import sys

    key = str(path.resolve())
    if key in _SAID or multiprocessing.parent_process() is not None:
        return
    _SAID.add(key)
    for n in notes:
        print(f"note: {path}: format 1: {n}", file=sys.stderr)
