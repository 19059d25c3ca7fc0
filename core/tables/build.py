"""`remap table build`: fit every grid point and every held-out material (ordinary remap jobs
through the store and the runner: resumable, `--jobs`, Dask), fit the candidate maps to the grid,
look up the held-out materials with each map and render the lookups, keep the map whose lookups
come closest to the direct fits, and write the table.

The output folder holds `points/<id>/` (each grid fit), `holdout/<id>/` (each held-out fit),
`checks/<method>/<id>/` (each map's lookup of a held-out material, rendered and judged),
`table.json`, and `points.csv` (every fit in a row). Rerun after an interruption and only what
is missing runs."""

from __future__ import annotations

import csv
import io
import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..atomic import write_text_atomic
from ..errors import ConfigError
from ..executors import Workers
from ..job import Job, Lookup, Where, model_of, resolve
from ..plugins import AdapterRegistry
from ..runner import Done, Runner, Task
from ..schemas import Material, ModelSpec
from ..store import Store, owned
from .maps import METHODS, build, choose_hyperparameter
from .spec import Layout, TableSpec
from .outputs import choose_scales, outputs_for
from .table import TABLE_SCHEMA_VERSION, BuildRecord, Candidate, PointRecord, Table, TableMap, grid_of, write_table

QUESTIONED = frozenset({"not_at_minimum", "cannot_resolve", "image_precision", "renderer_alters", "no_effect"})
"""Findings that put the fit itself in question (it may not be the best this target does): such a
point is left out of the regression. A mismatch, a held-out light over the threshold, a bound the
fit presses on, parameters that trade off: the fit is still the closest the target gets, and kept."""
REMEDIES: dict[str, dict] = {"not_at_minimum": {"scheme": "three"}}
"""The refit a grid point's finding names as its remedy (the fit's own advice to a user: a fit that
stopped short of a minimum of the full image is fitted again by scheme three, every parameter on
the full image). The refit replaces the first fit where it ends lower."""
PREFERENCE = ("polynomial", "rbf", "multilinear")
"""Order among maps that do equally well: the smoothest first."""


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
        if p.kind == "choice" and p.explore and not same and p.name not in spec.target.fix:
            raise ConfigError(f"the fit would try each {p.name} and keep the best, point by point, and a map cannot "
                              f"follow a choice: hold it (target.fix.{p.name}: one of {', '.join(p.choices)})",
                              file=file, field="target.fix")
    layout = Layout(spec.axes, kinds)
    return Plan(spec, file, layout, src, tgt, {k: v for k, v in params.items() if k not in spec.axes},
                layout.grid(), layout.draw(spec.holdout, spec.seed))


def _axis_kind(src: ModelSpec, name: str, ax, params: dict, file: str) -> str:
    field = f"axes.{name}"
    if name not in src.names:
        raise ConfigError(f"model {src.name!r} has no parameter {name!r} (known: {', '.join(src.names)})", file=file,
                          field=field)
    p = src.param(name)
    if p.kind == "choice":
        raise ConfigError(f"{name} is a choice ({', '.join(p.choices)}): an axis is a continuous parameter; give "
                          "the choice in source.params (a table per value)", file=file, field=field)
    if not src.is_active(name, params):
        raise ConfigError(f"{name} does nothing with {', '.join(f'{k}={params[k]}' for k in p.active_when)}",
                          file=file, field=field)
    lo, hi = ax.range
    if lo < p.lower or hi > p.upper:
        raise ConfigError(f"range [{lo:g}, {hi:g}] goes outside {name}'s bounds [{p.lower:g}, {p.upper:g}]",
                          file=file, field=f"{field}.range")
    if p.kind == "scalar" and ax.mode == "channels":
        raise ConfigError("mode channels is for an RGB parameter", file=file, field=f"{field}.mode")
    if p.kind == "rgb" and ax.mode == "scale" and not p.separable:
        raise ConfigError(f"{name}'s channels do not act alone in the image, so a grey sample cannot stand for a "
                          "colour: use mode: channels", file=file, field=f"{field}.mode")
    return p.kind


