"""A library's conversion as a user runs it, and where its seconds went.

    python bench/convert.py [INPUT ...] [--to cycles] [--jobs 1 [2 ...]] [--save RUN.json] [--keep DIR]
                            [--against RUN.json] [--out FILE.txt] [--screenshot docs/report.png]

Converts INPUT (default: `make demo`'s job, the example scene with its tables) into a fresh folder, so
every material is fitted (nothing reused), once for each --jobs value, each a whole `remap convert`
(interpreter and renderers' start-up included). Prints the wall time, seconds a material and the
verdicts, then the account of every job summed over the library (`result.json`'s `account`):
renders by purpose with their count, pixels x samples and seconds, and the seconds outside
renderers. A job that several materials share (a ground plane in many files) is counted once.

--save keeps the figures of the last run as JSON; --against compares this run with one kept:
the ratio of each purpose's seconds, and every material whose verdict changed or whose error
moved by more than 2 % of itself (the issue's "no verdict lost")."""

from __future__ import annotations

import argparse
import collections
import json
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "examples" / "library" / "scene.xml"
DEMO_TABLES = [str(ROOT / "configs" / "tables" / "built" / f"{t}.json") for t in (
    "mitsuba-roughconductor-to-cycles-principled", "mitsuba-roughconductor-to-cycles-metallic",
    "mitsuba-roughplastic-to-cycles-principled")]
"""`make demo`'s tables: with no INPUT, the bench runs the demo's command."""


def run(inputs: list[str], to: str, jobs: int, out: Path, tables: list[str]) -> tuple[float, dict]:
    shutil.rmtree(out, ignore_errors=True)
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "brdfremap.core.cli", "convert", *inputs, "--to", to, "--out",
                           str(out), "--jobs", str(jobs), "--quiet", *(a for t in tables for a in ("--table", t))],
                          capture_output=True, text=True)
    secs = time.perf_counter() - t0
    if proc.returncode not in (0, 1):
        raise SystemExit(proc.stderr)
    return secs, json.loads((out / "convert.json").read_text())


def reports(summary: dict, out: Path) -> dict[str, dict]:
    """Each job's result.json once (by job key), from the materials' slots."""
    found: dict[str, dict] = {}
    for m in summary["materials"]:
        path = out / "materials" / (m.get("slot") or "") / "result.json"
        if m.get("slot") and path.is_file():
            rep = json.loads(path.read_text())
            found.setdefault(rep["key"], rep)
    return found


def account(reps: dict[str, dict]) -> dict:
    """The library's renders by purpose (both sides), its seconds inside and outside renderers."""
    rows: dict[str, list[float]] = collections.defaultdict(lambda: [0, 0, 0.0])
    inside = outside = jobs_seconds = 0.0
    for rep in reps.values():
        acc = rep.get("account") or {}
        for s in acc.get("renders", []):
            row = rows[s["purpose"]]
            row[0] += s["renders"]
            row[1] += s["pixel_samples"]
            row[2] += s["seconds"]
        inside += acc.get("render_seconds", 0.0)
        outside += acc.get("other_seconds", 0.0)
        jobs_seconds += rep["seconds"]
    return {"purposes": {k: {"renders": v[0], "pixel_samples": v[1], "seconds": v[2]} for k, v in rows.items()},
            "render_seconds": inside, "other_seconds": outside, "job_seconds": jobs_seconds, "jobs": len(reps)}


def figures(summary: dict, reps: dict[str, dict], secs: float, jobs: int) -> dict:
    verdicts = collections.Counter(m["status"] for m in summary["materials"])
    mats = {f"{m['file']}::{m['name']}": {"status": m["status"], "error": m.get("relative_rmse"),
                                         "renders": m.get("renders"), "seconds": m.get("seconds")}
            for m in summary["materials"]}
    return {"jobs": jobs, "wall_seconds": secs, "materials": len(summary["materials"]),
            "converted": summary["converted"], "verdicts": dict(verdicts), "account": account(reps),
            "by_material": mats}


