"""Experiments from the paper as runnable files: parameter sweeps and round trips (Figs. 5-10).

A sweep remaps every point of a one-parameter family of source materials (optionally one
curve per value of a second parameter) and records the fitted target parameters; a round
trip then remaps each result back to the source model. Every point is an ordinary remap
written to ``DIR/points/<id>/`` (result.json last), so an interrupted experiment resumes
where it stopped; the CSV, summary and plots are rebuilt from the points at the end.

No renderer knowledge here: derived quantities (a conductor's reflectivity) come from the
adapters' ``derived()``."""

from __future__ import annotations

import csv
import io
import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Literal

import numpy as np
from pydantic import Field, model_validator

from . import interrupt
from .atomic import write_json_atomic, write_text_atomic
from .configio import load_yaml_model
from .errors import ConfigError
from .plugins import AdapterRegistry
from .remap import ENGINE, RemapOptions
from .scene import ProbeScene, load_scene
from .schemas import Material, Value, _Strict


class Range(_Strict):
    start: float
    stop: float
    steps: int = Field(ge=2, description="Number of values, ends included.")

    def values(self) -> list[float]:
        return [float(v) for v in np.linspace(self.start, self.stop, self.steps)]


class Sweep(_Strict):
    param: str = Field(description="Source parameter that varies.")
    values: list[Any] | None = Field(None, description="Explicit values (numbers, RGB lists or choices).")
    range: Range | None = Field(None, description="Evenly spaced numbers instead of values.")

    @model_validator(mode="after")
    def _one(self) -> "Sweep":
        if (self.values is None) == (self.range is None):
            raise ValueError("give exactly one of values or range")
        if self.values is not None and not self.values:
            raise ValueError("values is empty")
        return self

    def all_values(self) -> list[Any]:
        return self.range.values() if self.range is not None else list(self.values or [])


class Groups(_Strict):
    param: str = Field(description="Source parameter held at one value per curve.")
    values: list[Any] = Field(min_length=1)


class SourceSide(_Strict):
    adapter: str
    model: str
    params: dict[str, Any] = Field(default_factory=dict, description="Fixed source parameters.")


class TargetSide(_Strict):
    adapter: str
    model: str
    fix: dict[str, Any] = Field(default_factory=dict, description="Target parameters held fixed.")


class SceneSpec(_Strict):
    file: str | None = Field(None, description="Probe scene YAML (default: the built-in probe).")
    resolution: int | None = None
    spp: int | None = None
    seed: int | None = None


class Options(_Strict):
    scheme: Literal["auto", "one", "two", "three"] = "auto"
    starts: int = Field(4, ge=1)
    coarse: int = Field(32, ge=0, description="Coarse-level resolution (0: off).")
    threshold: float = Field(0.05, gt=0)
    method: Literal["trf", "dogbox"] = "trf"
    jacobian_updates: int | None = Field(
        None, ge=0, description="Broyden updates between rendered Jacobians (0: a rendered one every "
                                "iteration, as the paper; default: the engine's).")
    start: Literal["informed", "defaults"] = Field(
        "informed", description="First start: the exporters' conversion of the source (as `remap`), or the target "
                                "model's defaults (as the paper's fits).")


class PlotSpec(_Strict):
    x: str = Field(description="source.<name>: a source parameter or derived quantity.")
    y: str = Field(description="target.<name> (or back.<name> in a round trip).")
    channels: Literal["mean", "each"] = Field("mean", description="RGB values: their mean, or one point per channel.")
    xlabel: str | None = None
    ylabel: str | None = None
    title: str | None = None


class CliffSpec(_Strict):
    k: float = Field(4.0, gt=1, description="A step larger than k times the median of its neighbours is a cliff.")
    window: int = Field(3, ge=1, description="Neighbouring steps on each side.")
    params: list[str] | None = Field(None, description="Target parameters checked (default: all fitted).")
    min_step: float = Field(0.002, ge=0, description="Steps below this fraction of a parameter's range (of the "
                                                    "error for the error series) never count.")
    error: bool = Field(True, description="Also look for jumps in the relative RMSE.")
    error_min_step: float = Field(0.005, ge=0, description="Error jumps below this (0.005: half a point of "
                                                          "relative RMSE) never count.")


