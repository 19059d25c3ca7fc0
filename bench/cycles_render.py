"""What a Cycles render of the probe costs with and without the lobe passes and the light tree.

    python bench/cycles_render.py [--reps 5] [--renders 6]

Runs Blender in this process (the adapter's worker code, BlenderState) and renders the default
probe with a Principled metal at 128² and 32², 16 spp, changing the roughness before each render
as a fit does. The four settings alternate in every repetition, so that the machine's noise
falls on all of them alike; prints the median milliseconds per render and the ratios to the
adapter's former setting (passes on, light tree on). The adapter renders the passes only when a
lobe is asked for (two-stage fits of a target with two lobes), with the light tree off."""

from __future__ import annotations

import argparse
import statistics
import time

from brdfremap.adapters.cycles.worker import BlenderState
from brdfremap.core.data.scene import ProbeScene

PARAMS = {"distribution": "multi_ggx", "base_color": [0.9, 0.6, 0.3], "metallic": 1.0, "roughness": 0.3,
          "ior": 1.5, "specular_ior_level": 0.5, "specular_tint": [1, 1, 1], "coat_weight": 0.0,
          "coat_roughness": 0.03}
SETTINGS = {"passes, light tree (before)": (True, True), "passes, no light tree": (True, False),
            "no passes, light tree": (False, True), "no passes, no light tree (now)": (False, False)}


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--renders", type=int, default=6, help="renders per setting and repetition")
    args = ap.parse_args()
    state = BlenderState()
    print(f"{'resolution':>10}  {'setting':32} {'ms/render (median)':>18}  ratio")
    for res in (128, 32):
        req = {"model": "principled", "params": PARAMS, "scene": ProbeScene(resolution=res).document(),
               "out": f"/tmp/brdfremap-bench-cycles-{res}.exr"}
        state.render(req)  # builds the scene
        times: dict[str, list[float]] = {k: [] for k in SETTINGS}
        for _ in range(args.reps):
            for label, (passes, tree) in SETTINGS.items():
                state.bpy.context.scene.cycles.use_light_tree = tree
                state.render(dict(req, passes=passes))  # the switch itself is not timed
                t0 = time.perf_counter()
                for i in range(args.renders):
                    state.render(dict(req, passes=passes, params=dict(PARAMS, roughness=0.3 + 0.01 * i)))
                times[label].append((time.perf_counter() - t0) / args.renders * 1000)
        ref = statistics.median(times["passes, light tree (before)"])
        for label, ts in times.items():
            m = statistics.median(ts)
            print(f"{res:>8}²  {label:32} {m:18.1f}  {ref / m:.2f}x as fast")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
