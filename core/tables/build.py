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
from pathlib import Path

import numpy as np

from ..data.atomic import write_text_atomic
from ..data.errors import ConfigError
from ..host.plugins import AdapterRegistry
from ..job.job import Lookup
from ..run.executors import Workers
from ..run.runner import Done, Runner
from ..run.store import Store, owned
from .colours import choose_degree, shared_outputs
from .maps import METHODS, build, choose_hyperparameter
from .outputs import choose_scales, outputs_for
from .plan import Plan, fitted_names, plan, point_task, record, shown
from .refits import (continue_points, follow_colours, follow_points, leave_out_cliffs, refits_account,
                     remedy_points)
from .spec import TableSpec
from .table import (
    TABLE_SCHEMA_VERSION,
    BuildRecord,
    Candidate,
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
            out[f"{method}-mean"] = out[method].model_copy(update={"channels": "mean"})
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
        o.kind != "error" and not o.per_channel and o.channel is None for o in draft.outputs)


def build_table(spec: TableSpec, file: str, out: str | Path, registry: AdapterRegistry, workers: Workers, *,
                quiet: bool = False) -> Table:
    t0 = time.perf_counter()
    p = plan(spec, file, registry)
    scene = spec.scene.scene(Path(file).resolve().parent)
    grid_ids, grid_tasks = _tasks(p, registry, scene, "points", "g{:04d}", [v for _, v in p.grid])
    held_ids, held_tasks = _tasks(p, registry, scene, "holdout", "h{:03d}", p.held)
    # The coloured points' fits after the grid's: a rerun resumes the grid first.
    colour_ids, colour_tasks = _tasks(p, registry, scene, "colours", "c{:04d}", p.colours)
    with owned(out) as folder:
        runner = Runner(Store(folder), workers, renderer_files=tuple(registry.loaded_files()), quiet=quiet,
                        stop_on_error=False, line=_line)
        done = runner.run(grid_tasks + held_tasks + colour_tasks)
        n, m = len(grid_tasks), len(grid_tasks) + len(held_tasks)
        grid_done, held_done, colour_done = done[:n], done[n:m], done[m:]
        firsts = [record(k, v, d, idx) for k, (idx, v), d in zip(grid_ids, p.grid, grid_done)]
        points = _refitted(p, registry, runner, scene, firsts)
        first_colours = [record(k, v, d) for k, v, d in zip(colour_ids, p.colours, colour_done)]
        colours = remedy_points(p, registry, runner, scene, first_colours, "colours")
        need = len(p.layout.dims) + 2
        if sum(pt.used for pt in points) < need:
            write_points_csv(folder / "points.csv", _draft(p, file, spec, points, [], [], None, scene))
            raise ConfigError(f"{sum(pt.used for pt in points)} of {len(points)} grid points gave a fit the map can "
                              f"use, and a map over {need - 2} dimensions needs {need}: see points.csv for why",
                              file=file)
        held = [record(k, v, d) for k, v, d in zip(held_ids, p.held, held_done)]
        first = (next((d.report for d, pt in zip(grid_done, points) if pt.used and d.report is not None), None)
                 or next(d.report for d in grid_done if d.report is not None))  # a followed point's may have failed
        draft = _draft(p, file, spec, points, held, fitted_names(p, points, grid_done), first, scene
                       ).model_copy(update={"colours": colours})
        draft = draft.model_copy(update={"outputs": choose_scales(draft.outputs, lambda o: grid_of(draft, o))})
        if spec.follow and draft.colours:
            draft = draft.model_copy(update={"colours": follow_colours(p, registry, runner, draft)})
        if spec.continuation:
            draft = draft.model_copy(update={"points": continue_points(p, registry, runner, draft)})
        kept = leave_out_cliffs(draft)
        cliffs = sum(a.used and not b.used for a, b in zip(draft.points, kept))
        draft = draft.model_copy(update={"points": kept})
        draft = draft.model_copy(update={"candidates": fit_candidates(draft)})
        if all(c.problem for c in draft.candidates.values()):
            raise ConfigError("no map could be fitted to the grid: " + "; ".join(
                f"{m}: {c.problem}" for m, c in draft.candidates.items()), file=file)
        candidates = _check_holdout(p, registry, runner, draft)
        chosen, why = choose(candidates)
        table = draft.model_copy(update={"candidates": candidates, "chosen": chosen, "chosen_why": why})
        renders, seconds = checks_account(folder, table)
        final = table.points  # after continuation and the cliffs
        refit_renders, refit_seconds = refits_account(folder, final, follow=tuple(spec.follow))
        colour_renders, colour_seconds = refits_account(folder, colours, "colours", follow=tuple(spec.follow))
        table = table.model_copy(update={"build": BuildRecord(
            points=len(final), used=sum(pt.used for pt in final),
            flagged=sum(pt.verdict.flagged for pt in final),
            left_out=sum(not pt.used for pt in final), cliffs=cliffs, holdout=len(held),
            renders=sum(pt.renders for pt in firsts + held + first_colours) + renders + refit_renders + colour_renders,
            seconds=sum(pt.seconds for pt in firsts + held + first_colours) + seconds + refit_seconds + colour_seconds,
            wall_seconds=time.perf_counter() - t0, ran_in=workers.where)})
        write_table(folder / "table.json", table)
        write_points_csv(folder / "points.csv", table)
    return table


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


def checks_account(folder: Path, table: Table) -> tuple[int, float]:
    """Target renders and seconds of this table's stored lookups (checks/<map>/<held-out id>)."""
    from ..job.report import read_report

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
    settings = draft.spec.options.for_study().model_copy(update={"validation": "none"})
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
        vals = [v for k, v in candidates[m].cv_rms.items() if k != "error" and v is not None]
        return float(np.mean(vals)) if vals and not candidates[m].problem else math.inf

    best = min(candidates, key=lambda m: (round(cv(m), 4), _preference(candidates[m])))
    return best, f"no held-out materials: least cross-validated error on the grid ({cv(best):.4f} of the range)"


def _preference(c: Candidate) -> tuple[int, bool, bool]:
    """Among maps that do equally well: the smoother kind, then the colour read channel by channel,
    then the map without a correction."""
    return PREFERENCE.index(c.method), c.channels != "weighted", c.correction is not None


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
