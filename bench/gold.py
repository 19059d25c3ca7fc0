"""The README's single remap, Mitsuba gold -> Cycles Principled, against a paper-like fit, in one run.

    python bench/gold.py [--reps 3]

In one warm process (renderers started once, an untimed remap first): the paper-faithful
baseline of bench/speed.py (one-stage TRF at 512² from the target's defaults, a rendered
Jacobian every iteration) once, and brdf-remap's default (`remap --adapter cycles --model
principled --source configs/materials/gold.yaml`: fit, held-out validation, files in memory)
--reps times. Both are scored on one evaluation render (128², 64 spp). Prints each run's
renders, seconds and error, the default's account by purpose, and the ratio of the paper's
seconds to the default's median."""

from __future__ import annotations

import argparse
import statistics
import sys

from common import ROOT, open_adapters, registry, remap_once
from speed import evaluate, run_case

from brdfremap.core.data.schemas import load_material

TARGET = "cycles:principled"


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--reps", type=int, default=3)
    args = ap.parse_args()
    reg = registry()
    gold = load_material(ROOT / "configs" / "materials" / "gold.yaml")
    with open_adapters(reg, ["mitsuba", "cycles"]) as adapters:
        remap_once(reg, adapters, gold, "cycles", "principled")  # warm: kernels compiled, Blender up
        paper = run_case(reg, adapters, gold, TARGET, paper=True, variants=False, cache=None, methods={"paper"})
        p = paper["paper"]
        print(f"paper-like fit   {p['renders']:4d} renders  {p['seconds']:7.1f} s  {p['err']:.2%} (evaluation render)",
              flush=True)
        secs = []
        for _ in range(args.reps):
            o = remap_once(reg, adapters, gold, "cycles", "principled")
            r = o.report
            err, _ = evaluate(reg, adapters, gold, TARGET, r.params)
            secs.append(r.seconds)
            print(f"brdf-remap       {r.renders:4d} renders  {r.seconds:7.2f} s  {err:.2%} (evaluation render), "
                  f"{r.source_renders} source renders, verdict {r.verdict}", flush=True)
        for s in r.account.renders:
            print(f"  {s.purpose:11} {s.side:6} {s.renders:3d} renders {s.pixel_samples / 1e6:6.2f} Mpx*spp "
                  f"{s.seconds:6.2f} s")
        print(f"  outside renderers {r.account.other_seconds:.2f} s")
        m = statistics.median(secs)
        print(f"paper {p['seconds']:.1f} s / brdf-remap median {m:.2f} s = {p['seconds'] / m:.1f}x as fast")
    return 0


if __name__ == "__main__":
    sys.exit(main())