def _material(p: Plan, values: dict, name: str) -> Material:
    return Material(adapter=p.spec.source.adapter, model=p.spec.source.model,
                    params={**p.spec.source.params, **values}, name=name)


def _task(p: Plan, registry: AdapterRegistry, slot: str, values: dict, title: str, scene, settings,
          lookup: Lookup | None = None) -> Task:
    job = Job(source=_material(p, values, slot), target=p.spec.target, scene=scene, settings=settings,
              label=f"{p.file} {slot}", lookup=lookup)
    where = Where(source_file=p.file, source_prefix="source.", params_prefix=f"{slot} ({_shown(values)})",
                  target_file=p.file, target_prefix="target.", fix_prefix="target.fix")
    return Task(slot, resolve(job, registry, where).job, title)


def _shown(values: dict) -> str:
    return ", ".join(f"{k}=" + ("[" + ",".join(f"{x:.3g}" for x in v) + "]" if isinstance(v, list) else f"{v:.4g}")
                     for k, v in values.items())


def record(point_id: str, values: dict, done: Done, index: tuple[int, ...] = ()) -> PointRecord:
    """What the table keeps of one fit, and whether the map may use it."""
    r = done.report
    if r is None:
        return PointRecord(id=point_id, index=list(index), values=values, params=None, error=None, verdict="failed",
                           reason=done.error, used=False, left_out=f"the fit failed: {done.error}")
    kinds = [f.kind for f in r.findings if f.severity == "unreliable"]
    questioned = [f.message for f in r.findings if f.severity == "unreliable" and f.kind in QUESTIONED]
    return PointRecord(id=point_id, index=list(index), values=values, params=dict(r.params),
                       error=r.metrics.relative_rmse, noise_floor=r.metrics.noise_floor, verdict=r.verdict,
                       reason="" if r.reliable else r.reason, findings=kinds, used=not questioned,
                       left_out="; ".join(questioned), renders=r.renders, seconds=r.seconds, key=r.key)


def _mapped(p: Plan, points: list[PointRecord], done: list[Done]) -> list[str]:
    """The target parameters the fits varied (in the model's order)."""
    fitted = {n for d in done if d.report is not None for n in d.report.fitted}
    return [n for n in p.target_spec.names if n in fitted]


def remedy_points(p: Plan, registry: AdapterRegistry, runner: Runner, scene, points: list[PointRecord]
                  ) -> list[PointRecord]:
    """Each grid point whose fit is in question for a reason with a remedy (`REMEDIES`) fitted again
    with it, stored as `points/<id>/remedy/`; the refit's record replaces the first where its error
    is lower (and says so), whatever its own findings say (they decide whether the map uses it)."""
    tasks, which = [], []
    for i, pt in enumerate(points):
        update = _remedy(pt, p.spec.options)
        if update:
            tasks.append(_task(p, registry, f"points/{pt.id}/remedy", pt.values, f"{pt.id} remedy "
                               + " ".join(f"{k}={v}" for k, v in update.items()), scene,
                               p.spec.options.model_copy(update=update)))
            which.append(i)
    out = list(points)
    for i, d in zip(which, runner.run(tasks)):
        first = points[i]
        if d.report is not None and first.error is not None and d.report.metrics.relative_rmse < first.error:
            out[i] = record(first.id, first.values, d, tuple(first.index)).model_copy(update={
                "remedy": ", ".join(f"{k} {v}" for k, v in _remedy(first, p.spec.options).items()),
                "first_error": first.error})
    return out


def _remedy(pt: PointRecord, options) -> dict:
    """The settings the first remedy among the point's findings changes (none already in effect)."""
    for kind in pt.findings:
        update = {k: v for k, v in REMEDIES.get(kind, {}).items() if getattr(options, k) != v}
        if update and not pt.used:
            return update
    return {}