def show(f: dict, against: dict | None) -> list[str]:
    n, secs = f["materials"], f["wall_seconds"]
    verdicts = ", ".join(f"{v} {k}" for k, v in sorted(f["verdicts"].items()))
    acc = f["account"]
    lines = [f"--jobs {f['jobs']}: {n} materials in {secs:.1f} s, {secs / max(n, 1):.2f} s a material; {verdicts}",
             f"account of {acc['jobs']} jobs ({acc['job_seconds']:.1f} s of jobs; in renderers "
             f"{acc['render_seconds']:.1f} s, outside {acc['other_seconds']:.1f} s):",
             f"  {'purpose':12} {'renders':>8} {'Mpx*spp':>9} {'seconds':>8} {'share':>6}"
             + ("  seconds before  ratio" if against else "")]
    before = (against or {}).get("account", {}).get("purposes", {})
    total = max(acc["job_seconds"], 1e-9)
    for name, row in sorted(acc["purposes"].items(), key=lambda kv: -kv[1]["seconds"]):
        line = (f"  {name:12} {row['renders']:8d} {row['pixel_samples'] / 1e6:9.1f} {row['seconds']:8.1f} "
                f"{row['seconds'] / total:6.1%}")
        if against:
            b = before.get(name, {}).get("seconds", 0.0)
            line += f"  {b:14.1f}  {b / row['seconds']:.2f}x" if row["seconds"] else f"  {b:14.1f}"
        lines.append(line)
    lines.append(f"  {'outside':12} {'':8} {'':9} {acc['other_seconds']:8.1f} {acc['other_seconds'] / total:6.1%}")
    if against:
        lines += compare(f, against)
    return lines


def compare(f: dict, against: dict) -> list[str]:
    b = against
    lines = [f"against the kept run: wall {b['wall_seconds']:.1f} s -> {f['wall_seconds']:.1f} s "
             f"({b['wall_seconds'] / f['wall_seconds']:.2f}x as fast); renders "
             f"{sum(r['renders'] for r in b['account']['purposes'].values())} -> "
             f"{sum(r['renders'] for r in f['account']['purposes'].values())}"]
    changed = 0
    for key, m in sorted(f["by_material"].items()):
        old = b["by_material"].get(key)
        if old is None:
            continue
        e0, e1 = old["error"], m["error"]
        moved = e0 is not None and e1 is not None and abs(e1 - e0) > 0.02 * e0
        if old["status"] != m["status"] or moved:
            changed += 1
            lines.append(f"  {key}: {old['status']} {_pct(e0)} -> {m['status']} {_pct(e1)}")
    lines.append(f"materials whose verdict changed or whose error moved by more than 2 %: {changed} of "
                 f"{len(f['by_material'])}")
    return lines


def _pct(e: float | None) -> str:
    return "-" if e is None else f"{100 * e:.2f}%"


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("inputs", nargs="*")
    ap.add_argument("--table", action="append", default=None, help="as convert's --table (default with no INPUT: "
                                                                   "the demo's tables)")
    ap.add_argument("--to", default="cycles")
    ap.add_argument("--jobs", type=int, nargs="+", default=[1])
    ap.add_argument("--save", default=None)
    ap.add_argument("--against", default=None)
    ap.add_argument("--out", default=None)
    ap.add_argument("--screenshot", default=None)
    ap.add_argument("--keep", default=None, help="keep the last run's output folder here")
    args = ap.parse_args()
    tables = args.table if args.table is not None else ([] if args.inputs else DEMO_TABLES)
    args.inputs = args.inputs or [str(SCENE)]
    against = json.loads(Path(args.against).read_text()) if args.against else None
    tmp = Path(tempfile.mkdtemp(prefix="bench-convert-"))
    lines: list[str] = [f"# python bench/convert.py {' '.join(sys.argv[1:])}", f"# {' '.join(args.inputs)} -> {args.to}"]
    last = None
    for jobs in args.jobs:
        out = tmp / f"j{jobs}"
        secs, summary = run(args.inputs, args.to, jobs, out, tables)
        last = figures(summary, reports(summary, out), secs, jobs)
        shown = show(last, against)
        print("\n".join(shown), flush=True)
        lines += shown
    if args.screenshot:
        sys.path.insert(0, str(ROOT / "tests"))
        from helpers import open_in_chromium

        page = open_in_chromium(tmp / f"j{args.jobs[-1]}" / "index.html", screenshot=args.screenshot)
        lines.append(f"report: {page['images']} images, {len(page['broken'])} broken, console errors {page['errors']}")
        print(lines[-1])
    if args.save and last:
        Path(args.save).write_text(json.dumps(last, indent=1))
    if args.out:
        Path(args.out).write_text("\n".join(lines) + "\n")
    if args.keep:
        shutil.rmtree(args.keep, ignore_errors=True)
        shutil.move(str(tmp / f"j{args.jobs[-1]}"), args.keep)
    shutil.rmtree(tmp, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
