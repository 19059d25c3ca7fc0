"""The README's picture: source, remap and error side by side for two remaps, and their figures.

    python bench/readme_figure.py [--out docs/readme-remap.png]

Runs two remaps with `remap` (a same-family pair that matches to the render noise under every
light, and a model mismatch) into out/readme/, then shows each one's previews in a row: source and
remap through the display transform with one exposure, and the error map with its scale."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CASES = [
    ("Mitsuba copper (Beckmann α 0.2) → Cycles Metallic", "copper.yaml",
     ["--adapter", "cycles", "--model", "metallic", "--fix", "distribution=beckmann"]),
    ("Mitsuba gold (Beckmann α 0.1) → Cycles Principled", "gold.yaml", ["--adapter", "cycles", "--model", "principled"]),
]


def main() -> int:
    from brdfremap.core.cli import main as remap

    ap = argparse.ArgumentParser()
    ap.add_argument("--out", default=str(ROOT / "docs" / "readme-remap.png"))
    args = ap.parse_args()
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(len(CASES), 3, figsize=(7.2, 2.6 * len(CASES)))
    for row, (title, material, flags) in zip(axes, CASES):
        out = ROOT / "out" / "readme" / Path(material).stem
        if remap(["--source", str(ROOT / "configs/materials" / material), "--out", str(out), "--quiet", *flags]):
            return 1
        r = json.loads((out / "result.json").read_text())
        m = r["metrics"]
        print(f"{title}: {m['relative_rmse']:.2%} relative RMSE, ΔE_ITP {m['perceptual']:.2f}, {r['renders']} renders, "
              f"{r['seconds']:.1f} s, verdict {r['verdict']}")
        images = [plt.imread(out / f"{n}.png") for n in ("source", "target", "error")]
        for ax, img, label in zip(row, images, ("source", f"remap: {m['relative_rmse']:.1%} ({r['verdict']})",
                                                "error (scale on its bar)")):
            ax.imshow(img)
            ax.set_xticks([])
            ax.set_yticks([])
            ax.set_title(label, fontsize=8)
        row[0].set_ylabel(title.replace(" → ", "\n→ "), fontsize=7)
    fig.tight_layout()
    fig.savefig(args.out, dpi=110)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
