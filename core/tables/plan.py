"""A table spec checked against the installed adapters (`plan`), and its points as remap jobs:
each grid point or held-out material a job (`point_task`), each finished fit the record the table
keeps of it (`record`)."""

from __future__ import annotations

from dataclasses import dataclass

from ..data.errors import ConfigError
from ..data.findings import CannotResolve, ImagePrecision, NoEffect, NotAtMinimum, RendererAlters, Severity
from ..data.schemas import Material, ModelSpec, ParamKind
from ..host.plugins import AdapterRegistry
from ..job.job import Job, Lookup, Where, model_of, resolve
from ..run.runner import Done, Task
from .spec import AxisMode, Layout, TableSpec
from .table import LeftOut, PointRecord, PointVerdict

QUESTIONED = (NotAtMinimum, CannotResolve, ImagePrecision, RendererAlters, NoEffect)
"""Findings that put the fit itself in question (it may not be the best this target does): such a
point is left out of the regression. A mismatch, a held-out light over the threshold, a bound the
fit presses on, parameters that trade off: the fit is still the closest the target gets, and kept."""
COLOUR_SEED = 7919
"""The coloured points' draw: the held-out draw's seed plus this (another Sobol' scrambling)."""


@dataclass
class Plan:
    """A spec checked against the installed adapters: its layout and the jobs of its points."""

    spec: TableSpec
    file: str
    layout: Layout
    source_spec: ModelSpec
    target_spec: ModelSpec
    source_params: dict
    grid: list[tuple[tuple[int, ...], dict]]
    held: list[dict]
    colours: list[dict]


def plan(spec: TableSpec, file: str, registry: AdapterRegistry) -> Plan:
    """Every check before any render: axes are continuous parameters of the source within its
    bounds, the target's discrete choices are held, and every point's job resolves."""
    src = model_of(registry, spec.source.adapter, spec.source.model, file, "source.")
    tgt = model_of(registry, spec.target.adapter, spec.target.model, file, "target.")
    params = src.complete(spec.source.params, file=file, prefix="source.params")
    kinds = {}
    for name, ax in spec.axes.items():
        kinds[name] = _axis_kind(src, name, ax, params, file)
    same = (spec.source.adapter, spec.source.model) == (spec.target.adapter, spec.target.model)
    for p in tgt.parameters:
        if p.kind == ParamKind.CHOICE and p.explore and not same and p.name not in spec.target.fix:
            raise ConfigError(f"the fit would try each {p.name} and keep the best, point by point, and a map cannot "
                              f"follow a choice: hold it (target.fix.{p.name}: one of {', '.join(p.choices)})",
                              file=file, field="target.fix")
    layout = Layout(spec.axes, kinds)
    if spec.colours and (len(layout.grey_axes) != 1 or not layout.separable):
        raise ConfigError(f"coloured points correct a map over one RGB axis sampled as grey levels (and none as "
                          f"channels), and this spec has {len(layout.grey_axes)} grey: set colours to 0, or give one "
                          "RGB axis with mode: scale", file=file, field="colours")
    if spec.colours and not spec.holdout:
        raise ConfigError("coloured points need held-out materials, on which a map is compared with its "
                          "correction: give holdout (10 or more) or set colours to 0", file=file, field="colours")
    return Plan(spec, file, layout, src, tgt, {k: v for k, v in params.items() if k not in spec.axes},
                layout.grid(), layout.draw(spec.holdout, spec.seed), layout.draw(spec.colours, spec.seed + COLOUR_SEED))


def _axis_kind(src: ModelSpec, name: str, ax, params: dict, file: str) -> str:
    field = f"axes.{name}"
    if name not in src.names:
        raise ConfigError(f"model {src.name!r} has no parameter {name!r} (known: {', '.join(src.names)})", file=file,
                          field=field)
    p = src.param(name)
    if p.kind == ParamKind.CHOICE:
        raise ConfigError(f"{name} is a choice ({', '.join(p.choices)}): an axis is a continuous parameter; give "
                          "the choice in source.params (a table per value)", file=file, field=field)
    if not src.is_active(name, params):
        raise ConfigError(f"{name} does nothing with {', '.join(f'{k}={params[k]}' for k in p.active_when)}",
                          file=file, field=field)
    lo, hi = ax.range
    if lo < p.lower or hi > p.upper:
        raise ConfigError(f"range [{lo:g}, {hi:g}] goes outside {name}'s bounds [{p.lower:g}, {p.upper:g}]",
                          file=file, field=f"{field}.range")
    if p.kind == ParamKind.SCALAR and ax.mode == AxisMode.CHANNELS:
        raise ConfigError("mode channels is for an RGB parameter", file=file, field=f"{field}.mode")
    if p.kind == ParamKind.RGB and ax.mode == AxisMode.SCALE and not p.separable:
        raise ConfigError(f"{name}'s channels do not act alone in the image, so a grey sample cannot stand for a "
                          "colour: use mode: channels", file=file, field=f"{field}.mode")
    return p.kind


def _material(p: Plan, values: dict, name: str) -> Material:
    return Material(adapter=p.spec.source.adapter, model=p.spec.source.model,
                    params={**p.spec.source.params, **values}, name=name)


def point_task(p: Plan, registry: AdapterRegistry, slot: str, values: dict, title: str, scene, settings,
               lookup: Lookup | None = None, start: dict | None = None) -> Task:
    """The job of one point (a fit, a refit from ``start``, or a lookup's check) stored at ``slot``."""
    job = Job(source=_material(p, values, slot), target=p.spec.target, scene=scene, settings=settings.for_study(),
              label=f"{p.file} {slot}", lookup=lookup, start=start,
              fit_same_model=True)
    where = Where(source_file=p.file, source_prefix="source.", params_prefix=f"{slot} ({shown(values)})",
                  target_file=p.file, target_prefix="target.", fix_prefix="target.fix", command_line=False)
    return Task(slot, resolve(job, registry, where), title)


def shown(values: dict) -> str:
    return ", ".join(f"{k}=" + ("[" + ",".join(f"{x:.3g}" for x in v) + "]" if isinstance(v, list) else f"{v:.4g}")
                     for k, v in values.items())


def record(point_id: str, values: dict, done: Done, index: tuple[int, ...] = ()) -> PointRecord:
    """What the table keeps of one fit, and whether the map may use it."""
    r = done.report
    if r is None:
        return PointRecord(id=point_id, index=list(index), values=values, params=None, error=None,
                           verdict=PointVerdict.FAILED, reason=done.error, used=False,
                           left_out=f"the fit failed: {done.error}", left_out_as=LeftOut.FAILED)
    kinds = [f.kind for f in r.findings if f.severity == Severity.UNRELIABLE]
    questioned = [f.message for f in r.findings if f.severity == Severity.UNRELIABLE and isinstance(f, QUESTIONED)]
    return PointRecord(id=point_id, index=list(index), values=values, params=dict(r.params),
                       error=r.metrics.relative_rmse, noise_floor=r.metrics.noise_floor, verdict=r.verdict,
                       reason="" if r.reliable else r.reason, findings=kinds, used=not questioned,
                       left_out="; ".join(questioned), left_out_as=LeftOut.QUESTIONED if questioned else None,
                       renders=r.renders, seconds=r.seconds, key=r.key)


def fitted_names(p: Plan, points: list[PointRecord], done: list[Done]) -> list[str]:
    """The target parameters the fits varied (in the model's order)."""
    fitted = {n for d in done if d.report is not None for n in d.report.fitted}
    return [n for n in p.target_spec.names if n in fitted]


