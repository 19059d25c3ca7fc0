"""One Blender worker against two for the finite-difference Jacobians, in one warm process.

    python bench/workers.py [--reps 2]

Remaps a few Mitsuba materials to Cycles Principled alternately with one and with two Cycles
workers (BRDFREMAP_CYCLES_WORKERS) and prints seconds, renders and errors per run and the
ratio of the medians. Results must be identical: only the wall time may differ."""

from __future__ import annotations

import argparse
import time

from common import ROOT, job_for, median, open_adapters, registry

from brdfremap.core.job.execute import execute
from brdfremap.core.job.job import resolve
from brdfremap.core.data.schemas import load_material

MATERIALS = ("gold", "copper", "blue-plastic")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--reps", type=int, default=2)
    args = ap.parse_args()
    reg = registry()
    secs: dict[int, list[float]] = {1: [], 2: []}
    with open_adapters(reg, ["mitsuba", "cycles"]) as adapters:
        cycles = adapters["cycles"]
        cycles.n_workers = 2
        cycles._workers(2)  # both started before any timing
        extra = cycles._extra
        for n in (1, 2):  # warm-up, untimed: Blender's first renders of a material compile its shaders
            cycles.n_workers, cycles._extra = n, (extra if n == 2 else [])
            src = load_material(ROOT / "configs/materials" / "gold.yaml")
            execute(resolve(job_for(reg, src, "cycles", "principled"), reg), adapters)
        print(f"{'material':14s} {'workers':>7s} {'seconds':>8s} {'renders':>8s} {'error':>8s}")
        for _ in range(args.reps):
            for name in MATERIALS:
                results = {}
                for n in (1, 2):
                    cycles.n_workers, cycles._extra = n, (extra if n == 2 else [])
                    src = load_material(ROOT / "configs/materials" / f"{name}.yaml")
                    job = resolve(job_for(reg, src, "cycles", "principled"), reg)
                    t0 = time.perf_counter()
                    o = execute(job, adapters)
                    dt = time.perf_counter() - t0
                    secs[n].append(dt)
                    results[n] = (o.report.params, o.report.renders)
                    print(f"{name:14s} {n:7d} {dt:8.2f} {o.report.renders:8d} {o.report.metrics.relative_rmse:8.2%}", flush=True)
                assert results[1] == results[2], f"{name}: one and two workers disagree"
        cycles._extra = extra
    m1, m2 = median(secs[1]), median(secs[2])
    print(f"median seconds: one worker {m1:.2f}, two workers {m2:.2f}; two are {m1 / m2:.2f}x as fast")


if __name__ == "__main__":
    main()