class Experiment(_Strict):
    kind: Literal["sweep", "roundtrip"]
    name: str
    description: str = ""
    figure: str = Field("", description="The paper's figure this reproduces.")
    source: SourceSide
    sweep: Sweep
    groups: Groups | None = None
    target: TargetSide
    back: TargetSide | None = Field(None, description="Round trip: the model to return to (default: the "
                                                      "source's, fitting the swept parameter).")
    compare: str | None = Field(None, description="Round trip: quantity compared, source vs back (default: "
                                                 "the plot's x without its prefix).")
    scene: SceneSpec = SceneSpec()
    options: Options = Options()
    plot: PlotSpec
    cliff: CliffSpec = CliffSpec()

    @model_validator(mode="after")
    def _check(self) -> "Experiment":
        for name, v in (("plot.x", self.plot.x), ("plot.y", self.plot.y)):
            if v.split(".", 1)[0] not in ("source", "target", "back") or "." not in v:
                raise ValueError(f"{name} must look like source.<name>, target.<name> or back.<name>")
        if self.kind == "sweep" and (self.back is not None or self.compare is not None):
            raise ValueError("back and compare belong to kind: roundtrip")
        return self


def load_experiment(path: str | Path) -> Experiment:
    return load_yaml_model(path, Experiment)


# --- points -----------------------------------------------------------------------------------


@dataclass
class Point:
    id: str
    group: Any
    value: Any
    params: dict[str, Any]


@dataclass
class Leg:
    """One remap of a point: what was fitted and how well."""

    params: dict[str, Value]
    derived: dict[str, Value]
    relative_rmse: float
    perceptual: float
    noise_floor: float
    renders: int
    seconds: float
    reliable: bool
    reason: str
    notes: list[str]
    fitted: list[str]
    verdict: str = "ok"
    resumed: bool = False

    @property
    def unstable(self) -> bool:
        """Unreliable for a reason other than a converged model mismatch (trimmed, pinned, ...)."""
        return self.verdict == "unreliable"


@dataclass
class Row:
    point: Point
    source: dict[str, Value]
    forward: Leg
    back: Leg | None = None
    cliff: list[str] = field(default_factory=list)

    @property
    def flagged(self) -> bool:
        """After a cliff, or a leg unreliable for a reason other than a plain model mismatch."""
        return bool(self.cliff) or self.forward.unstable or (self.back is not None and self.back.unstable)

    @property
    def mismatch(self) -> bool:
        """Not flagged, but a leg's error is above the threshold: the closest the target model gets."""
        legs = [self.forward] + ([self.back] if self.back is not None else [])
        return not self.flagged and any(leg.verdict == "mismatch" for leg in legs)

    def why(self) -> str:
        parts = list(self.cliff)
        if not self.forward.reliable:
            parts.append(f"forward: {self.forward.reason}")
        if self.back is not None and not self.back.reliable:
            parts.append(f"back: {self.back.reason}")
        return "; ".join(parts)


def _label(v: Any) -> str:
    if isinstance(v, (list, tuple)):
        return "[" + ",".join(f"{x:g}" for x in v) + "]"
    if isinstance(v, float):
        return f"{v:g}"
    return str(v)


def points_of(exp: Experiment) -> list[Point]:
    groups = exp.groups.values if exp.groups else [None]
    out = []
    for gi, g in enumerate(groups):
        for si, v in enumerate(exp.sweep.all_values()):
            params = dict(exp.source.params)
            if exp.groups:
                params[exp.groups.param] = g
            params[exp.sweep.param] = v
            out.append(Point(f"{gi:02d}-{si:03d}", g, v, params))
    return out


def _jsonable(v: Any) -> Any:
    if isinstance(v, tuple):
        return list(v)
    if isinstance(v, dict):
        return {k: _jsonable(x) for k, x in v.items()}
    return v


