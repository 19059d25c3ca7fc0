"""A material rendered as its .blend holds it (Cycles' probe mesh) against the same Principled BSDF as a
model (the exact point sphere), under each held-out light: how much of a native source's error is the
geometry, and how much the held-out lights' own noise between seeds.

    python bench/native_geometry.py [--resolution 32] [--spp 16] [--seeds 0 10 20]

Makes tests/data/blend/everyday.py's .blend in a scratch folder and uses its "grouped plastic" (a
Principled BSDF inside a node group: no reading, rendered as written)."""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
from pathlib import Path

from common import ROOT


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--resolution", type=int, default=32)
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 10, 20])
    args = ap.parse_args(argv)
    from brdfremap.adapters.cycles.adapter import CyclesAdapter
    from brdfremap.adapters.cycles.library import BlendReader
    from brdfremap.core.data.metrics import relative_rmse
    from brdfremap.core.data.scene import ProbeScene
    from brdfremap.core.job.validation import held_out_scenes

    with tempfile.TemporaryDirectory() as tmp:
        subprocess.run([sys.executable, str(ROOT / "tests" / "data" / "blend" / "everyday.py"), tmp], check=True,
                       capture_output=True)
        native = {e.name: e for e in BlendReader().read(Path(tmp) / "everyday.blend")}["grouped plastic"].material.native
        params = CyclesAdapter.models["principled"].complete({"base_color": (0.05, 0.12, 0.6), "roughness": 0.35})
        print("| seed | condition | spp | native vs point | point vs point (other seeds) | native vs native |")
        print("|---|---|---|---|---|---|")
        with CyclesAdapter() as cy:
            for seed in args.seeds:
                scene = ProbeScene().with_(resolution=args.resolution, spp=args.spp, seed=seed)
                for c, a, b in held_out_scenes(scene):
                    a2, b2 = a.with_(seed=a.seed + 2), b.with_(seed=b.seed + 2)
                    n = (cy.render_native(native, a) + cy.render_native(native, b)) / 2
                    n2 = (cy.render_native(native, a2) + cy.render_native(native, b2)) / 2
                    p = (cy.render("principled", params, a) + cy.render("principled", params, b)) / 2
                    p2 = (cy.render("principled", params, a2) + cy.render("principled", params, b2)) / 2
                    print(f"| {seed} | {c.name} | {a.spp} | {relative_rmse(n, p2):.2%} | {relative_rmse(p, p2):.2%} | "
                          f"{relative_rmse(n, n2):.2%} |")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
