"""Cycles Principled materials to MaterialX's OpenPBR: this tool's remap against the fixed table (Blender's
Principled values under OpenPBR's names, as Blender's MaterialX export and `library.mtlx` for a Cycles
target write them), both judged in MaterialX's own renderer.

    python bench/materialx_compare.py [--only NAME ...]

For each material of bench/threejs_compare.py (configs/materials/cycles-*.yaml): the remap to
`materialx:open_pbr_surface` (a full remap, judged under the held-out lights: its error, verdict, renders
and seconds), and the fixed table's OpenPBR (`correspondence.open_pbr_inputs`). Both are rendered by
MaterialX's GLSL and compared with Cycles under the probe and under the studio environment, each Cycles
image the mean of two seeds (their difference over two is its noise, printed). Prints a Markdown table."""

from __future__ import annotations

import argparse

import numpy as np
from common import ROOT, open_adapters, registry, remap_once

from brdfremap.adapters.materialx.correspondence import open_pbr_inputs
from brdfremap.core.data.metrics import relative_rmse
from brdfremap.core.data.scene import EnvironmentLight, ProbeScene
from brdfremap.core.data.schemas import load_material

MATERIALS = ("cycles-copper", "cycles-gold", "cycles-red-plastic", "cycles-coated-paint")
SCENES = {"probe": ProbeScene(spp=256), "studio": ProbeScene(lights=[EnvironmentLight(type="environment",
                                                                                       map="studio")],
                                                               resolution=64, spp=1024)}


def errors(cycles, mx, params: dict, fitted: dict, table: dict) -> dict[str, tuple[float, float, float]]:
    """Per scene: (the remap, the fixed table, Cycles' noise) relative RMSE against Cycles."""
    model = mx.models["open_pbr_surface"]
    out = {}
    for name, scene in SCENES.items():
        a, b = (cycles.render("principled", params, scene.with_(seed=s)) for s in (11, 12))
        ref, noise = (a + b) / 2, relative_rmse(a, b) / 2
        out[name] = (relative_rmse(ref, mx.render(model, fitted, scene)), relative_rmse(ref, mx.render(model, table, scene)),
                     noise)
    return out


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--only", nargs="*", default=list(MATERIALS))
    args = ap.parse_args()
    reg = registry()
    rows = []
    with open_adapters(reg, ["cycles", "materialx"]) as pool:
        cycles, mx = pool["cycles"], pool["materialx"]
        model = mx.models["open_pbr_surface"]
        for name in args.only:
            src = load_material(ROOT / "configs" / "materials" / f"{name}.yaml")
            params = cycles.models["principled"].complete(src.params)
            r = remap_once(reg, pool, src, "materialx", "open_pbr_surface").report
            fitted = model.complete(r.params)
            table = model.complete({k: v for k, v in open_pbr_inputs(params).items() if k in model.names})
            errs = errors(cycles, mx, params, fitted, table)
            rows.append((src.name or name, r, errs))
            print(f"{name}: remap {r.metrics.relative_rmse:.2%} {r.verdict}; " + ", ".join(
                f"{k} {v[0]:.2%} / table {v[1]:.2%} (noise {v[2]:.2%})" for k, v in errs.items()), flush=True)
    print()
    print("| material | remap: fit error, verdict, renders, seconds | probe: remap / fixed table | "
          "studio: remap / fixed table | Cycles' noise (probe, studio) |")
    print("|---|---|---|---|---|")
    for name, r, e in rows:
        print(f"| {name} | {r.metrics.relative_rmse:.2%}, {r.verdict}, {r.renders}, {r.seconds:.1f} s | "
              f"{e['probe'][0]:.2%} / {e['probe'][1]:.2%} | {e['studio'][0]:.2%} / {e['studio'][1]:.2%} | "
              f"{e['probe'][2]:.2%}, {e['studio'][2]:.2%} |")
    return 0


if __name__ == "__main__":
    np.seterr(all="ignore")
    raise SystemExit(main())