def _leg_from_doc(doc: dict, params: dict[str, Value], derived: dict[str, Value]) -> Leg:
    """A finished leg read back; ``params`` are its parameters completed as a fresh leg has them."""
    m = doc["metrics"]
    verdict = doc.get("verdict") or ("ok" if doc["reliable"] else "unreliable")
    return Leg(params, derived, m["relative_rmse"], m["perceptual"], m["noise_floor"], doc["renders"],
               doc["seconds"], doc["reliable"], doc["reason"], doc.get("notes", []), doc["fitted"], verdict,
               resumed=True)


def _matches(doc: dict, source: Material, source_params: dict, target: TargetSide, fixed: dict, scene: ProbeScene,
             options: RemapOptions) -> bool:
    """A finished point is reused only when every input of its remap is unchanged, and the engine too."""
    opts = json.loads(json.dumps({k: getattr(options, k) for k in options.__dataclass_fields__}))
    try:
        return (doc["source"]["adapter"] == source.adapter and doc["source"]["model"] == source.model
                and _jsonable(source_params) == doc["source"]["params"]
                and doc["target"] == {"adapter": target.adapter, "model": target.model}
                and _jsonable(fixed) == doc["fixed"]
                and json.loads(scene.model_dump_json()) == doc["scene"]
                and opts == doc["options"]
                and doc.get("engine") == ENGINE)  # a result of another engine version is redone
    except (KeyError, TypeError):
        return False


# --- cliffs -----------------------------------------------------------------------------------


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


# --- quantities -------------------------------------------------------------------------------


def quantity(row: Row, name: str) -> Value | None:
    side, key = name.split(".", 1)
    if side == "source":
        return row.source.get(key)
    leg = row.forward if side == "target" else row.back
    if leg is None:
        return None
    # Derived first: it is computed from the active parameters (an inactive default may share its name).
    return leg.derived.get(key, leg.params.get(key))


def channels(v: Value | None, mode: str) -> list[float]:
    """Numbers to plot for one value: a scalar once, an RGB value as its mean or per channel."""
    if v is None or isinstance(v, str):
        return []
    if isinstance(v, (tuple, list)):
        return [float(np.mean(v))] if mode == "mean" else [float(c) for c in v]
    return [float(v)]


# --- running ----------------------------------------------------------------------------------


ProgressFn = Callable[[str], None]


@dataclass
class ExperimentResult:
    exp: Experiment
    rows: list[Row]
    cliffs: list[dict[str, Any]]
    fit: dict[str, float] | None
    files: list[Path]
    seconds: float
    resumed: int


def _scene(exp: Experiment, base_dir: Path) -> ProbeScene:
    s = exp.scene
    scene = ProbeScene()
    if s.file:
        path = Path(s.file)
        scene = load_scene(path if path.is_absolute() or path.exists() else base_dir / path)
    overrides = {k: v for k, v in (("resolution", s.resolution), ("spp", s.spp), ("seed", s.seed)) if v is not None}
    return ProbeScene.model_validate({**scene.model_dump(), **overrides}) if overrides else scene


def validate(exp: Experiment, registry: AdapterRegistry, file: str) -> None:
    """Every point, both legs, before any render: a typo in point 37 must not cost 36 remaps."""
    from .session import _model

    src_spec = _model(registry, registry.resolve(exp.source.adapter, file=file), exp.source.model, file,
                      "source.model")
    for name, param in ((exp.sweep.param, "sweep.param"), (exp.groups.param if exp.groups else None, "groups.param")):
        if name is not None and name not in src_spec.names:
            raise ConfigError(f"model {src_spec.name!r} has no parameter {name!r} (known: {', '.join(src_spec.names)})",
                              file=file, field=param)
    for p in points_of(exp):
        src_spec.complete(p.params, file=file, prefix=f"point {p.id} ({exp.sweep.param}={_label(p.value)})")
    sides = [("target", exp.target)] + ([("back", exp.back)] if exp.back else [])
    for label, side in sides:
        spec = _model(registry, registry.resolve(side.adapter, file=file), side.model, file, f"{label}.model")
        spec.complete(side.fix, file=file, prefix=f"{label}.fix")


def _back_side(exp: Experiment) -> TargetSide:
    if exp.back is not None:
        return exp.back
    return TargetSide(adapter=exp.source.adapter, model=exp.source.model,
                      fix={k: v for k, v in exp.source.params.items() if k != exp.sweep.param})