CONTINUE_SLACK, CONTINUE_NOISE, CONTINUE_SMOOTHING = 1.02, 0.5, 1e-3
"""A refit from the neighbours' map replaces a point's first fit when its error is at most this much
of the first's, plus this much of the render noise (at the noise, two fits are alike); the
neighbours' map is an RBF of this smoothing."""


def continue_points(p: Plan, registry: AdapterRegistry, runner: Runner, draft: Table) -> list[PointRecord]:
    """Each grid point refitted from one start, the map of the other points' fits (continuation: a
    fit that fell into another optimum than its neighbours' is led into theirs, where it is as
    good); the refit replaces the first fit where its error is within `CONTINUE_SLACK` of it (and half
    the render noise).
    Stored as `points/<id>/continued/`."""
    settings = draft.spec.options.model_copy(update={"starts": 1})
    tasks, which = [], []
    for i, pt in enumerate(draft.points):
        if pt.params is None:
            continue
        start = _neighbours_map(draft, i).params(pt.values)[0]
        job = Job(source=_material(p, pt.values, pt.id), target=draft.spec.target, scene=draft.scene,
                  settings=settings, label=f"{p.file} points/{pt.id} continued", start=start)
        tasks.append(Task(f"points/{pt.id}/continued", resolve(job, registry).job, f"{pt.id} continued"))
        which.append(i)
    points = list(draft.points)
    for i, d in zip(which, runner.run(tasks)):
        first, again = points[i], d.report
        if again is not None and first.error is not None and again.metrics.relative_rmse <= (
                CONTINUE_SLACK * first.error + CONTINUE_NOISE * (first.noise_floor or 0.0)):
            points[i] = record(first.id, first.values, d, tuple(first.index)).model_copy(update={
                "continued": True, "first_error": first.first_error or first.error, "remedy": first.remedy})
    return points


def _neighbours_map(draft: Table, i: int) -> TableMap:
    """The map of every used point but the i-th (a thin-plate RBF, lightly smoothed)."""
    others = [pt.model_copy(update={"used": False}) if j == i else pt for j, pt in enumerate(draft.points)]
    hyper = {o.label: CONTINUE_SMOOTHING for o in draft.outputs}
    return TableMap(draft.model_copy(update={"points": others, "candidates": {"rbf": Candidate(
        method="rbf", hyper=hyper, cv_rms={})}}), "rbf")


CLIFF_SPAN, CLIFF_MAD, CLIFF_SHARE = 0.15, 6.0, 0.1
"""A used point is a cliff when a smooth map of its neighbours misses one of its parameters by over
CLIFF_SPAN of the parameter's range and CLIFF_MAD times the points' median miss; at most
CLIFF_SHARE of the points, the worst."""


def leave_out_cliffs(draft: Table) -> list[PointRecord]:
    """The points with the fits that landed in another optimum than their neighbours' (the paper's
    cliffs: a parameter that jumps where the source changes a little) left out of the regression, and
    said: a smooth map cannot follow a jump, and would carry it to every lookup around it."""
    from .maps import cv_predictions

    worst: dict[int, tuple[float, str]] = {}
    for o in draft.outputs:
        if o.kind == "error":
            continue
        grid = grid_of(draft, o)
        try:
            miss = np.abs(cv_predictions("rbf", grid, 1e-3) - grid.y)
        except (ValueError, np.linalg.LinAlgError):
            continue
        seen = grid.used & np.isfinite(miss)
        if not seen.any():
            continue
        mad = float(np.median(miss[seen]))
        for i in np.flatnonzero(seen & (miss > max(CLIFF_SPAN, CLIFF_MAD * mad))):
            if miss[i] > worst.get(int(i), (0.0, ""))[0]:
                worst[int(i)] = (float(miss[i]), o.label)
    cap = int(CLIFF_SHARE * len(draft.points))
    chosen = sorted(worst.items(), key=lambda kv: -kv[1][0])[:cap]
    points = list(draft.points)
    for i, (miss, label) in chosen:
        points[i] = points[i].model_copy(update={"used": False, "left_out": (
            f"a cliff: its {label} is {miss:.0%} of the range off a smooth map of its neighbours' (its fit found "
            "another optimum)")})
    return points


