"""What a render costs each adapter, and the least time a library's renders can take at their samples.

    python bench/render_cost.py [--keep DIR] [--reps 5] [--materialx]

Measures, in this process, each adapter's seconds per render of the default probe (an opaque
material, a parameter changed before each render as a fit does) at several resolutions and
samples, and fits seconds = fixed + per_sample * pixels * samples by least squares. With --keep
(a folder `bench/convert.py --keep DIR` left, Mitsuba to Cycles), prints for each side of that library's jobs the
renders and pixel-samples it made, the seconds they took, and the seconds the cost model says
they need: what is left to win without rendering fewer samples. With --materialx, the materialx
adapter's seconds a render by resolution under a point light and under the studio: a rasteriser's cost
follows its pixels (8 x 8 samples each under point lights, 4 x 4 and 256 importance samples under an
environment), not the scene's samples. `make demo` (Mitsuba to Cycles) renders nothing with it."""

from __future__ import annotations

import argparse
import json
import statistics
import time
from pathlib import Path

import numpy as np
from common import open_adapters, registry

from brdfremap.core.data.scene import ProbeScene

CASES = {("mitsuba", "roughconductor"): ({"alpha": 0.2}, "alpha"),
         ("mitsuba", "roughplastic"): ({"alpha": 0.2, "diffuse_reflectance": (0.5, 0.2, 0.1)}, "alpha"),
         ("cycles", "principled"): ({"base_color": (0.8, 0.2, 0.1), "roughness": 0.4}, "roughness")}
"""Mitsuba's roughplastic redoes its rough-Fresnel set-up whenever its alpha changes (as a fit
changes it), which its roughconductor does not."""
SETTINGS = ((128, 1), (128, 16), (128, 64), (64, 64), (256, 16))


def cost_model(adapter, model: str, params: dict, moved: str, reps: int) -> tuple[float, float]:
    """(fixed seconds a render, seconds a pixel-sample), from the median of ``reps`` renders a setting."""
    spec = adapter.models[model]
    rows, secs = [], []
    for k, (res, spp) in enumerate(SETTINGS):
        scene, times = ProbeScene(resolution=res, spp=spp), []
        for i in range(reps + 1):
            value = params[moved] + 1e-3 * (k * (reps + 1) + i)  # a new point each time: nothing cached
            t0 = time.perf_counter()
            adapter.render(model, spec.complete({**params, moved: value}), scene)
            if i:  # the first render of a setting builds its scene
                times.append(time.perf_counter() - t0)
        rows.append((1.0, res * res * spp))
        secs.append(statistics.median(times))
    (fixed, per_sample), *_ = np.linalg.lstsq(np.array(rows), np.array(secs), rcond=None)
    return float(fixed), float(per_sample)


def _median_seconds(adapter, model, scene: ProbeScene, base: dict, rough: str, reps: int) -> float:
    """Median seconds a render of ``model`` on ``scene``, its ``rough`` changed each time (no cache)."""
    times = []
    for i in range(reps + 1):
        params = model.complete({**base, rough: 0.3 + 1e-3 * i})
        t0 = time.perf_counter()
        adapter.render(model, params, scene)
        if i:  # the first compiles and warms
            times.append(time.perf_counter() - t0)
    return statistics.median(times)


def materialx_costs(pool, reps: int) -> None:
    """The materialx adapter's median seconds a render (an OpenPBR copper), against Cycles' Principled on
    the same scene in the same run: under the probe's point light, and under the studio at the
    resolutions environments are rendered at (the held-out check's 32 px, a fit's 64 px)."""
    from brdfremap.core.data.scene import EnvironmentLight

    mx, cy = pool["materialx"], pool["cycles"]
    mxm, cym = mx.models["open_pbr_surface"], cy.models["principled"]
    studio = [EnvironmentLight(type="environment", map="studio")]
    print(f"\n{'open_pbr_surface vs principled':30} {'materialx s':>11} {'cycles s':>9} {'ratio':>6}")
    for label, res, lights in (("point light", 32, None), ("point light", 64, None), ("point light", 128, None),
                               ("studio", 32, studio), ("studio", 64, studio)):
        scene = ProbeScene(resolution=res) if lights is None else ProbeScene(resolution=res, lights=lights)
        m = _median_seconds(mx, mxm, scene, {"base_color": (0.9, 0.6, 0.4)}, "specular_roughness", reps)
        c = _median_seconds(cy, cym, scene, {"base_color": (0.9, 0.6, 0.4)}, "roughness", reps)
        print(f"{f'{label}, {res} px':30} {m:11.2f} {c:9.2f} {m / c:6.1f}")


def library_sides(keep: Path) -> dict[str, dict[str, float]]:
    """Renders, pixel-samples and seconds by side over a kept library's distinct jobs."""
    sides: dict[str, dict[str, float]] = {}
    seen = set()
    for path in sorted(keep.glob("materials/*/result.json")):
        rep = json.loads(path.read_text())
        if rep["key"] in seen:
            continue
        seen.add(rep["key"])
        for row in rep["account"]["renders"]:
            side = sides.setdefault(row["side"], {"renders": 0, "pixel_samples": 0, "seconds": 0.0})
            for k in side:
                side[k] += row[k]
    return sides


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--keep", type=Path, help="a folder bench/convert.py --keep left (source Mitsuba, target Cycles)")
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--materialx", action="store_true", help="also the materialx adapter's seconds a render")
    args = ap.parse_args()
    models = {}
    with open_adapters(registry(), sorted({a for a, _ in CASES} | ({"materialx", "cycles"} if args.materialx else set()))) as pool:
        print(f"{'adapter:model':22} {'fixed ms/render':>15} {'ns/pixel-sample':>16}")
        for (name, model), (params, moved) in CASES.items():
            models[name, model] = cost_model(pool[name], model, params, moved, args.reps)
            print(f"{name + ':' + model:22} {models[name, model][0] * 1e3:15.1f} {models[name, model][1] * 1e9:16.0f}")
        if args.materialx:
            materialx_costs(pool, args.reps)
    if args.keep:
        renderer = {"source": ("mitsuba", "roughconductor"), "target": ("cycles", "principled")}
        print(f"\n{'side':7} {'renders':>7} {'Mpx*spp':>8} {'seconds':>8} {'at the cost model':>18}")
        for side, s in library_sides(args.keep).items():
            fixed, per = models[renderer[side]]
            floor = s["renders"] * fixed + s["pixel_samples"] * per
            print(f"{side:7} {s['renders']:7.0f} {s['pixel_samples'] / 1e6:8.1f} {s['seconds']:8.1f} {floor:18.1f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