def run_experiment(exp: Experiment, file: str, out: Path, registry: AdapterRegistry,
                   progress: ProgressFn | None = None) -> ExperimentResult:
    from .plots import cliff_figure, roundtrip_plot, sweep_plot
    from .session import open_adapters, prepare, run, write_outputs

    t0 = time.perf_counter()
    base_dir = Path(file).resolve().parent
    validate(exp, registry, file)
    scene = _scene(exp, base_dir)
    o = exp.options
    options = RemapOptions(scheme=o.scheme, starts=o.starts, threshold=o.threshold, method=o.method,
                           coarse_resolution=o.coarse or None, informed_start=o.start == "informed",
                           **({} if o.jacobian_updates is None else {"jacobian_updates": o.jacobian_updates}))
    out.mkdir(parents=True, exist_ok=True)
    write_text_atomic(out / "experiment.json", exp.model_dump_json(indent=2) + "\n")
    points = points_of(exp)
    back_side = _back_side(exp) if exp.kind == "roundtrip" else None
    names = [exp.source.adapter, exp.target.adapter] + ([back_side.adapter] if back_side else [])
    names = [registry.resolve(n, file=file) for n in names]
    rows: list[Row] = []
    resumed = 0
    with open_adapters(registry, names) as adapters:
        tgt_spec = registry.get(names[1]).models[exp.target.model]
        tgt_fixed = tgt_spec.complete(exp.target.fix, file=file, prefix="target.fix")
        tgt_fixed = {k: tgt_fixed[k] for k in exp.target.fix}

        def leg(material: Material, label: str, side: TargetSide, adapter_name: str, fixed: dict, where: Path) -> Leg:
            nonlocal resumed
            spec = registry.get(adapter_name).models[side.model]
            job = prepare(registry, material, label, adapter_name, side.model, scene, fixed, options)
            doc_path = where / "result.json"
            if doc_path.exists():
                try:
                    doc = json.loads(doc_path.read_text())
                except (OSError, ValueError):
                    doc = None
                if doc and _matches(doc, job.source, job.source_spec.active(job.source_params), side, fixed, scene,
                                    options):
                    resumed += 1
                    params = spec.complete(doc["params"])
                    return _leg_from_doc(doc, params, adapters[adapter_name].derived(side.model, params))
            outcome = run(job, registry, adapters)
            write_outputs(outcome, where, adapters[adapter_name])
            interrupt.check()  # the point is complete and kept; the sweep stops
            r = outcome.result
            return Leg(dict(r.params), adapters[adapter_name].derived(side.model, r.params), r.relative_rmse,
                       r.perceptual, outcome.noise_floor, r.renders, r.seconds, r.reliable, r.reason, list(r.notes),
                       list(r.fitted), r.verdict)

        for i, p in enumerate(points):
            interrupt.check()  # a Ctrl-C swallowed inside a render still stops the sweep here
            src_mat = Material(adapter=names[0], model=exp.source.model, params=p.params, name=p.id)
            src_spec = registry.get(names[0]).models[exp.source.model]
            src_params = src_spec.complete(p.params, file=file, prefix=f"point {p.id}")
            source = {**src_spec.active(src_params), **adapters[names[0]].derived(exp.source.model, src_params)}
            where = out / "points" / p.id
            fwd = leg(src_mat, f"{file} point {p.id}", exp.target, names[1], tgt_fixed, where)
            row = Row(p, source, fwd)
            if back_side is not None:
                back_spec = registry.get(names[2]).models[back_side.model]
                back_mat = Material(adapter=names[1], model=exp.target.model, params=_jsonable(fwd.params),
                                    name=f"{p.id} forward")
                fixed = back_spec.complete(back_side.fix, file=file, prefix="back.fix")
                row.back = leg(back_mat, f"{file} point {p.id} (forward result)", back_side, names[2],
                               {k: fixed[k] for k in back_side.fix}, where / "back")
            rows.append(row)
            if progress:
                f = row.forward
                extra = "" if row.back is None else f"; back {row.back.relative_rmse:.2%}"
                progress(f"[{i + 1}/{len(points)}] {p.id} {exp.sweep.param}={_label(p.value)}"
                         + (f" {exp.groups.param}={_label(p.group)}" if exp.groups else "")
                         + f": {f.relative_rmse:.2%}, {f.renders} renders, {f.seconds:.2f} s"
                         + ("" if f.reliable else " (unreliable)") + extra + (" [resumed]" if f.resumed else ""))
        cliffs = detect_cliffs(exp, rows, registry, names)
    fit = roundtrip_fit(exp, rows) if exp.kind == "roundtrip" else None
    files = [write_csv(out / "results.csv", exp, rows)]
    files.append(sweep_plot(out / "sweep", exp, rows))
    if exp.kind == "roundtrip":
        files.append(roundtrip_plot(out / "roundtrip", exp, rows, fit))
    for n, c in enumerate(cliffs):
        files.append(cliff_figure(out / f"cliff-{n + 1}.png", exp, rows[c["before"]], rows[c["after"]], out))
    result = ExperimentResult(exp, rows, cliffs, fit, files, time.perf_counter() - t0, resumed)
    files.append(write_json_atomic(out / "summary.json", summary(result)))
    return result


