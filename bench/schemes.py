"""One, two and three-stage remaps side by side: error, renders, seconds.

    python bench/schemes.py [--repeat N]

Each row is the median over N runs of the same remap in one process (warm renderer)."""

from __future__ import annotations

import argparse

from common import figures, median, open_adapters, registry, remap_once


CASES = [
    ("configs/materials/blue-plastic.yaml", "mitsuba", "roughplastic", ()),
    ("configs/materials/blue-plastic.yaml", "mitsuba", "roughplastic", ("distribution=ggx",)),
    ("configs/materials/red-plastic-ggx.yaml", "mitsuba", "roughplastic", ("distribution=beckmann",)),
    ("configs/materials/gold.yaml", "mitsuba", "roughconductor", ("distribution=ggx",)),
]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    reg = registry()
    print(f"{'source':<22} {'target':<30} {'scheme':<6} {'rel.RMSE':>9} {'ΔE_ITP':>7} {'renders':>7} {'seconds':>7}  verdict")
    with open_adapters(reg, ["mitsuba"]) as adapters:
        remap_once(reg, adapters, CASES[0][0], "mitsuba", "roughplastic")  # warm-up: kernel compilation
        for src, adapter, model, fix in CASES:
            for scheme in ("one", "two", "three"):
                runs = [remap_once(reg, adapters, src, adapter, model, fix=fix, scheme=scheme)
                        for _ in range(args.repeat)]
                r = figures(runs[0].report)
                target = f"{model}" + (f" {' '.join(fix)}" if fix else "")
                print(f"{src.split('/')[-1]:<22} {target:<30} {scheme:<6} {r.relative_rmse:9.2%} {r.perceptual:7.2f} "
                      f"{r.renders:7d} {median([o.report.seconds for o in runs]):7.2f}  "
                      f"{'reliable' if r.reliable else 'UNRELIABLE: ' + r.reason[:60]}")


if __name__ == "__main__":
    main()
