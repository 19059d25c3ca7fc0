"""One unit of work: a source material remapped to a target model, under a scene and settings.

A `Job` is data (pydantic: serialisable, hashable into its key).
`resolve` validates it once, before any render, against the installed adapters and returns it
in canonical form (adapter names checked, parameters completed and coerced, adapter versions
recorded), together with what the engine needs. `Job.key()` of a canonical job identifies its
result: the same key means the same result, so a stored one can be reused."""

from __future__ import annotations

import functools
import hashlib
import json
from dataclasses import dataclass
from typing import Any

from pydantic import Field

from ..data.errors import ConfigError
from ..data.model import Strict
from ..data.scene import MAX_SPP, ProbeScene
from ..data.appearance import Appearance
from ..data.schemas import Material, ModelSpec, ParamKind, Value
from ..host.model import AS_WRITTEN, Model, Rule
from .texturing import TexturedStep
from ..data.settings import Settings
from ..engine.tuning import ENGINE_VERSION, Tuning
from ..host.plugins import AdapterRegistry


class Target(Strict):
    """The target side of a job: an adapter's model, and parameters held fixed."""

    adapter: str = Field(description="Target adapter (see `remap adapters`).")
    model: str = Field(description="Material model of that adapter.")
    fix: dict[str, Any] = Field(default_factory=dict, description="Target parameters held at these values.")


class Lookup(Strict):
    """The target's parameters read from a remap table instead of fitted: the result renders them
    and judges them like a fit's."""

    table: str = Field(description="The table's name.")
    digest: str = Field(description="The table file's digest (another table, another job).")
    file: str = Field("", description="Where the table was read (its map remaps a textured source texel by texel); "
                                      "not in the key.")
    method: str = Field(description="The table's map that gave the parameters.")
    params: dict[str, Any] = Field(description="The target's parameters the map gave (complete).")
    expected_error: float | None = Field(None, description="The relative RMSE the table's direct fits reach about "
                                                           "these source values.")
    outside: list[str] = Field(default_factory=list, description="Source values outside the table's range (the "
                                                                 "map clamped them), in words.")


