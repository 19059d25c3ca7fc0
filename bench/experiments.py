"""Run every shipped experiment (configs/experiments) and publish its figures in docs/.

    python bench/experiments.py [--out out/experiments] [--only fig5 ...]

Each experiment writes its full results under --out (resumable: a rerun reuses finished
points). Its plots are copied to docs/experiments/ (PNG; the SVGs stay in --out) and
docs/experiments.md gets one table row per experiment, from its summary.json."""

from __future__ import annotations

import argparse
import json
import shutil
import sys
from pathlib import Path

from brdfremap.core.cli import main as remap
from brdfremap.core.experiments import load_experiment

ROOT = Path(__file__).resolve().parents[1]


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", default=str(ROOT / "out" / "experiments"))
    ap.add_argument("--only", nargs="*", default=[], help="experiment file name prefixes")
    args = ap.parse_args()
    docs = ROOT / "docs" / "experiments"
    docs.mkdir(parents=True, exist_ok=True)
    rows = []
    for path in sorted((ROOT / "configs" / "experiments").glob("*.yaml"), key=lambda p: int(p.name[3:].split("-")[0])):
        if args.only and not any(path.name.startswith(o) for o in args.only):
            continue
        exp = load_experiment(path)
        out = Path(args.out) / path.stem
        print(f"== {path.relative_to(ROOT)}", flush=True)
        code = remap([exp.kind, str(path), "--out", str(out), "--quiet"])
        if code:
            return code
        s = json.loads((out / "summary.json").read_text())
        shutil.copyfile(out / "sweep.png", docs / f"{path.stem}.png")
        images = [f"experiments/{path.stem}.png"]
        if exp.kind == "roundtrip":
            shutil.copyfile(out / "roundtrip.png", docs / f"{path.stem}-roundtrip.png")
            images.append(f"experiments/{path.stem}-roundtrip.png")
        if s["cliffs"]:
            shutil.copyfile(out / "cliff-1.png", docs / f"{path.stem}-cliff.png")
            images.append(f"experiments/{path.stem}-cliff.png")
        else:
            (docs / f"{path.stem}-cliff.png").unlink(missing_ok=True)  # from an earlier run
        fit = s["roundtrip_fit_unflagged"]
        rt = (f"slope {fit['slope']:.3f}, R² {fit['r2']:.4f} ({fit['points']} values)" if fit else "")
        cliffs = "; ".join(c["short"] for c in s["cliffs"][:3])
        if len(s["cliffs"]) > 3:
            cliffs += f"; {len(s['cliffs']) - 3} more"
        rows.append(f"| {s['figure'].removeprefix('Sztrajman et al. 2017, ')} | `{path.name}` | {s['points']} | "
                    f"{s['flagged']} ({s['unstable']} unreliable, {s['after_a_cliff']} after a cliff) | "
                    f"{s['model_mismatch_only']} | {len(s['cliffs'])}{': ' + cliffs if cliffs else ''} | {rt} | "
                    f"{s['median_relative_rmse']:.2%} | {s['renders_all_points']} renders, "
                    f"{s['remap_seconds_all_points']:.0f} s | "
                    + " ".join(f"[{Path(i).stem}]({i})" for i in images) + " |")
    if args.only:
        print("\n".join(rows))
        return 0
    head = ("# The paper's experiments, reproduced\n\n"
            "Made by `python bench/experiments.py` (each row: `remap sweep|roundtrip configs/experiments/FILE "
            "--out DIR`). *Flagged*: unreliable for a reason other than a plain model mismatch (a trimmed "
            "reflectance, a pinned bound, an ill-conditioned fit), or the point after a cliff; the round-trip "
            "line is fitted without them. *Mismatch*: converged, but the error is above the threshold: the "
            "closest the target model gets.\n\n"
            "| figure | experiment | points | flagged | mismatch | cliffs | round trip (unflagged) | "
            "median error | cost (all remaps) | plots |\n|---|---|---|---|---|---|---|---|---|---|\n")
    (ROOT / "docs" / "experiments.md").write_text(head + "\n".join(rows) + "\n")
    print((ROOT / "docs" / "experiments.md").read_text())
    return 0


if __name__ == "__main__":
    sys.exit(main())