def _point_name(exp: Experiment, row: Row) -> str:
    extra = f", {exp.groups.param}={_label(row.point.group)}" if exp.groups else ""
    return f"{row.point.id} ({exp.sweep.param}={_label(row.point.value)}{extra})"


def detect_cliffs(exp: Experiment, rows: list[Row], registry: AdapterRegistry, names: list[str]) -> list[dict]:
    """Per curve and per checked parameter (per channel), mark the point after each cliff."""
    spec = registry.get(names[1]).models[exp.target.model]
    found: dict[tuple[int, int], dict] = {}
    checked = exp.cliff.params or (rows[0].forward.fitted if rows else [])
    xs_name = exp.plot.x
    by_group: dict[str, list[int]] = {}
    for i, r in enumerate(rows):
        by_group.setdefault(_label(r.point.group), []).append(i)
    series: list[tuple[str, int, str, float, Callable[[Row], Any]]] = []  # label, channel, scale, span, value
    for pname in checked:
        if pname not in spec.names or spec.param(pname).kind == "choice":
            continue
        ps = spec.param(pname)
        span = (math.log(ps.upper) - math.log(ps.lower)) if ps.scale == "log" else (ps.upper - ps.lower)
        for c in range(ps.size):
            label = pname + ("" if ps.size == 1 else "[" + "rgb"[c] + "]")
            series.append((label, c, ps.scale, span, lambda r, n=pname: r.forward.params.get(n)))
    if exp.cliff.error:
        series.append(("error", 0, "linear", exp.cliff.error_min_step / max(exp.cliff.min_step, 1e-12),
                       lambda r: r.forward.relative_rmse))
    for idx in by_group.values():
        for label, c, scale, span, get in series:
            xv, yv, members, shown = [], [], [], []
            for i in idx:
                x = channels(quantity(rows[i], xs_name), exp.plot.channels)
                y = get(rows[i])
                if not x or y is None:
                    continue
                yc = float(y[c] if isinstance(y, tuple) else y)
                xv.append(x[c] if len(x) > c else x[0])
                yv.append(math.log(max(yc, 1e-12)) if scale == "log" else yc)
                members.append(i)
                shown.append(yc)
            for a, b, ratio in find_cliffs(xv, yv, exp.cliff.k, exp.cliff.window, exp.cliff.min_step * span):
                ia, ib = members[a], members[b]
                va, vb = shown[a], shown[b]
                text = (f"cliff: {label} jumps {va:.3g} -> {vb:.3g} between {_point_name(exp, rows[ia])} and "
                        f"{_point_name(exp, rows[ib])} ({ratio:.1f}x the median neighbouring step)")
                key = (min(ia, ib), max(ia, ib))
                grp = f", {exp.groups.param} {_label(rows[ia].point.group)}" if exp.groups else ""
                short = (f"{label} {va:.3g}→{vb:.3g} ({_label(rows[ia].point.value)}→"
                         f"{_label(rows[ib].point.value)}{grp})")
                if key not in found:
                    found[key] = {"before": ia, "after": ib, "why": [], "short": short}
                    rows[ib].cliff.append(text)
                found[key]["why"].append(text)
    return sorted(found.values(), key=lambda c: (c["before"], c["after"]))


