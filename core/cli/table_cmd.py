"""`remap table build SPEC.yaml --out TABLE` (a remap table over a model pair), `remap table show
TABLE`, and `remap --table TABLE --source MATERIAL.yaml --out DIR` (an instant remap through one)."""

from __future__ import annotations

import argparse
import sys
import time

from ..data.errors import ConfigError
from . import options
from ..data.schemas import ParamKind

ACTIONS = ("build", "show")


def parser(action: str) -> argparse.ArgumentParser:
    if action == "build":
        p = options.Parser(prog="remap table build", description="Fit a grid of source materials over the axes "
                           "of SPEC.yaml (and a few held-out ones), learn a smooth map from source to target "
                           "parameters, and write TABLE/table.json. An interrupted build resumes.")
        p.add_argument("spec", metavar="SPEC.yaml", help="table spec (see configs/tables/)")
        p.add_argument("--out", required=True, metavar="TABLE", help="output folder (created)")
        options.add_workers(p)
    else:
        p = options.Parser(prog="remap table show", description="What a table holds: its pair, grid, fits and "
                           "how each candidate map did on held-out materials.")
        p.add_argument("table", metavar="TABLE", help="a table's folder or its table.json")
    options.add_common(p)
    return p


def run(argv: list[str]) -> int:
    if not argv or argv[0] not in ACTIONS:
        got = f"got {argv[0]!r}" if argv else "got nothing"
        raise ConfigError(f"expected one of: {', '.join(ACTIONS)} ({got}; e.g. `remap table build SPEC.yaml --out "
                          "DIR`)", field="remap table")
    args = parser(argv[0]).parse_args(argv[1:])
    return build(args) if argv[0] == "build" else show(args)


def build(args: argparse.Namespace) -> int:
    from ..job.execute import adapter_pool
    from ..run.executors import workers
    from ..host.plugins import collect_adapters
    from ..tables import load_table_spec
    from ..tables.build import build_table

    spec = load_table_spec(args.spec)
    registry = collect_adapters()
    with workers(args.jobs, args.scheduler) as w, adapter_pool(registry) as adapters:
        table = build_table(spec, args.spec, args.out, registry, w, adapters, quiet=args.quiet)
    _summary(table)
    print(f"wrote          {args.out}/table.json, {args.out}/points.csv")
    return 0


def show(args: argparse.Namespace) -> int:
    from ..tables import read_table

    _summary(read_table(args.table))
    return 0


def _summary(t) -> None:
    from ..tables.outputs import ERROR, OutputKind
    from ..tables.spec import AxisMode
    from ..tables.table import Channels

    s, b = t.spec, t.build
    axes = " x ".join(f"{n} {a.count}" + (" per channel" if a.mode == AxisMode.CHANNELS and t.source_kinds[n] == ParamKind.RGB
                                            else "")
                      + (f" ({', '.join(f'{v:g}' for v in a.values)})" if a.values is not None else "")
                      for n, a in s.axes.items())
    print(f"table          {t.name}: {s.source.adapter}:{s.source.model} -> {s.target.adapter}:{s.target.model}")
    print(f"grid           {axes} = {b.points} points; mapped: "
          f"{', '.join(dict.fromkeys(o.param for o in t.outputs if o.kind != OutputKind.ERROR))}")
    continued = sum(pt.continued for pt in t.points)
    remedied = sum(bool(pt.remedy) for pt in t.points)
    why = (f"{b.left_out - b.cliffs} whose fit is in question, {b.cliffs} cliffs" if b.cliffs is not None else
           "built before cliffs were counted apart")
    print(f"fits           {b.used} used, {b.flagged} flagged unreliable, {b.left_out} left out of the regression "
          f"({why})"
          + (f"; {remedied} refitted as their findings advised" if remedied else "")
          + (f"; {continued} continued from their neighbours" if t.spec.continuation or t.spec.follow else "")
          + (f" along {', '.join(t.spec.follow)}" if t.spec.follow else ""))
    if t.colours:
        used = sum(pt.used for pt in t.colours)
        took = sum(c.correction is not None for c in t.candidates.values())
        print(f"colours        {len(t.colours)} coloured points fitted, {used} usable, to correct the maps where the "
              "target couples a colour's channels (+colours: a map with that correction; "
              + (f"{took} maps took one)" if took else "no map gained by one)"))
    print(f"cost           {b.renders} target renders, {b.seconds:.0f} s of fits; this build {b.wall_seconds:.1f} s "
          f"in {b.ran_in}")
    print("maps           held-out lookup error / direct fit error; cross-validated error on the grid (a fraction "
          "of each parameter's range)")
    if any(c.channels == Channels.MEAN for c in t.candidates.values()):
        print("               (-mean: a parameter the colour's channels share read at its mean grey level; the others "
              "read it at each channel's and weigh them by the channel's value squared)")
    for m, c in t.candidates.items():
        if c.problem:
            print(f"    {m:<24} cannot be fitted here: {c.problem}")
            continue
        held = (f"median {c.median_ratio:.3f}, 95th percentile {c.p95_ratio:.3f}" if c.median_ratio is not None
                else "no held-out lookups")
        cv = ", ".join(f"{k} " + ("–" if v is None else f"{v:.3f}") for k, v in c.cv_rms.items() if k != ERROR)
        if c.correction_cv:
            cv += "; coloured points' mean miss " + ", ".join(f"{k} {before:.3f}->{after:.3f}" for k, (before, after)
                                                           in c.correction_cv.items())
        mark = "*" if m == t.chosen else " "
        print(f"  {mark} {m:<24} {held}; {cv}")
    print(f"chosen         {t.chosen}: {t.chosen_why}")


