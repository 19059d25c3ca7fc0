"""The informed start (the exporters' conversion as the fit's first start) against the target's defaults.

    python bench/analytic_start.py

For the 29 Mitsuba → Cycles Principled cases of bench/speed.py: the default (4 starts, the first
the source adapter's neutral reading of the material written into Principled's parameters by
the Cycles adapter: metallic 1 and F0 for metals, the diffuse colour, metallic 0 and Specular IOR
Level for plastics, roughness √α), the same with one start, and the fit from Principled's
defaults (`--start defaults`, the engine before it). Every fit's starts are moved 5 % of each
range inside the bounds (Tuning.start_margin): started on Metallic 1, TRF hardly moves
along it. Prints renders, seconds and the error on the evaluation render (128², 64 spp) per
case and as medians by family, and how many cases each variant made more than 2 % worse than
the default. One untimed remap first."""

from __future__ import annotations

import statistics
import time

import speed
from common import job_for, open_adapters, registry

from brdfremap.core.job.execute import execute
from brdfremap.core.job.job import resolve

VARIANTS = {"default (informed, 4 starts)": {}, "informed, 1 start": {"starts": 1},
            "from the defaults": {"start": "defaults"}}


def main() -> int:
    reg = registry()
    srcs = speed.CONDUCTORS + speed.PLASTICS
    res: dict[str, list[tuple[int, float, float]]] = {k: [] for k in VARIANTS}
    with open_adapters(reg, ["mitsuba", "cycles"]) as ads:
        execute(resolve(job_for(reg, srcs[0], "cycles", "principled"), reg), ads)
        for src in srcs:
            for label, opts in VARIANTS.items():
                job = resolve(job_for(reg, src, "cycles", "principled", **opts), reg)
                t0 = time.perf_counter()
                o = execute(job, ads)
                secs = time.perf_counter() - t0
                err, _ = speed.evaluate(reg, ads, src, "cycles:principled", o.report.params)
                res[label].append((o.report.renders, secs, err))
                print(f"{src.name:28s} {label:30s} {o.report.renders:3d} {secs:5.2f} {err:.2%}", flush=True)
    base = res[next(iter(VARIANTS))]
    families = {"all": range(len(srcs)), "metals": range(len(speed.CONDUCTORS)),
                "plastics": range(len(speed.CONDUCTORS), len(srcs))}
    for label, rows in res.items():
        for fam, idx in families.items():
            sel = [rows[i] for i in idx]
            ref = [base[i] for i in idx]
            worse = sum(r[2] > 1.02 * b[2] for r, b in zip(sel, ref))
            print(f"{label:30s} {fam:8s} median renders {statistics.median(r[0] for r in sel)} "
                  f"(<= 25: {sum(r[0] <= 25 for r in sel)}/{len(sel)}), median s {statistics.median(r[1] for r in sel):.2f}, "
                  f"median error {statistics.median(r[2] for r in sel):.2%}, >2 % worse than default: {worse}/{len(sel)}, "
                  f"error ratio to default {min(r[2] / b[2] for r, b in zip(sel, ref)):.3f}"
                  f"–{max(r[2] / b[2] for r, b in zip(sel, ref)):.3f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
