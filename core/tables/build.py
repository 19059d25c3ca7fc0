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
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from ..data.atomic import write_text_atomic
from ..data.errors import ConfigError
from ..data.settings import Validation
from ..host.plugins import AdapterRegistry
from ..job.job import Lookup
from ..job.execute import AdapterPool
from ..run.executors import Workers
from ..run.runner import Done, Runner
from ..run.store import Store, owned
from .colours import choose_degree, shared_outputs
from .maps import METHODS, build, choose_hyperparameter
from .outputs import ERROR, Output, OutputKind, choose_scales, outputs_for
from .plan import Plan, fitted_names, plan, point_task, record, shown
from .refits import (continue_points, follow_colours, follow_points, leave_out_cliffs, refits_account,
                     remedy_points)
from .spec import TableSpec
from .table import (
    TABLE_SCHEMA_VERSION,
    BuildRecord,
    Candidate,
    Channels,
    LeftOut,
    PointRecord,
    Table,
    TableMap,
    correction_rows,
    grid_of,
    write_table,
)

PREFERENCE = ("polynomial", "rbf", "multilinear")
"""Order among maps that do equally well: the smoothest first."""


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
            out[f"{method}-mean"] = out[method].model_copy(update={"channels": Channels.MEAN})
    if draft.colours:
        out.update(corrected_candidates(draft, out))
    return out


def corrected_candidates(draft: Table, candidates: dict[str, Candidate]) -> dict[str, Candidate]:
    """Each map with the coloured points' correction (`colours`): for each target colour mapped channel
    by channel, the degree cross-validation chooses, where it gains (`colours.GAIN`). None without a
    parameter the channels share (nothing moves a channel off its own lookup)."""
    if not shared_outputs(draft.outputs):
        return {}
    table = draft.model_copy(update={"candidates": candidates})
    out = {}
    for name, c in candidates.items():
        if c.problem:
            continue
        tmap = TableMap(table, name)
        degrees, cv = {}, {}
        for o in draft.outputs:
            if not o.per_channel:  # a shared parameter is the bright channels' (`Layout.channel_weights`)
                continue
            chosen = choose_degree(correction_rows(table, tmap, o))
            if chosen is not None:
                degree, err, before = chosen
                degrees[o.label], cv[o.label] = degree, [before, err]
        if degrees:
            out[f"{name}+colours"] = c.model_copy(update={"correction": degrees, "correction_cv": cv})
    return out


def _shares_channels(draft: Table) -> bool:
    """Whether some output is shared by the channels of a grey `scale` axis (a scalar target parameter)."""
    return bool(draft.layout.grey_axes) and any(
        o.kind != OutputKind.ERROR and not o.per_channel and o.channel is None for o in draft.outputs)


@dataclass(frozen=True)
class Parts:
    """What the build's stages give, from which `assemble_table` makes the table."""

    points: list[PointRecord]
    holdout: list[PointRecord]
    colours: list[PointRecord]
    outputs: list[Output]
    candidates: dict[str, Candidate] = field(default_factory=dict)
    chosen: str = ""
    chosen_why: str = ""
    build: BuildRecord = field(default_factory=lambda: BuildRecord(
        points=0, used=0, flagged=0, left_out=0, holdout=0, renders=0, seconds=0, wall_seconds=0, ran_in=""))


@dataclass(frozen=True)
class Fits:
    """The build's first fits (grid, held-out, coloured) and the grid's and coloured points' records
    after the remedies and path following."""

    firsts: list[PointRecord]
    points: list[PointRecord]
    held: list[PointRecord]
    first_colours: list[PointRecord]
    colours: list[PointRecord]
    fitted: list[str]
    first: Any


def build_table(spec: TableSpec, file: str, out: str | Path, registry: AdapterRegistry, workers: Workers,
                adapters: AdapterPool, *, quiet: bool = False) -> Table:
    t0 = time.perf_counter()
    p = plan(spec, file, registry)
    scene = spec.scene.scene(Path(file).resolve().parent)
    first = first_tasks(p, registry, scene)  # a job the spec cannot make is said before the folder is taken
    with owned(out) as folder:
        runner = Runner(Store(folder), workers, adapters, quiet=quiet, stop_on_error=False, line=_line)
        fits = fit_points(p, registry, runner, scene, first)

        def draft(parts: Parts) -> Table:
            return assemble_table(p, file, scene, fits.first, parts)

        need = len(p.layout.dims) + 2
        if sum(pt.used for pt in fits.points) < need:
            write_points_csv(folder / "points.csv", draft(Parts(fits.points, [], [], [])))
            raise ConfigError(f"{sum(pt.used for pt in fits.points)} of {len(fits.points)} grid points gave a fit "
                              f"the map can use, and a map over {need - 2} dimensions needs {need}: see points.csv "
                              "for why", file=file)
        parts = refine(p, registry, runner, draft, fits)
        parts = replace(parts, **choose_map(p, registry, runner, draft, parts))
        table = draft(replace(parts, build=account(folder, spec, fits, parts, time.perf_counter() - t0,
                                                   workers.where)))
        write_table(folder / "table.json", table)
        write_points_csv(folder / "points.csv", table)
    return table