class Job(Strict):
    """A remap request, complete: what determines its result, and a label for people."""

    source: Material
    target: Target
    scene: ProbeScene = Field(default_factory=ProbeScene)
    settings: Settings = Field(default_factory=Settings)
    tuning: Tuning = Field(default_factory=Tuning, description="Engine internals (benchmarks change them).")
    label: str = Field("", description="Where the source came from (a file, a point, a material); not in the key.")
    versions: dict[str, str] = Field(default_factory=dict, description="Versions of the adapters involved, "
                                                                       "recorded by `resolve`; in the key.")
    lookup: Lookup | None = Field(None, description="Parameters from a remap table: rendered and judged, not "
                                                    "fitted.")
    fit_same_model: bool = Field(False, description="Fit a source to its own model of the same renderer all the same "
                                                    "(a test of the optimiser, whose answer is known; tables and "
                                                    "experiments); else its parameters are the result, with nothing "
                                                    "to fit.")
    start: dict[str, Any] | None = Field(None, description="Target parameters the fit starts from instead of the "
                                                           "exporters' conversion (a table's continuation from its "
                                                           "neighbours' fits).")

    def key(self) -> str:
        """The hash of everything that determines the result (the engine version included),
        not of labels, names or notes."""
        doc = {
            "engine": ENGINE_VERSION,
            # A material rendered as written by its content (`Native.sha256`), not its file's path or its text's
            # (a Mitsuba element names its files by absolute paths).
            "source": self.source.model_dump(mode="json", exclude={"name": True, "textures": True,
                                                                   "native": {"file", "element"}}),
            "target": self.target.model_dump(mode="json"),
            "scene": json.loads(self.scene.cache_key()),
            "settings": self.settings.model_dump(mode="json"),
            "tuning": self.tuning.model_dump(mode="json"),
            "versions": self.versions,
        }
        # Absent from the key when unused: fits stored before tables and textures keep their keys
        # (and their reports are read as they are: report.READS_FROM).
        if self.lookup is not None:
            doc["lookup"] = self.lookup.model_dump(mode="json", exclude={"file"})
        if self.start is not None:
            doc["start"] = self.start
        if self.fit_same_model:
            doc["fit_same_model"] = True
        if self.source.textures:  # an image by its content, not its path
            doc["textures"] = {k: t.model_dump(mode="json", exclude={"file"}) for k, t in self.source.textures.items()}
        blob = json.dumps(doc, sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(blob.encode()).hexdigest()[:20]


@dataclass(frozen=True)
class Where:
    """Where a job's fields came from, so an error names them as the user wrote them: a material
    file (fields `adapter`, `params.alpha`), an experiment (`source.model`, `target.fix.alpha`)
    or the command line (`--model`)."""

    source_file: str | None = None
    source_prefix: str = ""
    params_prefix: str = "params"
    target_file: str | None = None
    target_prefix: str = "--"
    fix_prefix: str = "--fix"
    command_line: bool = True
    """Whether the target's fields are flags (`--fix alpha`) or a file's keys (`target.fix.alpha`)."""

    def fix_field(self, name: str) -> str:
        """A held parameter's field as the user wrote it."""
        return f"{self.fix_prefix}{' ' if self.command_line else '.'}{name}"

    def field(self, flag: str, key: str) -> str:
        """A setting's field: its flag on the command line, its key in a file."""
        return flag if self.command_line else key


@dataclass(frozen=True)
class Resolved:
    """A validated job in canonical form, and what the engine needs of it."""

    job: Job
    source_spec: Model
    target_spec: Model
    source_params: dict[str, Value]
    base: dict[str, Value]
    """The target's complete parameters before the fit: defaults, carried choices, fixed values."""
    free: list[str]
    fixed: dict[str, Value]
    textured: TexturedStep | None = None
    """A textured source's remap texel by texel and its check (`core.textured.texture_result`), given
    by whoever resolved the job; None for a uniform one."""

    @functools.cached_property
    def look(self) -> Appearance | None:
        """The source read in renderer-neutral terms (`Model.appearance`), read once for the job: its
        informed start, the inputs it needs, its reference for the renderers' floor."""
        return self.source_spec.appearance(self.source_params)

    @functools.cached_property
    def rule(self) -> Rule | None:
        """The source's fixed rule for the target model, where its format defines one (`Model.rule_for`):
        the fit's start, and the rule's error beside the fit's."""
        return self.source_spec.rule_for(self.target_spec, self.source_params)

    @property
    def source_transmits(self) -> bool:
        """Whether light passes through the source: its reading says so, or its file as written does
        (`Native.transmits`): one answer for its renders, its fit scene and its verdict."""
        native = self.job.source.native
        return self.source_spec.transmissive(self.source_params) or (native is not None and native.transmits)

    @property
    def same_material(self) -> bool:
        """The target is the source's own model in the same renderer, nothing held otherwise and nothing
        looked up: the source's parameters are the result, with nothing to fit."""
        job = self.job
        return (not job.fit_same_model
                and (job.source.adapter, job.source.model) == (job.target.adapter, job.target.model)
                and job.lookup is None and job.start is None and self.textured is None and job.source.native is None
                and all(self.source_params.get(k) == v for k, v in self.fixed.items()))


def source_model(registry: AdapterRegistry, material: Material, file: str | None, prefix: str) -> Model:
    """A source's model: its adapter's (`model_of`), or `AS_WRITTEN` for a material its renderer renders
    from its own file with no reading (`Material.native`, no model), where that adapter renders such."""
    if material.native is not None:
        entry = registry.get(material.adapter, file=file, field_name=f"{prefix}adapter")
        if not entry.natives:
            raise ConfigError(f"adapter {material.adapter!r} does not render a material from its own file",
                              file=file, field=f"{prefix}native")
        if not material.model:
            return AS_WRITTEN
    return model_of(registry, material.adapter, material.model, file, prefix)


def model_of(registry: AdapterRegistry, adapter: str, model: str, file: str | None, prefix: str) -> Model:
    entry = registry.get(adapter, file=file, field_name=f"{prefix}adapter")
    if not entry.models and entry.unavailable_reason():
        raise ConfigError(f"adapter {adapter!r} is unavailable: {entry.unavailable_reason()}", file=file,
                          field=f"{prefix}adapter")
    if model not in entry.models:
        known = ", ".join(sorted(entry.models)) or "none"
        raise ConfigError(f"adapter {adapter!r} has no model {model!r} (models: {known})", file=file,
                          field=f"{prefix}model")
    if not isinstance(entry.models[model], Model):  # a plugin written before models were objects
        raise ConfigError(f"adapter {adapter!r} is unavailable: {entry.unavailable_reason()}", file=file,
                          field=f"{prefix}adapter")
    return entry.models[model]


def resolve(job: Job, registry: AdapterRegistry, where: Where = Where(),
            textured: TexturedStep | None = None) -> Resolved:
    """Check everything before any render: adapters, models, parameters, bounds. Adapters are
    named, never given as files here: a data file must not choose a program to run. A textured
    source's job is a table's lookup, and ``textured`` its remap texel by texel
    (`core.textured.texture_result`, from the rooms above that know tables)."""
    src = job.source
    src_spec = source_model(registry, src, where.source_file, where.source_prefix)
    if src.textures and job.lookup is None:
        raise ConfigError(f"drives {', '.join(sorted(src.textures))} by images: a fit remaps one uniform material; "
                          "remap a textured one texel by texel through a table (--table TABLE, built with `remap "
                          "table build`)", file=where.source_file, field="textures")
    if src.textures and textured is None:  # a caller's mistake, not the user's: every command passes it
        raise ConfigError("drives its inputs by images, and the job was made without its texel-by-texel step: "
                          "resolve(..., textured=brdfremap.core.textured.texture_result)", file=where.source_file,
                          field="textures")
    settled = src_spec.settle(src.params, file=where.source_file, prefix=where.params_prefix)
    src_params = src_spec.complete(settled, file=where.source_file, prefix=where.params_prefix)
    tgt = job.target
    tgt_spec = model_of(registry, tgt.adapter, tgt.model, where.target_file, where.target_prefix)
    fix = tgt_spec.settle(tgt.fix, file=where.target_file, prefix=where.fix_prefix)
    given = tgt_spec.complete(fix, file=where.target_file, prefix=where.fix_prefix)
    fixed = {k: given[k] for k in fix}
    base = tgt_spec.complete({})
    if (src.adapter, src.model) == (tgt.adapter, tgt.model):
        # Same model: what the fit does not vary carries over unless fixed: discrete choices
        # (distribution, material preset) and the held values a neutral reading has no word for (a
        # Principled BSDF's subsurface), which the target would otherwise render at its defaults.
        base.update({p.name: src_params[p.name] for p in tgt_spec.parameters
                     if p.kind == ParamKind.CHOICE or not p.fit})
    base.update(fixed)
    if job.lookup is not None:
        looked = {k: v for k, v in job.lookup.params.items() if k not in fixed}
        base.update({k: v for k, v in tgt_spec.complete(looked, file=where.target_file,
                                                         prefix="lookup.params").items() if k in looked})
    start = None
    if job.start is not None:  # a fixed value is the job's, not the start's
        given = {k: v for k, v in job.start.items() if k not in fixed}
        start = _plain({k: v for k, v in tgt_spec.complete(given, file=where.target_file, prefix="start").items()
                        if k in given})
    _check_fixed(tgt_spec, base, fixed, where)
    _check_sampling(job, where)
    _check_scene(registry, job, where)
    free = [] if job.lookup is not None else tgt_spec.fittable(base, fixed=set(fixed))
    versions = {name: registry.get(name).version for name in dict.fromkeys((src.adapter, tgt.adapter))}
    canonical = job.model_copy(update={
        "source": src.model_copy(update={"params": _plain(src_params)}),
        "target": tgt.model_copy(update={"fix": _plain(fixed)}),
        "versions": versions,
        "lookup": None if job.lookup is None else job.lookup.model_copy(update={"params": _plain(
            {k: base[k] for k in job.lookup.params})}),
        "start": start,
    })
    return Resolved(canonical, src_spec, tgt_spec, src_params, base, free, fixed,
                    textured if src.textures else None)


def _check_fixed(spec: ModelSpec, base: dict[str, Value], fixed: dict[str, Value], where: Where) -> None:
    """A value held for a parameter the model's choices switch off would silently do nothing."""
    for name in fixed:
        if spec.is_inert(name, base):
            cond = ", ".join(f"{k}={base[k]:g}" for k in spec.param(name).inert_when)
            raise ConfigError(f"does nothing with {cond}", file=where.target_file, field=where.fix_field(name))
        if spec.is_active(name, base):
            continue
        cond = " and ".join(f"{k} is {' or '.join(v)}" for k, v in spec.param(name).active_when.items())
        now = ", ".join(f"{k}={base[k]}" for k in spec.param(name).active_when)
        raise ConfigError(f"does nothing with {now}: it is used only when {cond}", file=where.target_file,
                          field=where.fix_field(name))


def _check_scene(registry: AdapterRegistry, job: Job, where: Where) -> None:
    """Each adapter renders every light of the scene (a missing light type is found here, not mid-fit)."""
    for name in dict.fromkeys((job.source.adapter, job.target.adapter)):
        problem = registry.get(name).scene_problem(job.scene)
        if problem:
            raise ConfigError(f"adapter {name!r} cannot render the scene {job.scene.name!r}: it {problem}: use a "
                              "scene it can render",
                              field=where.field("--scene", "scene"))


def _check_sampling(job: Job, where: Where) -> None:
    spp, k = job.scene.spp, job.settings.precise_spp
    if spp * k > MAX_SPP:
        raise ConfigError(f"{spp} spp x {k} is {spp * k} samples per pixel for the noise-limited polish, over the "
                          f"{MAX_SPP} renderers take: lower it (1: no such polish)",
                          field=where.field("--precise-spp", "options.precise_spp"))


def _plain(params: dict[str, Value]) -> dict[str, Any]:
    return {k: list(v) if isinstance(v, tuple) else v for k, v in params.items()}
