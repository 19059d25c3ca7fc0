"""Run an experiment: one job per point (and per way back), through the store and the runner.

Every point is an ordinary remap stored in ``DIR/points/<id>/`` (its way back in
``.../<id>/back/``), so an interrupted experiment resumes where it stopped and a changed point
alone is redone; the table, summary and plots are rebuilt from the reports at the end."""

from __future__ import annotations

import json
import re
import time
from pathlib import Path

from ..data.atomic import write_json_atomic, write_text_atomic
from ..data.errors import ConfigError
from ..data.scene import ProbeScene
from ..data.schemas import Material
from ..host.plugins import AdapterRegistry
from ..job.job import Job, Where, model_of, resolve
from ..job.execute import AdapterPool
from ..run.executors import Workers
from ..run.runner import Done, Runner, Task
from ..run.store import Store, owned
from .analysis import Leg, Row, detect_cliffs, roundtrip_fit
from .plots import cliff_figure, roundtrip_plot, sweep_plot
from .spec import Experiment, ExperimentKind, Point, Side, label, points_of
from .table import ExperimentResult, summary, write_csv


def run_experiment(exp: Experiment, file: str, out: str | Path, registry: AdapterRegistry, workers: Workers,
                   adapters: AdapterPool, *, quiet: bool = False) -> ExperimentResult:
    t0 = time.perf_counter()
    scene = exp.scene.scene(Path(file).resolve().parent)
    points = points_of(exp)
    validate(exp, file, registry)
    forward = [_forward_task(exp, file, p, scene, registry) for p in points]  # every point checked first
    if exp.kind is ExperimentKind.ROUNDTRIP:
        back = exp.back_side()
        model_of(registry, back.adapter, back.model, file, "back.").complete(back.fix, file=file, prefix="back.fix")
    with owned(out) as folder:
        _check_outputs(folder, file)
        write_text_atomic(folder / "experiment.json", exp.model_dump_json(indent=2) + "\n")
        runner = Runner(Store(folder / "points"), workers, adapters, quiet=quiet,
                        line=lambda d, i, n: _line(exp, d, i, n))
        fwd = runner.run(forward)
        tgt_spec = registry.get(exp.target.adapter).models[exp.target.model]
        rows = [Row(p, _source_quantities(d), Leg.of(d.report, tgt_spec, d.resumed)) for p, d in zip(points, fwd)]
        if exp.kind is ExperimentKind.ROUNDTRIP:
            _run_back(exp, file, scene, registry, runner, rows)
        cliffs = detect_cliffs(exp, rows, tgt_spec)
        fit = roundtrip_fit(exp, rows) if exp.kind is ExperimentKind.ROUNDTRIP else None
        files = _write_outputs(folder, exp, rows, cliffs, fit)
        result = ExperimentResult(exp, rows, cliffs, fit, files, time.perf_counter() - t0,
                                  sum(leg.resumed for r in rows for leg in r.legs), workers.where)
        files.append(write_json_atomic(folder / "summary.json", summary(result).model_dump(mode="json")))
    return result


def validate(exp: Experiment, file: str, registry: AdapterRegistry) -> None:
    """What no single job can check, before any render: the swept and grouped parameters exist in
    the source model, and what the plot, the comparison and the cliffs read exists."""
    spec = model_of(registry, exp.source.adapter, exp.source.model, file, "source.")
    for name, where in ((exp.sweep.param, "sweep.param"), (exp.groups.param if exp.groups else None, "groups.param")):
        if name is not None and name not in spec.names:
            raise ConfigError(f"model {spec.name!r} has no parameter {name!r} (known: {', '.join(spec.names)})",
                              file=file, field=where)
    target = model_of(registry, exp.target.adapter, exp.target.model, file, "target.")
    sides = {Side.SOURCE: spec, Side.TARGET: target}
    if exp.kind is ExperimentKind.ROUNDTRIP:
        back = exp.back_side()
        sides[Side.BACK] = model_of(registry, back.adapter, back.model, file, "back.")
    for where, q in (("plot.x", exp.plot.x), ("plot.y", exp.plot.y)):
        if q.side not in sides:
            raise ConfigError(f"{q.side}.<name> belongs to a round trip", file=file, field=where)
        _known(sides[q.side], q.name, file, where)
    if exp.kind is ExperimentKind.ROUNDTRIP:
        for side in (Side.SOURCE, Side.BACK):
            _known(sides[side], exp.compared(), file, "compare")
    for name in exp.cliff.params or ():
        if name not in target.names:
            raise ConfigError(f"model {target.name!r} has no parameter {name!r} (known: {', '.join(target.names)})",
                              file=file, field="cliff.params")


