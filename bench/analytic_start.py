"""The exporters' conversion as the fit's start, against the default starts (a measurement only).

    python bench/analytic_start.py

The issue's "a good start" speed-up, measured before building it into the product: for the 29
Mitsuba → Cycles Principled cases of bench/speed.py, the fit starts from the α = roughness²
conversion of bench/baselines.py (written into the job's base point, which the engine's first
start is) with 4, 2 or 1 starts, against the default (Principled's defaults plus a spread).
Prints renders, seconds and the error on the evaluation render (128², 64 spp) per case and as
medians, and how many cases each start made more than 2 % worse. One untimed remap first."""

from __future__ import annotations

import dataclasses
import statistics
import time

import baselines
import speed
from common import registry

from brdfremap.core.remap import RemapOptions
from brdfremap.core.scene import ProbeScene
from brdfremap.core.session import open_adapters, prepare, run

VARIANTS = {"default": (False, {}), "analytic first of 4 starts": (True, {}),
            "analytic, 2 starts": (True, {"starts": 2}), "analytic, 1 start": (True, {"starts": 1})}


def main() -> int:
    reg = registry()
    srcs = speed.CONDUCTORS + speed.PLASTICS
    res: dict[str, list[tuple[int, float, float]]] = {k: [] for k in VARIANTS}
    with open_adapters(reg, ["mitsuba", "cycles"]) as ads:
        run(prepare(reg, srcs[0], "warm-up", "cycles", "principled", ProbeScene(), {}, RemapOptions()), reg, ads)
        for src in srcs:
            for label, (analytic, opts) in VARIANTS.items():
                job = prepare(reg, src, src.name, "cycles", "principled", ProbeScene(), {}, RemapOptions(**opts))
                if analytic:
                    conv = baselines.convert(src.model, src.params, "cycles:principled", "squared")
                    job = dataclasses.replace(job, base={**job.base, **{k: v for k, v in conv.items() if k in job.free}})
                t0 = time.perf_counter()
                o = run(job, reg, ads)
                secs = time.perf_counter() - t0
                err, _ = speed.evaluate(reg, ads, src, "cycles:principled", o.result.params)
                res[label].append((o.result.renders, secs, err))
                print(f"{src.name:28s} {label:28s} {o.result.renders:3d} {secs:5.2f} {err:.2%}", flush=True)
    base = res["default"]
    for label, rows in res.items():
        worse = sum(r[2] > 1.02 * b[2] for r, b in zip(rows, base))
        print(f"{label:28s} median renders {statistics.median(r[0] for r in rows)} "
              f"(<= 25: {sum(r[0] <= 25 for r in rows)}/{len(rows)}), median s {statistics.median(r[1] for r in rows):.2f}, "
              f"median error {statistics.median(r[2] for r in rows):.2%}, >2 % worse than default: {worse}/{len(rows)}, "
              f"worst ratio {max(r[2] / b[2] for r, b in zip(rows, base)):.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