def assemble_table(p: Plan, file: str, scene, first, parts: Parts) -> Table:
    """The table, in one place, from its parts (a draft while the parts lack their maps)."""
    from .. import __version__

    return Table(schema_version=TABLE_SCHEMA_VERSION, tool=f"brdf-remap {__version__}",
                 name=p.spec.name or Path(file).stem, spec=p.spec, scene=scene, source_kinds=p.layout.kinds,
                 source_params=p.source_params, target_params=p.target_spec.complete(first.params if first else {}),
                 versions=first.job.versions if first else {}, outputs=parts.outputs, points=parts.points,
                 holdout=parts.holdout, colours=parts.colours, candidates=parts.candidates, chosen=parts.chosen,
                 chosen_why=parts.chosen_why, build=parts.build)


def first_tasks(p: Plan, registry: AdapterRegistry, scene) -> tuple[tuple[list, list], ...]:
    """The ids and fit tasks of the grid points, the held-out materials and the coloured points."""
    return (_tasks(p, registry, scene, "points", "g{:04d}", [v for _, v in p.grid]),
            _tasks(p, registry, scene, "holdout", "h{:03d}", p.held),
            _tasks(p, registry, scene, "colours", "c{:04d}", p.colours))


def fit_points(p: Plan, registry: AdapterRegistry, runner: Runner, scene, first: tuple) -> Fits:
    """Every grid point, held-out material and coloured point fitted (the coloured points after the
    grid's: a rerun resumes the grid first), the grid's and coloured points' remedies, and path
    following along the axes of ``follow``."""
    (grid_ids, grid_tasks), (held_ids, held_tasks), (colour_ids, colour_tasks) = first
    done = runner.run(grid_tasks + held_tasks + colour_tasks)
    n, m = len(grid_tasks), len(grid_tasks) + len(held_tasks)
    grid_done, held_done, colour_done = done[:n], done[n:m], done[m:]
    firsts = [record(k, v, d, idx) for k, (idx, v), d in zip(grid_ids, p.grid, grid_done)]
    points = _refitted(p, registry, runner, scene, firsts)
    first_colours = [record(k, v, d) for k, v, d in zip(colour_ids, p.colours, colour_done)]
    first = (next((d.report for d, pt in zip(grid_done, points) if pt.used and d.report is not None), None)
             or next((d.report for d in grid_done if d.report is not None), None))  # a followed point's may fail
    return Fits(firsts=firsts, points=points, held=[record(k, v, d) for k, v, d in zip(held_ids, p.held, held_done)],
                first_colours=first_colours,
                colours=remedy_points(p, registry, runner, scene, first_colours, "colours"),
                fitted=fitted_names(p, points, grid_done), first=first)


def refine(p: Plan, registry: AdapterRegistry, runner: Runner, draft: Callable[[Parts], Table], fits: Fits) -> Parts:
    """The outputs' scales chosen on the grid, the coloured points followed from the grid's map and
    the grid continued from its neighbours' (where the spec asks), and the cliffs left out."""
    parts = Parts(fits.points, fits.held, fits.colours, outputs_for(p.target_spec, fits.fitted, p.layout.separable))
    unscaled = draft(parts)
    parts = replace(parts, outputs=choose_scales(parts.outputs, lambda o: grid_of(unscaled, o)))
    scaled = draft(parts)
    colours = follow_colours(p, registry, runner, scaled) if p.spec.follow and parts.colours else parts.colours
    points = continue_points(p, registry, runner, scaled) if p.spec.continuation else parts.points
    return replace(parts, points=leave_out_cliffs(draft(replace(parts, points=points, colours=colours))),
                   colours=colours)