def fit_candidates(draft: Table) -> dict[str, Candidate]:
    """Each kind of map's hyperparameters and cross-validated errors; a kind that cannot be fitted to
    these points says why (and is not chosen)."""
    out = {}
    for method in METHODS:
        hyper, cv = {}, {}
        try:
            for o in draft.outputs:
                grid = grid_of(draft, o)
                h, err = choose_hyperparameter(method, grid)
                build(method, grid, h)  # it must fit all the used points, whatever the folds did
                hyper[o.label], cv[o.label] = h, (err if math.isfinite(err) else None)
        except (ValueError, np.linalg.LinAlgError) as exc:
            out[method] = Candidate(method=method, problem=str(exc).splitlines()[0], hyper={}, cv_rms={})
            continue
        out[method] = Candidate(method=method, hyper=hyper, cv_rms=cv)
        if _shares_channels(draft):  # the same map, the colour read at its mean grey level
            out[f"{method}-mean"] = out[method].model_copy(update={"channels": "mean"})
    return out


def _shares_channels(draft: Table) -> bool:
    """Whether some output is shared by the channels of a grey `scale` axis (a scalar target parameter)."""
    return bool(draft.layout.grey_axes) and any(
        o.kind != "error" and not o.per_channel and o.channel is None for o in draft.outputs)


def build_table(spec: TableSpec, file: str, out: str | Path, registry: AdapterRegistry, workers: Workers, *,
                quiet: bool = False) -> Table:
    t0 = time.perf_counter()
    p = plan(spec, file, registry)
    scene = spec.scene.scene(Path(file).resolve().parent)
    grid_tasks = [_task(p, registry, f"points/g{i:04d}", v, f"g{i:04d} {_shown(v)}", scene, spec.options)
                  for i, (_, v) in enumerate(p.grid)]
    held_tasks = [_task(p, registry, f"holdout/h{i:03d}", v, f"h{i:03d} {_shown(v)}", scene, spec.options)
                  for i, v in enumerate(p.held)]
    with owned(out) as folder:
        runner = Runner(Store(folder), workers, renderer_files=tuple(registry.loaded_files()), quiet=quiet,
                        stop_on_error=False, line=_line)
        done = runner.run(grid_tasks + held_tasks)
        grid_done, held_done = done[:len(grid_tasks)], done[len(grid_tasks):]
        firsts = [record(t.slot.split("/")[1], v, d, idx) for t, (idx, v), d in zip(grid_tasks, p.grid, grid_done)]
        points = remedy_points(p, registry, runner, scene, firsts)
        need = len(p.layout.dims) + 2
        if sum(pt.used for pt in points) < need:
            write_points_csv(folder / "points.csv", _draft(p, file, spec, points, [], [], None, scene))
            raise ConfigError(f"{sum(pt.used for pt in points)} of {len(points)} grid points gave a fit the map can "
                              f"use, and a map over {need - 2} dimensions needs {need}: see points.csv for why",
                              file=file)
        held = [record(t.slot.split("/")[1], v, d) for t, v, d in zip(held_tasks, p.held, held_done)]
        first = next(d.report for d, pt in zip(grid_done, points) if pt.used)
        draft = _draft(p, file, spec, points, held, _mapped(p, points, grid_done), first, scene)
        draft = draft.model_copy(update={"outputs": choose_scales(draft.outputs, lambda o: grid_of(draft, o))})
        if spec.continuation:
            draft = draft.model_copy(update={"points": continue_points(p, registry, runner, draft)})
        draft = draft.model_copy(update={"points": leave_out_cliffs(draft)})
        draft = draft.model_copy(update={"candidates": fit_candidates(draft)})
        if all(c.problem for c in draft.candidates.values()):
            raise ConfigError("no map could be fitted to the grid: " + "; ".join(
                f"{m}: {c.problem}" for m, c in draft.candidates.items()), file=file)
        candidates = _check_holdout(p, registry, runner, draft)
        chosen, why = choose(candidates)
        table = draft.model_copy(update={"candidates": candidates, "chosen": chosen, "chosen_why": why})
        renders, seconds = checks_account(folder, table)
        final = table.points  # after continuation and the cliffs
        refit_renders, refit_seconds = _refits(folder, final)
        table = table.model_copy(update={"build": BuildRecord(
            points=len(final), used=sum(pt.used for pt in final),
            flagged=sum(pt.verdict in ("unreliable", "failed") for pt in final),
            left_out=sum(not pt.used for pt in final), holdout=len(held),
            renders=sum(pt.renders for pt in firsts + held) + renders + refit_renders,
            seconds=sum(pt.seconds for pt in firsts + held) + seconds + refit_seconds,
            wall_seconds=time.perf_counter() - t0, ran_in=workers.where)})
        write_table(folder / "table.json", table)
        write_points_csv(folder / "points.csv", table)
    return table


