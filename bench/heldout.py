"""Two kept library conversions compared under the held-out lights, material by material.

    python bench/heldout.py BEFORE_DIR AFTER_DIR [--limit 0.10]

BEFORE_DIR and AFTER_DIR are folders `bench/convert.py --keep DIR` left for the same input. For each
material both converted, its verdict and its worst held-out error beyond the noise (over the
conditions whose noise floor is within --limit) in each run; then the verdict counts, how many
materials' worst held-out error fell or rose by more than a point, and the median and worst ratio of
held-out error to the fit scene's error over every resolved (material, light) pair."""

from __future__ import annotations

import argparse
import collections
import json
import statistics
from pathlib import Path


def results(keep: Path) -> dict[str, dict]:
    """Each material's result.json by its file and name, from a kept conversion's convert.json."""
    summary = json.loads((keep / "convert.json").read_text())
    out = {}
    for m in summary["materials"]:
        path = keep / "materials" / (m.get("slot") or "") / "result.json"
        if m.get("slot") and path.is_file():
            out[f"{Path(m['file']).name}::{m['name']}"] = json.loads(path.read_text())
    return out


def worst(rep: dict, limit: float) -> float:
    return max((c["beyond_noise"] for c in rep["validation"] if c["noise_floor"] <= limit), default=0.0)


def ratios(reps: dict[str, dict], limit: float) -> list[tuple[float, str, str]]:
    return [(c["error"] / max(r["metrics"]["relative_rmse"], 1e-9), k, c["condition"]) for k, r in reps.items()
            for c in r["validation"] if c["noise_floor"] <= limit and not c.get("given")]


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("before", type=Path)
    ap.add_argument("after", type=Path)
    ap.add_argument("--limit", type=float, default=0.10)
    args = ap.parse_args()
    before, after = results(args.before), results(args.after)
    both = sorted(set(before) & set(after))
    print(f"{'material':60} {'before':>22} {'after':>22}")
    fell = rose = 0
    for k in both:
        b, a = worst(before[k], args.limit), worst(after[k], args.limit)
        fell, rose = fell + (a < b - 0.01), rose + (a > b + 0.01)
        if abs(a - b) > 0.01 or before[k]["verdict"] != after[k]["verdict"]:
            print(f"{k[:60]:60} {before[k]['verdict']:>12} {b:8.1%} {after[k]['verdict']:>12} {a:8.1%}")
    for label, reps in (("before", before), ("after", after)):
        counts = collections.Counter(reps[k]["verdict"] for k in both)
        rs = ratios({k: reps[k] for k in both}, args.limit)
        top = max(rs) if rs else (0.0, "", "")
        print(f"{label}: {dict(sorted(counts.items()))}; held-out / fit error over {len(rs)} resolved pairs: median "
              f"{statistics.median(r[0] for r in rs):.2f}x, worst {top[0]:.1f}x ({top[1]}, {top[2]})")
    print(f"{len(both)} materials; worst held-out error beyond the noise fell by more than a point for {fell}, "
          f"rose for {rose}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
