"""Library conversion throughput: materials per minute with --jobs 1 against --jobs 2, one run.

    python bench/convert.py [--to cycles] [--reps 1] [--out docs/convert.txt] [--screenshot docs/report.png]

Converts the example scene (examples/library/scene.xml, ten materials) into fresh folders, so
every material is fitted (nothing reused), in one process and then in two worker processes, each
a whole `remap convert` as a user runs it (interpreter, renderers' start-up included). Prints
seconds, materials per minute and the ratio, and checks that both give the same fits. With
--screenshot, the report of the last run is opened in headless Chromium and captured."""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "examples" / "library" / "scene.xml"


def run(to: str, jobs: int, out: Path) -> tuple[float, dict]:
    shutil.rmtree(out, ignore_errors=True)
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "brdfremap.core.cli", "convert", str(SCENE), "--to", to, "--out",
                           str(out), "--jobs", str(jobs), "--quiet"], capture_output=True, text=True)
    secs = time.perf_counter() - t0
    if proc.returncode not in (0, 1):
        raise SystemExit(proc.stderr)
    return secs, json.loads((out / "convert.json").read_text())


def fits(summary: dict) -> list:
    return [(m["name"], m["model"], round(m["relative_rmse"] or 0, 6)) for m in summary["materials"]]


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--to", default="cycles")
    ap.add_argument("--reps", type=int, default=1)
    ap.add_argument("--out", default=None)
    ap.add_argument("--screenshot", default=None)
    args = ap.parse_args()
    tmp = Path(tempfile.mkdtemp(prefix="bench-convert-"))
    lines, secs = [], {1: [], 2: []}
    for rep in range(args.reps):
        results = {}
        for jobs in (1, 2):
            s, summary = run(args.to, jobs, tmp / f"j{jobs}")
            secs[jobs].append(s)
            results[jobs] = summary
            n = len(summary["materials"])
            line = (f"--to {args.to} --jobs {jobs}: {n} materials in {s:.1f} s = {60 * n / s:.1f} materials a minute "
                    f"({summary['converted']} converted)")
            print(line, flush=True)
            lines.append(line)
        same = fits(results[1]) == fits(results[2])
        lines.append(f"run {rep + 1}: --jobs 2 is {secs[1][-1] / secs[2][-1]:.2f}x as fast as --jobs 1; same fits: {same}")
        print(lines[-1], flush=True)
    if args.screenshot:
        sys.path.insert(0, str(ROOT / "tests"))
        from helpers import open_in_chromium

        page = open_in_chromium(tmp / "j2" / "index.html", screenshot=args.screenshot)
        lines.append(f"report: {page['images']} images, {len(page['broken'])} broken, console errors {page['errors']}")
        print(lines[-1])
    if args.out:
        head = (f"# python bench/convert.py --to {args.to} --reps {args.reps}\n# {SCENE.relative_to(ROOT)}, "
                "a fresh output folder each run (every material fitted), 2 cores\n")
        Path(args.out).write_text(head + "\n".join(lines) + "\n")
    shutil.rmtree(tmp, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