def _draft(p: Plan, file: str, spec: TableSpec, points, held, names, first, scene) -> Table:
    """The table without its maps' account yet."""
    from .. import __version__

    return Table(schema_version=TABLE_SCHEMA_VERSION, tool=f"brdf-remap {__version__}",
                 name=spec.name or Path(file).stem, spec=spec, scene=scene, source_kinds=p.layout.kinds,
                 source_params=p.source_params,
                 target_params=p.target_spec.complete(first.params if first else {}),
                 versions=first.job.versions if first else {}, outputs=outputs_for(p.target_spec, names,
                                                                                   p.layout.separable),
                 points=points, holdout=held, candidates={}, chosen="", chosen_why="",
                 build=BuildRecord(points=0, used=0, flagged=0, left_out=0, holdout=0, renders=0, seconds=0,
                                   wall_seconds=0, ran_in=""))


def _refits(folder: Path, points: list[PointRecord]) -> tuple[int, float]:
    """Target renders and seconds of the refits stored (remedies and continuation, kept or not)."""
    from ..report import read_report

    renders, seconds = 0, 0.0
    for pt in points:
        for refit in ("remedy", "continued"):
            try:
                r = read_report(folder / "points" / pt.id / refit / "result.json")
            except ConfigError:
                continue
            renders, seconds = renders + r.renders, seconds + r.seconds
    return renders, seconds


def checks_account(folder: Path, table: Table) -> tuple[int, float]:
    """Target renders and seconds of this table's stored lookups (checks/<map>/<held-out id>)."""
    from ..report import read_report

    renders, seconds = 0, 0.0
    for method, c in table.candidates.items():
        for h, err in zip(table.holdout, c.holdout_errors):
            if err is None:
                continue
            try:
                r = read_report(folder / "checks" / method / h.id / "result.json")
            except ConfigError:
                continue
            renders, seconds = renders + r.renders, seconds + r.seconds
    return renders, seconds


def _check_holdout(p: Plan, registry: AdapterRegistry, runner: Runner, draft: Table) -> dict[str, Candidate]:
    """Each candidate map's lookup of each held-out material, rendered and judged (no held-out lights:
    the scene's error is what is compared with the direct fit's)."""
    fitted = [(i, h) for i, h in enumerate(draft.holdout) if h.error is not None]
    if not fitted:
        return draft.candidates
    settings = draft.spec.options.model_copy(update={"validation": "none"})
    tasks, where = [], []
    for method, c in draft.candidates.items():
        if c.problem:
            continue
        tmap = TableMap(draft, method)
        for i, h in fitted:
            params, expected = tmap.params(h.values)
            lookup = Lookup(table=draft.name, digest="draft", method=method, params=params,
                            expected_error=expected)
            tasks.append(_task(p, registry, f"checks/{method}/{h.id}", h.values, f"{method} {h.id}", draft.scene,
                               settings, lookup))
            where.append((method, i))
    results = runner.run(tasks)
    errors: dict[str, list] = {m: [None] * len(draft.holdout) for m in draft.candidates}
    for (method, i), d in zip(where, results):
        errors[method][i] = d.report.metrics.relative_rmse if d.report is not None else None
    out = {}
    for method, c in draft.candidates.items():
        ratios = [e / h.error if e is not None and h.error else None for e, h in zip(errors[method], draft.holdout)]
        r = np.array([x for x in ratios if x is not None], float)
        out[method] = c.model_copy(update={
            "holdout_errors": errors[method], "ratios": ratios,
            "median_ratio": float(np.median(r)) if r.size else None,
            "p95_ratio": float(np.percentile(r, 95)) if r.size else None})
    return out