def choose_map(p: Plan, registry: AdapterRegistry, runner: Runner, draft: Callable[[Parts], Table],
               parts: Parts) -> dict:
    """Each kind of map fitted to the grid and checked on the held-out materials, and the one
    chosen, with why (`Parts`' fields)."""
    fitted = fit_candidates(draft(parts))
    if all(c.problem for c in fitted.values()):
        raise ConfigError("no map could be fitted to the grid: " + "; ".join(
            f"{m}: {c.problem}" for m, c in fitted.items()), file=p.file)
    candidates = _check_holdout(p, registry, runner, draft(replace(parts, candidates=fitted)))
    chosen, why = choose(candidates)
    return {"candidates": candidates, "chosen": chosen, "chosen_why": why}


def account(folder: Path, spec: TableSpec, fits: Fits, parts: Parts, wall: float, where: str) -> BuildRecord:
    """What the build did and cost: its points, and the renders and seconds of every fit, refit and
    check (resumed ones included, from their stored results)."""
    renders, seconds = checks_account(folder, parts.candidates, parts.holdout)
    refit_renders, refit_seconds = refits_account(folder, parts.points, follow=tuple(spec.follow))
    colour_renders, colour_seconds = refits_account(folder, fits.colours, "colours", follow=tuple(spec.follow))
    firsts = fits.firsts + fits.held + fits.first_colours
    final = parts.points
    return BuildRecord(points=len(final), used=sum(pt.used for pt in final),
                       flagged=sum(pt.verdict.flagged for pt in final), left_out=sum(not pt.used for pt in final),
                       cliffs=sum(pt.left_out_as == LeftOut.CLIFF for pt in final), holdout=len(fits.held),
                       renders=sum(pt.renders for pt in firsts) + renders + refit_renders + colour_renders,
                       seconds=sum(pt.seconds for pt in firsts) + seconds + refit_seconds + colour_seconds,
                       wall_seconds=wall, ran_in=where)


def _tasks(p: Plan, registry: AdapterRegistry, scene, folder: str, ids: str, values: list) -> tuple[list, list]:
    """The points' ids and their fits' tasks, each stored under ``folder``/its id."""
    names = [ids.format(i) for i in range(len(values))]
    return names, [point_task(p, registry, f"{folder}/{k}", v, f"{k} {shown(v)}", scene, p.spec.options)
                   for k, v in zip(names, values)]


def _refitted(p: Plan, registry: AdapterRegistry, runner: Runner, scene, firsts: list) -> list:
    """The grid's fits after the remedies their findings name, then path following along each axis
    of ``follow``."""
    points = remedy_points(p, registry, runner, scene, firsts)
    for axis in p.spec.follow:
        points = follow_points(p, registry, runner, scene, points, axis)
    return points


def checks_account(folder: Path, candidates: dict[str, Candidate], holdout: list[PointRecord]) -> tuple[int, float]:
    """Target renders and seconds of the stored lookups of the held-out materials (checks/<map>/<id>)."""
    from ..job.report import read_report

    renders, seconds = 0, 0.0
    for method, c in candidates.items():
        for h, err in zip(holdout, c.holdout_errors):
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
    settings = draft.spec.options.for_study().model_copy(update={"validation": Validation.NONE})
    tasks, where = [], []
    for method, c in draft.candidates.items():
        if c.problem:
            continue
        tmap = TableMap(draft, method)
        for i, h in fitted:
            params, expected = tmap.params(h.values)
            lookup = Lookup(table=draft.name, digest="draft", method=method, params=params,
                            expected_error=expected)
            tasks.append(point_task(p, registry, f"checks/{method}/{h.id}", h.values, f"{method} {h.id}", draft.scene,
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
        vals = [v for k, v in candidates[m].cv_rms.items() if k != ERROR and v is not None]
        return float(np.mean(vals)) if vals and not candidates[m].problem else math.inf

    best = min(candidates, key=lambda m: (round(cv(m), 4), _preference(candidates[m])))
    return best, f"no held-out materials: least cross-validated error on the grid ({cv(best):.4f} of the range)"


def _preference(c: Candidate) -> tuple[int, bool, bool]:
    """Among maps that do equally well: the smoother kind, then the colour read channel by channel,
    then the map without a correction."""
    return PREFERENCE.index(c.method), c.channels != Channels.WEIGHTED, c.correction is not None


def write_points_csv(path: Path, table: Table) -> Path:
    buf = io.StringIO()
    rows = []
    for kind, pts in (("grid", table.points), ("holdout", table.holdout)):
        for pt in pts:
            row = {"kind": kind, "id": pt.id}
            row.update({f"source.{k}": _cell(v) for k, v in pt.values.items()})
            row.update({f"target.{o.param}": _cell((pt.params or {}).get(o.param)) for o in table.outputs
                        if o.kind != OutputKind.ERROR})
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
