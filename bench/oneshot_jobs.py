"""One-shot external renderers: a batch of renders (a Jacobian's) one at a time against `jobs` at once.

    python bench/oneshot_jobs.py [--renders 8] [--jobs 1,2,4]

Renders the same batch through `configs/renderers/mitsuba-cli.yaml` (Mitsuba's own command line,
one process per render, most of it process start-up) with each `jobs:` setting, in one run, and
prints seconds and the ratio to jobs 1."""

import argparse
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT.parent))


def main() -> None:
    from brdfremap.adapters.subprocess.adapter import adapter_class
    from brdfremap.core.data.scene import ProbeScene

    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--renders", type=int, default=8)
    p.add_argument("--jobs", default="1,2,4")
    args = p.parse_args()
    src = ROOT / "configs" / "renderers" / "mitsuba-cli.yaml"
    scene = ProbeScene(resolution=64, spp=16)
    times = {}
    with tempfile.TemporaryDirectory() as tmp:
        for jobs in (int(j) for j in args.jobs.split(",")):
            path = Path(tmp) / f"jobs{jobs}.yaml"
            path.write_text(src.read_text().replace("name: mitsuba-cli", f"name: mitsuba-cli-{jobs}")
                            + f"jobs: {jobs}\n")
            (Path(tmp) / "mitsuba-cli.xml").write_text((src.parent / "mitsuba-cli.xml").read_text())
            adapter = adapter_class(path)()
            try:
                base = adapter.models["roughconductor"].complete({})
                reqs = [("roughconductor", {**base, "alpha": 0.05 + 0.01 * i}, scene, None) for i in range(args.renders)]
                t0 = time.perf_counter()
                adapter.render_batch(reqs)
                times[jobs] = time.perf_counter() - t0
            finally:
                adapter.close()
            print(f"jobs {jobs}: {args.renders} renders in {times[jobs]:.2f} s, {times[list(times)[0]] / times[jobs]:.2f}x "
                  f"jobs {list(times)[0]}", flush=True)


if __name__ == "__main__":
    main()