MEDIAN_TIE = 0.01
"""Maps whose held-out median ratios are within this fraction of the best one's are told apart by
their 95th percentile (a 0.1 % better median is not worth a tail twice as far off)."""


def choose(candidates: dict[str, Candidate]) -> tuple[str, str]:
    """The map whose lookups of the held-out materials come closest to their direct fits (median
    ratio, within `MEDIAN_TIE`; then the 95th percentile); without held-out materials, the least
    cross-validated error."""
    judged = {m: c for m, c in candidates.items() if c.median_ratio is not None and not c.problem}
    if judged:
        lowest = min(c.median_ratio for c in judged.values())
        close = [m for m, c in judged.items() if c.median_ratio <= lowest * (1 + MEDIAN_TIE)]
        best = min(close, key=lambda m: (round(judged[m].p95_ratio, 3), judged[m].median_ratio,
                                         _preference(judged[m])))
        c = judged[best]
        return best, (f"lookups of {sum(r is not None for r in c.ratios)} held-out materials: median "
                      f"{c.median_ratio:.3f}, 95th percentile {c.p95_ratio:.3f} of the direct fit's error")

    def cv(m: str) -> float:
        vals = [v for k, v in candidates[m].cv_rms.items() if k != "error" and v is not None]
        return float(np.mean(vals)) if vals and not candidates[m].problem else math.inf

    best = min(candidates, key=lambda m: (round(cv(m), 4), _preference(candidates[m])))
    return best, f"no held-out materials: least cross-validated error on the grid ({cv(best):.4f} of the range)"


def _preference(c: Candidate) -> tuple[int, int]:
    """Among maps that do equally well: the smoother kind, then the colour read channel by channel."""
    return PREFERENCE.index(c.method), c.channels != "weighted"


def write_points_csv(path: Path, table: Table) -> Path:
    buf = io.StringIO()
    rows = []
    for kind, pts in (("grid", table.points), ("holdout", table.holdout)):
        for pt in pts:
            row = {"kind": kind, "id": pt.id}
            row.update({f"source.{k}": _cell(v) for k, v in pt.values.items()})
            row.update({f"target.{o.param}": _cell((pt.params or {}).get(o.param)) for o in table.outputs
                        if o.kind != "error"})
            row.update({"error": _cell(pt.error), "noise_floor": _cell(pt.noise_floor), "verdict": pt.verdict,
                        "used": pt.used, "left_out": pt.left_out, "reason": pt.reason, "refit": pt.remedy})
            rows.append(row)
    cols: list[str] = []
    for r in rows:
        cols += [c for c in r if c not in cols]
    w = csv.DictWriter(buf, fieldnames=cols)
    w.writeheader()
    w.writerows(rows)
    return write_text_atomic(path, buf.getvalue())


def _cell(v) -> str:
    if v is None:
        return ""
    if isinstance(v, (list, tuple)):
        return " ".join(f"{float(x):.6g}" for x in v)
    return f"{float(v):.6g}" if isinstance(v, (int, float)) else str(v)


def _line(done: Done, i: int, n: int) -> str:
    if done.report is None:
        return f"[{i}/{n}] {done.task.title}: FAILED: {done.error}"
    r = done.report
    return (f"[{i}/{n}] {done.task.title}: {r.metrics.relative_rmse:.2%}, {r.renders} renders, {r.seconds:.1f} s, "
            f"{r.verdict}" + (" [resumed]" if done.resumed else ""))


__all__ = ["build_table", "plan", "choose", "record"]