def lookup(args: argparse.Namespace) -> int:
    """`remap --table T --source M --out DIR`: the target's parameters from the table's map; rendered
    and judged as a fit is (or not at all with --no-render)."""
    from ..job.execute import adapter_pool
    from ..run.executors import workers
    from ..run.runner import Runner, Task
    from ..run.store import Store, owned
    from ..tables.lookup import write_answer
    from .progress import RenderProgress
    from .show import print_report

    resolved, answer, header, registry = _lookup_job(args)
    if args.no_render:
        with owned(args.out) as folder, adapter_pool(registry) as adapters:
            files = write_answer(folder, resolved, answer, adapters[resolved.job.target.adapter], str(args.table))
        if not args.quiet:
            print(header, file=sys.stderr)
        _print_answer(resolved, answer, folder, files)
        return 0
    with owned(args.out) as folder, workers() as w, adapter_pool(registry) as adapters:
        runner = Runner(Store(folder), w, adapters, quiet=True, render_progress=RenderProgress(not args.quiet, header),
                        reuse=not args.force)
        (done,) = runner.run([Task("", resolved, str(args.source))])
    print_report(done.report, folder, resumed=done.resumed)
    return 0


def _lookup_job(args: argparse.Namespace):
    """The lookup as a job, checked: (resolved job, answer, progress header, registry)."""
    from ..job.job import Job, Where, model_of, resolve
    from ..host.plugins import collect_adapters
    from ..data.schemas import load_material
    from ..tables import TableMap, read_table
    from ..tables.lookup import axis_values, look_up
    from ..tables.texels import mean_values, read_inputs
    from ..textured import texture_result

    t0 = time.perf_counter()
    if args.fix:
        raise ConfigError("goes with a fit; a table's lookup holds what its spec's target.fix held (build another "
                          "table to hold more)", field="--fix")
    table = read_table(args.table)
    source = load_material(args.source)
    registry = collect_adapters()
    tgt = table.spec.target
    for flag, given, want in (("--adapter", args.adapter, tgt.adapter), ("--model", args.model, tgt.model)):
        if given is not None and given != want:
            raise ConfigError(f"the table maps to {tgt.adapter}:{tgt.model}; leave it out or give {want}", field=flag)
    src_spec = model_of(registry, source.adapter, source.model, str(args.source), "")
    values = axis_values(table, source, src_spec, str(args.source))
    if source.textures:  # the uniform material that stands for it: its textures' mean
        values = mean_values(read_inputs(table, source, src_spec, str(args.source)))
        source = source.model_copy(update={"params": {**source.params, **values}})
    tmap = TableMap(table)
    loaded = time.perf_counter() - t0
    answer = look_up(table, tmap, values)
    answer.lookup = answer.lookup.model_copy(update={"file": str(_table_file(args.table))})
    job = Job(source=source, target=tgt, scene=options.scene_from(args, table.scene),
              settings=options.settings_from(args, table.spec.options), label=str(args.source), lookup=answer.lookup)
    resolved = resolve(job, registry, Where(source_file=str(args.source)), textured=texture_result)
    header = (f"remap {source.adapter}:{source.model} -> {tgt.adapter}:{tgt.model} through the table {table.name!r} "
              f"({tmap.method} map): looked up in {answer.seconds * 1e3:.3f} ms (the table read in "
              f"{loaded * 1e3:.0f} ms)")
    return resolved, answer, header, registry


def _table_file(table_arg: str):
    from ..tables.table import table_file

    return table_file(table_arg).resolve()


def _print_answer(resolved, answer, folder, files) -> None:
    from .show import format_params

    lk = answer.lookup
    spec = resolved.target_spec
    rows = [("params", format_params(spec.active(resolved.base))),
            ("expected", f"direct fits about these source values reach about {lk.expected_error:.2%} (the "
                         "table's grid); not rendered (--no-render)"),
            *([("outside", "; ".join(lk.outside) + ": clamped")] if lk.outside else []),
            ("lookup", f"{answer.seconds * 1e3:.3f} ms"),
            ("wrote", f"{folder}/ ({', '.join(p.name for p in files)})")]
    width = max(len(k) for k, _ in rows)
    for k, v in rows:
        print(f"{k:<{width}}  {v}")
