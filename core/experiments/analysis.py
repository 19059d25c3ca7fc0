"""What an experiment's results say: rows of legs read from reports, cliffs, the round-trip line."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from ..data.schemas import ModelSpec, ParamKind, Scale, Value
from ..job.report import Report
from .spec import Experiment, PlotChannels, Point, Side, SideParam, label
from ..data.findings import Status


@dataclass
class Leg:
    """One remap of a point, as its report tells it; ``params`` completed with the model's defaults."""

    report: Report
    params: dict[str, Value]
    resumed: bool = False

    @classmethod
    def of(cls, report: Report, spec: ModelSpec, resumed: bool) -> "Leg":
        return cls(report, spec.complete(report.params), resumed)

    @property
    def derived(self) -> dict[str, Value]:
        return {k: tuple(v) if isinstance(v, list) else v for k, v in self.report.derived.items()}

    @property
    def relative_rmse(self) -> float:
        return self.report.metrics.relative_rmse

    @property
    def reliable(self) -> bool:
        return self.report.reliable

    @property
    def verdict(self) -> str:
        return self.report.verdict

    @property
    def unstable(self) -> bool:
        """Unreliable for a reason other than a converged model mismatch (trimmed, pinned, ...)."""
        return self.verdict == Status.UNRELIABLE


@dataclass
class Row:
    point: Point
    source: dict[str, Value]
    forward: Leg
    back: Leg | None = None
    cliff: list[str] = field(default_factory=list)

    @property
    def legs(self) -> list[Leg]:
        return [self.forward] + ([self.back] if self.back is not None else [])

    @property
    def flagged(self) -> bool:
        """After a cliff, or a leg unreliable for a reason other than a plain model mismatch."""
        return bool(self.cliff) or any(leg.unstable for leg in self.legs)

    @property
    def mismatch(self) -> bool:
        """Not flagged, but a leg's error is above the threshold: the closest the target model gets."""
        return not self.flagged and any(leg.verdict == Status.MISMATCH for leg in self.legs)

    def why(self) -> str:
        parts = list(self.cliff)
        if not self.forward.reliable:
            parts.append(f"forward: {self.forward.report.reason}")
        if self.back is not None and not self.back.reliable:
            parts.append(f"back: {self.back.report.reason}")
        return "; ".join(parts)


def point_name(exp: Experiment, row: Row) -> str:
    extra = f", {exp.groups.param}={label(row.point.group)}" if exp.groups else ""
    return f"{row.point.id} ({exp.sweep.param}={label(row.point.value)}{extra})"


def find_cliffs(x: list[float], y: list[float], k: float, window: int, min_step: float) -> list[tuple[int, int, float]]:
    """Steps of y (ordered by x) larger than k times what the neighbouring steps lead one to expect.

    On evenly spaced x that is k times the median of the neighbouring steps (up to ``window``
    on each side). Where x is uneven (a sweep over named materials), each step is compared
    with the neighbours' median slope times its own width in x, so a gap between clusters
    of materials is not a cliff. Returns (index before, index after, ratio) with indices
    into the given lists. ``min_step`` is an absolute floor: no step below it is a cliff,
    and an expectation below it counts as it (a flat run does not make noise a cliff).
    A lone outlier (a jump and an opposite jump straight back) is one cliff, reported as
    (its neighbour, the outlier)."""
    if len(x) < 4:
        return []
    xs_all = np.asarray(x, dtype=float)
    order = np.argsort(xs_all, kind="stable")
    xs, ys = xs_all[order], np.asarray(y, dtype=float)[order]
    diffs = np.diff(ys)
    steps = np.abs(diffs)
    dx = np.diff(xs)
    tiny = 1e-9 * max(float(np.ptp(xs)), 1e-30)
    slopes = np.where(dx > tiny, steps / np.maximum(dx, tiny), np.nan)
    big = []
    for j, s in enumerate(steps):
        if s <= min_step:
            continue
        near = np.concatenate([slopes[max(0, j - window):j], slopes[j + 1:j + 1 + window]])
        near = near[np.isfinite(near)]
        if near.size < 2:
            continue  # one neighbour cannot say what is usual: two unequal steps are not a cliff
        expected = max(float(np.median(near)) * float(dx[j]), min_step)
        if s > k * expected:
            big.append((j, float(s / expected)))
    out, skip = [], set()
    for n, (j, ratio) in enumerate(big):
        if j in skip:
            continue
        nxt = big[n + 1] if n + 1 < len(big) else None
        if nxt and nxt[0] == j + 1 and np.sign(diffs[j]) != np.sign(diffs[j + 1]):
            skip.add(j + 1)  # out and straight back: the middle point is the outlier
            ratio = max(ratio, nxt[1])
        out.append((int(order[j]), int(order[j + 1]), ratio))
    return out


def quantity(row: Row, q: SideParam) -> Value | None:
    key = q.name
    if q.side is Side.SOURCE:
        return row.source.get(key)
    leg = row.forward if q.side is Side.TARGET else row.back
    if leg is None:
        return None
    # Derived first: it is computed from the active parameters (an inactive default may share its name).
    return leg.derived.get(key, leg.params.get(key))