def roundtrip_fit(exp: Experiment, rows: list[Row]) -> dict[str, float]:
    """Least-squares line through (original, recovered) of the unflagged points; slope, intercept, R²."""
    name = exp.compare or exp.plot.x.split(".", 1)[1]
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


def _cells(prefix: str, d: dict[str, Value]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for k, v in d.items():
        if isinstance(v, (tuple, list)):
            out[f"{prefix}{k}"] = f"{float(np.mean(v)):.6g}"
            for c, x in zip("rgb", v):
                out[f"{prefix}{k}_{c}"] = f"{float(x):.6g}"
        elif isinstance(v, float):
            out[f"{prefix}{k}"] = f"{v:.6g}"
        else:
            out[f"{prefix}{k}"] = v
    return out


def _leg_cells(prefix: str, leg: Leg) -> dict[str, Any]:
    d = _cells(prefix, {k: v for k, v in leg.params.items() if k in leg.fitted})
    d.update(_cells(prefix, leg.derived))
    d.update({f"{prefix}relative_rmse": f"{leg.relative_rmse:.5f}", f"{prefix}perceptual": f"{leg.perceptual:.3f}",
              f"{prefix}noise_floor": f"{leg.noise_floor:.5f}", f"{prefix}renders": leg.renders,
              f"{prefix}seconds": f"{leg.seconds:.3f}", f"{prefix}reliable": leg.reliable,
              f"{prefix}verdict": leg.verdict,
              f"{prefix}reason": "" if leg.reliable else leg.reason})
    return d


def write_csv(path: Path, exp: Experiment, rows: list[Row]) -> Path:
    records = []
    for r in rows:
        rec: dict[str, Any] = {"point": r.point.id}
        if exp.groups:
            rec["group"] = _label(r.point.group)
        rec[f"source.{exp.sweep.param}"] = _label(r.point.value)
        rec.update(_cells("source.", {k: v for k, v in r.source.items()
                                      if k not in (exp.sweep.param,) and not isinstance(v, str)}))
        rec.update(_leg_cells("target.", r.forward))
        if r.back is not None:
            rec.update(_leg_cells("back.", r.back))
        rec["cliff"] = bool(r.cliff)
        rec["flagged"] = r.flagged
        rec["mismatch"] = r.mismatch
        rec["why"] = r.why()
        records.append(rec)
    columns: list[str] = []
    for rec in records:
        columns += [c for c in rec if c not in columns]
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=columns)
    w.writeheader()
    for rec in records:
        w.writerow(rec)
    return write_text_atomic(path, buf.getvalue())


def summary(result: ExperimentResult) -> dict[str, Any]:
    rows = result.rows
    legs = [r.forward for r in rows] + [r.back for r in rows if r.back is not None]
    return {
        "name": result.exp.name,
        "figure": result.exp.figure,
        "points": len(rows),
        "flagged": sum(r.flagged for r in rows),
        "unstable": sum(r.forward.unstable or (r.back is not None and r.back.unstable) for r in rows),
        "after_a_cliff": sum(bool(r.cliff) for r in rows),
        "model_mismatch_only": sum(r.mismatch for r in rows),
        "cliffs": [{"before": rows[c["before"]].point.id, "after": rows[c["after"]].point.id, "why": c["why"],
                    "short": c["short"]} for c in result.cliffs],
        "roundtrip_fit_unflagged": result.fit,
        "median_relative_rmse": float(np.median([r.forward.relative_rmse for r in rows])) if rows else None,
        "renders": int(sum(leg.renders for leg in legs if not leg.resumed)),
        "renders_all_points": int(sum(leg.renders for leg in legs)),
        "remap_seconds_all_points": float(sum(leg.seconds for leg in legs)),
        "remaps_resumed": result.resumed,
        "seconds": result.seconds,
        "files": [p.name for p in result.files],
    }
