"""Refits of a table's grid points, each a remap job stored beside its point: the remedy a fit's
finding names (`remedy_points`), path following along an axis (`follow_points`, carried to the
coloured points by `follow_colours`), continuation from the neighbours' map (`continue_points`),
cliffs left out (`leave_out_cliffs`), and what all refits cost (`refits_account`)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..data.errors import ConfigError
from ..data.findings import FindingKind
from ..data.settings import Scheme
from ..host.plugins import AdapterRegistry
from ..run.runner import Runner
from .plan import Plan, point_task, record
from .table import Candidate, LeftOut, PointRecord, Table, TableMap, grid_of
from .outputs import OutputKind

REMEDIES: dict[FindingKind, dict] = {FindingKind.NOT_AT_MINIMUM: {"scheme": Scheme.THREE}}
"""The refit a grid point's finding names as its remedy (the fit's own advice to a user: a fit that
stopped short of a minimum of the full image is fitted again by scheme three, every parameter on
the full image). The refit replaces the first fit where it ends lower."""


def remedy_points(p: Plan, registry: AdapterRegistry, runner: Runner, scene, points: list[PointRecord],
                  folder: str = "points") -> list[PointRecord]:
    """Each point (grid or coloured) whose fit is in question for a reason with a remedy (`REMEDIES`)
    fitted again with it, stored as `<folder>/<id>/remedy/`; the refit's record replaces the first
    where its error is lower (and says so), whatever its own findings say (they decide whether the
    map uses it)."""
    tasks, which = [], []
    for i, pt in enumerate(points):
        update = _remedy(pt, p.spec.options)
        if update:
            tasks.append(point_task(p, registry, f"{folder}/{pt.id}/remedy", pt.values, f"{pt.id} remedy "
                                    + " ".join(f"{k}={v}" for k, v in update.items()), scene,
                                    p.spec.options.model_copy(update=update)))
            which.append((i, ", ".join(f"{k} {v}" for k, v in update.items())))
    out = list(points)
    for (i, said), d in zip(which, runner.run(tasks)):
        first = points[i]
        if d.report is not None and first.error is not None and d.report.metrics.relative_rmse < first.error:
            out[i] = record(first.id, first.values, d, tuple(first.index)).model_copy(update={
                "remedy": said, "first_error": first.error})
    return out


def _remedy(pt: PointRecord, options) -> dict:
    """The settings the first remedy among the point's findings changes (none already in effect)."""
    for kind in pt.findings:
        update = {k: v for k, v in REMEDIES.get(kind, {}).items() if getattr(options, k) != v}
        if update and not pt.used:
            return update
    return {}


SWEEPS = (("up", 1), ("down", -1))
"""Path following runs up an axis, then back down it (a better family found high up reaches the
points below it too)."""


def refit_folders(follow: list[str] | tuple[str, ...] = ()) -> tuple[str, ...]:
    """The folders a point's refits are stored in, beside it: the remedy, continuation, and with
    path following along the axes ``follow``, each sweep's and the coloured points' refit."""
    return ("remedy", "continued", *(f"{a}-{s}" for a in follow for s, _ in SWEEPS)) + (("followed",) if follow
                                                                                        else ())


def follow_points(p: Plan, registry: AdapterRegistry, runner: Runner, scene, points: list[PointRecord],
                  axis: str) -> list[PointRecord]:
    """Path following along one axis: step by step up the axis, then back down, each grid point
    fitted again from one start, its predecessor's fit (as it stands after its own refit); the refit
    replaces the fit where its error ends lower (`_lower`). Each step's points are fitted together,
    stored as `points/<id>/<axis>-up/` and `-down/`."""
    d = next(i for i, dim in enumerate(p.layout.dims) if dim.axis == axis)
    n = p.spec.axes[axis].count
    settings = p.spec.options.model_copy(update={"starts": 1})
    at = {tuple(pt.index): i for i, pt in enumerate(points)}
    out = list(points)
    for sweep, way in SWEEPS:
        for k in (range(1, n) if way > 0 else range(n - 2, -1, -1)):
            tasks, which = [], []
            for idx, i in at.items():
                before = at.get(idx[:d] + (k - way,) + idx[d + 1:])
                if idx[d] != k or before is None or out[before].params is None:
                    continue
                pt = out[i]
                tasks.append(point_task(p, registry, f"points/{pt.id}/{axis}-{sweep}", pt.values,
                                        f"{pt.id} {axis} {sweep}", scene, settings, start=out[before].params))
                which.append(i)
            for i, done in zip(which, runner.run(tasks)):
                out[i] = _lower(out[i], done)
    return out


def _lower(first: PointRecord, done) -> PointRecord:
    """The refit's record where its error ends lower than the point's fit (or the fit failed), marked
    continued, with the first fit's error; else the fit. A refit in question never replaces a fit the
    map uses. No margin for the noise: where the two are alike, the followed one keeps the family."""
    if done.report is None:
        return first
    again = record(first.id, first.values, done, tuple(first.index))
    if first.error is not None and (again.error >= first.error or (first.used and not again.used)):
        return first
    return again.model_copy(update={"continued": True, "remedy": first.remedy, "first_error":
                                    first.first_error if first.first_error is not None else first.error})


def follow_colours(p: Plan, registry: AdapterRegistry, runner: Runner, draft: Table) -> list[PointRecord]:
    """Each coloured point fitted again from one start, the grid's map at its colour (a lightly
    smoothed RBF of the used grid fits, uncorrected): the path following of the grid carried to the
    coloured points. The refit replaces the fit where it ends lower; stored as
    `colours/<id>/followed/`."""
    start = _smooth_map(draft, draft.points)
    settings = draft.spec.options.model_copy(update={"starts": 1})
    tasks = [point_task(p, registry, f"colours/{pt.id}/followed", pt.values, f"{pt.id} from the grid", draft.scene,
                        settings, start=start.params(pt.values)[0]) for pt in draft.colours]
    return [_lower(pt, done) for pt, done in zip(draft.colours, runner.run(tasks))]


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
        tasks.append(point_task(p, registry, f"points/{pt.id}/continued", pt.values, f"{pt.id} continued",
                                draft.scene, settings, start=start))
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
    return _smooth_map(draft, [pt.model_copy(update={"used": False}) if j == i else pt
                               for j, pt in enumerate(draft.points)])


def _smooth_map(draft: Table, points: list[PointRecord]) -> TableMap:
    """The map of these points' used fits (a thin-plate RBF, lightly smoothed), uncorrected."""
    hyper = {o.label: CONTINUE_SMOOTHING for o in draft.outputs}
    return TableMap(draft.model_copy(update={"points": points, "candidates": {"rbf": Candidate(
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
        if o.kind == OutputKind.ERROR:
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
        points[i] = points[i].model_copy(update={"used": False, "left_out_as": LeftOut.CLIFF, "left_out": (
            f"a cliff: its {label} is {miss:.0%} of the range off a smooth map of its neighbours' (its fit found "
            "another optimum)")})
    return points


def refits_account(folder: Path, points: list[PointRecord], under: str = "points",
                   follow: tuple[str, ...] = ()) -> tuple[int, float]:
    """Target renders and seconds of the refits stored under ``under`` (`refit_folders`: remedies,
    continuation, and path following along the axes ``follow``, kept or not)."""
    from ..job.report import read_report

    renders, seconds = 0, 0.0
    for pt in points:
        for refit in refit_folders(follow):
            try:
                r = read_report(folder / under / pt.id / refit / "result.json")
            except ConfigError:
                continue
            renders, seconds = renders + r.renders, seconds + r.seconds
    return renders, seconds