def channels(v: Value | None, mode: PlotChannels) -> list[float]:
    """Numbers to plot for one value: a scalar once, an RGB value as its mean or per channel."""
    if v is None or isinstance(v, str):
        return []
    if isinstance(v, (tuple, list)):
        return [float(np.mean(v))] if mode == PlotChannels.MEAN else [float(c) for c in v]
    return [float(v)]


Series = tuple[str, int, str, float, Callable[[Row], Any]]
"""A checked quantity: its name, channel, scale, span (the floor's unit) and how to read it from a row."""


def detect_cliffs(exp: Experiment, rows: list[Row], spec: ModelSpec) -> list[dict]:
    """Per curve and per checked parameter (per channel) of the target ``spec``, mark the point
    after each cliff."""
    found: dict[tuple[int, int], dict] = {}
    by_group: dict[str, list[int]] = {}
    for i, r in enumerate(rows):
        by_group.setdefault(label(r.point.group), []).append(i)
    for idx in by_group.values():
        for series in _series(exp, spec, rows):
            for ia, ib, text, short in _cliffs_of(exp, rows, idx, series):
                key = (min(ia, ib), max(ia, ib))
                if key not in found:
                    found[key] = {"before": ia, "after": ib, "why": [], "short": short}
                    rows[ib].cliff.append(text)
                found[key]["why"].append(text)
    return sorted(found.values(), key=lambda c: (c["before"], c["after"]))


def _series(exp: Experiment, spec: ModelSpec, rows: list[Row]) -> list[Series]:
    checked = exp.cliff.params or (rows[0].forward.report.fitted if rows else [])
    out: list[Series] = []
    for pname in checked:
        if pname not in spec.names or spec.param(pname).kind == ParamKind.CHOICE:
            continue
        ps = spec.param(pname)
        span = (math.log(ps.upper) - math.log(ps.lower)) if ps.scale == Scale.LOG else (ps.upper - ps.lower)
        for c in range(ps.size):
            name = pname + ("" if ps.size == 1 else "[" + "rgb"[c] + "]")
            out.append((name, c, ps.scale, span, lambda r, n=pname: r.forward.params.get(n)))
    if exp.cliff.error:
        out.append(("error", 0, "linear", exp.cliff.error_min_step / max(exp.cliff.min_step, 1e-12),
                    lambda r: r.forward.relative_rmse))
    return out


def _cliffs_of(exp: Experiment, rows: list[Row], idx: list[int], series: Series):
    """(row before, row after, sentence, short form) for each cliff of one series along one curve."""
    name, c, scale, span, get = series
    xv, yv, members, shown = [], [], [], []
    for i in idx:
        x = channels(quantity(rows[i], exp.plot.x), exp.plot.channels)
        y = get(rows[i])
        if not x or y is None:
            continue
        yc = float(y[c] if isinstance(y, tuple) else y)
        xv.append(x[c] if len(x) > c else x[0])
        yv.append(math.log(max(yc, 1e-12)) if scale == Scale.LOG else yc)
        members.append(i)
        shown.append(yc)
    out = []
    for a, b, ratio in find_cliffs(xv, yv, exp.cliff.k, exp.cliff.window, exp.cliff.min_step * span):
        ia, ib, va, vb = members[a], members[b], shown[a], shown[b]
        text = (f"cliff: {name} jumps {va:.3g} -> {vb:.3g} between {point_name(exp, rows[ia])} and "
                f"{point_name(exp, rows[ib])} ({ratio:.1f}x the median neighbouring step)")
        grp = f", {exp.groups.param} {label(rows[ia].point.group)}" if exp.groups else ""
        short = f"{name} {va:.3g}→{vb:.3g} ({label(rows[ia].point.value)}→{label(rows[ib].point.value)}{grp})"
        out.append((ia, ib, text, short))
    return out


def roundtrip_fit(exp: Experiment, rows: list[Row]) -> dict[str, float]:
    """Least-squares line through (original, recovered) of the unflagged points; slope, intercept, R²."""
    name = exp.compared()
    xs, ys = [], []
    for r in rows:
        if r.flagged or r.back is None:
            continue
        a = channels(r.source.get(name), exp.plot.channels)
        b = channels(r.back.derived.get(name, r.back.params.get(name)), exp.plot.channels)
        xs += a[:len(b)]
        ys += b[:len(a)]
    if len(xs) < 2 or np.ptp(xs) == 0:
        return {"points": len(xs), "slope": float("nan"), "intercept": float("nan"), "r2": float("nan"),
                "rms_from_unit_line": float("nan")}
    x, y = np.asarray(xs), np.asarray(ys)
    slope, intercept = np.polyfit(x, y, 1)
    pred = slope * x + intercept
    ss_tot = float(np.sum((y - y.mean()) ** 2))
    r2 = 1.0 - float(np.sum((y - pred) ** 2)) / ss_tot if ss_tot > 0 else float("nan")
    return {"points": int(x.size), "slope": float(slope), "intercept": float(intercept), "r2": r2,
            "rms_from_unit_line": float(np.sqrt(np.mean((y - x) ** 2)))}
