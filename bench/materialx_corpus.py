"""MaterialX's example materials (the corpus, `../shared/corpus/materialx/`) converted as a user would,
each rendered by MaterialX's own GLSL: the verdicts, the time, and for the OpenPBR and Standard Surface
examples the fixed table's error (Blender's Principled by name, where the target is Principled: the
fit's start) beside the fit's, against the document's own rendering.

    python bench/materialx_corpus.py --to cycles:principled --out OUT [--jobs N] [--report-only]

Runs `remap convert` over the corpus folders into OUT (a rerun resumes), then prints a Markdown summary
from OUT's results; --report-only prints it from OUT as it is."""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from collections import Counter
from pathlib import Path

from common import ROOT

CORPUS = ROOT.parent / "shared" / "corpus" / "materialx"
FOLDERS = ("DisneyPrincipled", "GltfPbr", "OpenPbr", "SimpleHair", "StandardSurface", "UsdPreviewSurface")


def run(to: str, out: Path, jobs: int) -> float:
    t0 = time.perf_counter()
    cmd = [sys.executable, "-m", "brdfremap.core.cli", "convert", *(str(CORPUS / f) for f in FOLDERS), "--to", to,
           "--out", str(out), "--jobs", str(jobs)]
    subprocess.run(cmd, check=False)
    return time.perf_counter() - t0


def summary(out: Path) -> None:
    conv = json.loads((out / "convert.json").read_text())
    rows = conv["materials"]
    counts = Counter(m["status"] for m in rows)
    print(f"{len(rows)} materials: " + ", ".join(f"{n} {s}" for s, n in sorted(counts.items())) +
          f"; {conv['seconds']:.0f} s for the run ({conv['ran_in']})")
    for m in rows:
        if m["status"] in ("unsupported", "failed"):
            print(f"  {m['status']}: {m['name']} ({Path(m['file']).name}): {m['reason']}")
    print()
    print("| example | shader | fixed table | fit | verdict | renders, seconds |")
    print("|---|---|---|---|---|---|")
    for m in rows:
        if m["slot"] is None or Path(m["file"]).parent.name not in ("OpenPbr", "StandardSurface"):
            continue
        r = json.loads((out / "materials" / m["slot"] / "result.json").read_text())
        rule = r["metrics"]["start_error"] if r["start"].get("rule") else None
        print(f"| {m['name']} | {r['source']['model']} | {'–' if rule is None else f'{rule:.2%}'} | "
              f"{r['metrics']['relative_rmse']:.2%} | {r['verdict']} | {r['renders']}, {r['seconds']:.0f} s |")


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--to", required=True)
    ap.add_argument("--out", required=True, type=Path)
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--report-only", action="store_true")
    args = ap.parse_args()
    if not args.report_only:
        print(f"converted in {run(args.to, args.out, args.jobs):.0f} s", flush=True)
    summary(args.out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
