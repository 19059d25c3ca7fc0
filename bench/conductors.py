"""Mitsuba conductor presets remapped to Cycles: error and renders per case.

    python bench/conductors.py [--quick] [--out docs/measurements/conductors.md]

Sources: Mitsuba roughconductor (Beckmann) with presets Au, Ag, Cu, Al, Cr at alpha 0.05,
0.1, 0.2, 0.4. Targets: Cycles principled, glossy GGX, glossy Beckmann. Prints one row per
case, then medians per target, and writes the same table as Markdown."""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from common import ROOT, figures, median, open_adapters, registry, remap_once

from brdfremap.core.data.atomic import write_text_atomic
from brdfremap.core.data.schemas import Material

PRESETS = ("Au", "Ag", "Cu", "Al", "Cr")
ALPHAS = (0.05, 0.1, 0.2, 0.4)
TARGETS = (("principled", ()), ("glossy", ("distribution=ggx",)), ("glossy", ("distribution=beckmann",)))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="Au and Cu at alpha 0.1 only")
    ap.add_argument("--out", default=str(ROOT / "docs" / "measurements" / "conductors.md"))
    args = ap.parse_args()
    presets, alphas = (("Au", "Cu"), (0.1,)) if args.quick else (PRESETS, ALPHAS)
    reg = registry()
    rows = []
    header = "| source | target | rel. RMSE | ΔE_ITP | noise floor | renders | seconds | fitted α | verdict |"
    print(header)
    print("|---|---|---:|---:|---:|---:|---:|---:|---|")
    t_all = time.perf_counter()
    with open_adapters(reg, ["mitsuba", "cycles"]) as adapters:
        for preset in presets:
            for alpha in alphas:
                src = Material(adapter="mitsuba", model="roughconductor",
                               params={"distribution": "beckmann", "material": preset, "alpha": alpha})
                for model, fix in TARGETS:
                    o = remap_once(reg, adapters, src, "cycles", model, fix=fix)
                    r = figures(o.report)
                    target = model + (f" {fix[0].split('=')[1]}" if fix else "")
                    verdict = "reliable" if r.reliable else r.reason.split(";")[0].split(" although")[0]
                    row = (f"| {preset} β α={alpha:g} | {target} | {r.relative_rmse:.2%} | {r.perceptual:.2f} | "
                           f"{o.report.metrics.noise_floor:.2%} | {r.renders} | {r.seconds:.1f} | {r.params['roughness'] ** 2:.4f} | "
                           f"{verdict} |")
                    print(row, flush=True)
                    rows.append((target, r, row))
    lines = ["| target | cases | median rel. RMSE | median ΔE_ITP | median renders | median seconds |",
             "|---|---:|---:|---:|---:|---:|"]
    for target in dict.fromkeys(t for t, _, _ in rows):
        rs = [r for t, r, _ in rows if t == target]
        lines.append(f"| {target} | {len(rs)} | {median([r.relative_rmse for r in rs]):.2%} | "
                     f"{median([r.perceptual for r in rs]):.2f} | {median([r.renders for r in rs]):.0f} | "
                     f"{median([r.seconds for r in rs]):.1f} |")
    print()
    print("\n".join(lines))
    print(f"\ntotal {time.perf_counter() - t_all:.0f} s")
    doc = ["# Mitsuba conductors remapped to Blender Cycles", "",
           "Produced by `python bench/conductors.py` (128², 16 spp, default options (scheme auto), default probe scene).",
           "β = Mitsuba Beckmann; fitted α = Blender roughness². 'model mismatch' = the fit converged "
           "and the error is what the target model can do.", "", *lines, "", header,
           "|---|---|---:|---:|---:|---:|---:|---:|---|", *[row for _, _, row in rows], ""]
    if not args.quick:
        write_text_atomic(Path(args.out), "\n".join(doc))


if __name__ == "__main__":
    main()
