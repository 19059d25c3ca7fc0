"""`remap sweep|roundtrip EXPERIMENT.yaml --out DIR`: the paper's analyses through the runner."""

from __future__ import annotations

import argparse

import numpy as np

from ..data.errors import ConfigError
from . import options

WHAT = {"sweep": "Sweep one source parameter, remap every point, and write a CSV, plots and the cliffs found.",
        "roundtrip": "Remap every point of a sweep to the target and back; plot recovered against original."}


def parser(kind: str) -> argparse.ArgumentParser:
    p = options.Parser(prog=f"remap {kind}", description=WHAT[kind] + " An interrupted run resumes: "
                                "finished points in DIR are reused when their inputs are unchanged.")
    p.add_argument("experiment", metavar="EXPERIMENT.yaml", help="experiment file (see configs/experiments/)")
    p.add_argument("--out", required=True, metavar="DIR", help="output folder (created)")
    options.add_workers(p)
    options.add_common(p)
    return p


def run(kind: str, args: argparse.Namespace) -> int:
    from ..job.execute import adapter_pool
    from ..run.executors import workers
    from ..experiments import load_experiment, run_experiment
    from ..host.plugins import collect_adapters

    exp = load_experiment(args.experiment)
    if exp.kind != kind:
        raise ConfigError(f"is a {exp.kind} experiment: run it with `remap {exp.kind}`", file=args.experiment,
                          field="kind")
    registry = collect_adapters()
    with workers(args.jobs, args.scheduler) as w, adapter_pool(registry) as adapters:
        r = run_experiment(exp, args.experiment, args.out, registry, w, adapters, quiet=args.quiet)
    _print(r, args.out)
    return 0


def _print(r, out) -> None:
    exp, rows = r.exp, r.rows
    print(f"experiment     {exp.name}" + (f"  ({exp.figure})" if exp.figure else ""))
    print(f"points         {len(rows)}  ({r.resumed} remaps resumed from {out}/points)")
    print(f"flagged        {sum(x.flagged for x in rows)}  (unreliable "
          f"{sum(any(leg.unstable for leg in x.legs) for x in rows)}, "
          f"after a cliff {sum(bool(x.cliff) for x in rows)}); above the error threshold by model mismatch "
          f"alone: {sum(x.mismatch for x in rows)}")
    print(f"cliffs         {len(r.cliffs)}")
    for c in r.cliffs:
        print(f"  {c['why'][0]}")
    if r.fit:
        f = r.fit
        print(f"round trip     slope {f['slope']:.4f}, intercept {f['intercept']:.4f}, R² {f['r2']:.5f}, "
              f"RMS from unit line {f['rms_from_unit_line']:.4f} over {f['points']} unflagged values")
    print(f"median error   {np.median([x.forward.relative_rmse for x in rows]):.2%} (forward)")
    print(f"renders        {sum(leg.report.renders for leg in r.legs if not leg.resumed)} target renders this run")
    print(f"seconds        {r.seconds:.1f}  (in {r.where})")
    print(f"wrote          {out}/ ({', '.join(p.name for p in r.files)})")