def _known(spec, name: str, file: str, where: str) -> None:
    known = [*spec.names, *spec.derived]
    if name not in known:
        raise ConfigError(f"model {spec.name!r} has no parameter or derived quantity {name!r} (known: "
                          f"{', '.join(known)})", file=file, field=where)


def _forward_task(exp: Experiment, file: str, p: Point, scene: ProbeScene, registry: AdapterRegistry) -> Task:
    job = Job(source=Material(adapter=exp.source.adapter, model=exp.source.model, params=p.params, name=p.id),
              target=exp.target, scene=scene, settings=exp.options.for_study(), label=f"{file} point {p.id}",
              fit_same_model=True)
    where = Where(source_file=file, source_prefix="source.",
                  params_prefix=f"point {p.id} ({exp.sweep.param}={label(p.value)})",
                  target_file=file, target_prefix="target.", fix_prefix="target.fix", command_line=False)
    return Task(p.id, resolve(job, registry, where), f"{p.id} {exp.sweep.param}={label(p.value)}")


def _run_back(exp: Experiment, file: str, scene: ProbeScene, registry: AdapterRegistry, runner: Runner,
              rows: list[Row]) -> None:
    back = exp.back_side()
    where = Where(source_file=file, source_prefix="target.", target_file=file, target_prefix="back.",
                  fix_prefix="back.fix", command_line=False)
    tasks = []
    for r in rows:
        fwd = r.forward.report
        job = Job(source=Material(adapter=fwd.target.adapter, model=fwd.target.model, params=fwd.params,
                                  name=f"{r.point.id} forward"),
                  target=back, scene=scene, settings=exp.options.for_study(),
                  label=f"{file} point {r.point.id} (forward result)", fit_same_model=True)
        tasks.append(Task(f"{r.point.id}/back", resolve(job, registry, where), f"{r.point.id} back"))
    spec = registry.get(back.adapter).models[back.model]
    for r, d in zip(rows, runner.run(tasks)):
        r.back = Leg.of(d.report, spec, d.resumed)


def _source_quantities(d: Done) -> dict:
    src = d.report.source
    return {**src.params, **src.derived}


OUTPUTS = ("experiment.json", "results.csv", "summary.json", "sweep.png", "sweep.svg", "roundtrip.png",
           "roundtrip.svg", "points")


def _check_outputs(folder: Path, file: str) -> None:
    """Before the first point: the names the experiment writes must be free to write."""
    for name in OUTPUTS:
        p = folder / name
        if name != "points" and p.is_dir():
            raise ConfigError(f"holds a folder named {name}, where the experiment writes a file: move it",
                              field=f"--out {folder}")
        if name == "points" and p.exists() and not p.is_dir():
            raise ConfigError("holds a file named points, where the experiment keeps its points: move it",
                              field=f"--out {folder}")


def _previous_cliffs(folder: Path) -> set[str]:
    """The cliff figures the previous run listed in its summary (the only ones this run may remove)."""
    try:
        doc = json.loads((folder / "summary.json").read_text(encoding="utf-8"))
        names = doc.get("files", [])  # any version's summary: only its list of files is needed
    except (OSError, ValueError, AttributeError):
        return set()
    return {n for n in names if isinstance(n, str) and re.fullmatch(r"cliff-\d+\.png", n)} if \
        isinstance(names, list) else set()


def _write_outputs(folder: Path, exp: Experiment, rows: list[Row], cliffs: list[dict], fit) -> list[Path]:
    previous = _previous_cliffs(folder)
    files = [write_csv(folder / "results.csv", exp, rows), sweep_plot(folder / "sweep", exp, rows)]
    if exp.kind is ExperimentKind.ROUNDTRIP:
        files.append(roundtrip_plot(folder / "roundtrip", exp, rows, fit))
    for n, c in enumerate(cliffs):
        files.append(cliff_figure(folder / f"cliff-{n + 1}.png", exp, rows[c["before"]], rows[c["after"]], folder))
    for stale in previous - {p.name for p in files}:
        (folder / stale).unlink(missing_ok=True)  # a cliff of an earlier run that this one does not have
    return files


def _line(exp: Experiment, d: Done, i: int, n: int) -> str:
    r = d.report
    return (f"[{i}/{n}] {d.task.title}: {r.metrics.relative_rmse:.2%}, {r.renders} renders, {r.seconds:.2f} s"
            + ("" if r.reliable else " (unreliable)") + (" [resumed]" if d.resumed else "")
            + (f" (redone: {d.redone})" if d.redone else ""))
