"""Cycles Principled materials to three.js: this tool's remap against Blender's own glTF exporter.

    python bench/threejs_compare.py [--only NAME ...]

For each material (configs/materials/cycles-*.yaml): the remap to `threejs:gltf_pbr` (a full remap,
judged under the held-out lights: its error, verdict, renders and seconds), and Blender's conversion
(the material saved by the Cycles adapter, put on a sphere and exported by `bpy.ops.export_scene.gltf`,
then read by three.js's GLTFLoader exactly as a viewer would). Both are rendered in three.js and
compared with Cycles under the probe and under the studio environment, each Cycles image the mean of
two seeds (their difference over two is its noise, printed). Prints a Markdown table."""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from common import ROOT, open_adapters, registry, remap_once

from brdfremap.core.data.metrics import relative_rmse
from brdfremap.core.data.scene import EnvironmentLight, ProbeScene
from brdfremap.core.data.schemas import load_material

MATERIALS = ("cycles-copper", "cycles-gold", "cycles-red-plastic", "cycles-coated-paint")
SCENES = {"probe": ProbeScene(spp=256), "studio": ProbeScene(lights=[EnvironmentLight(type="environment",
                                                                                       map="studio")],
                                                               resolution=64, spp=1024)}

EXPORT = """
import bpy, sys
blend, out = sys.argv[-2], sys.argv[-1]
bpy.ops.wm.open_mainfile(filepath=blend)
mat = bpy.data.materials["brdf-remap"]
bpy.ops.mesh.primitive_uv_sphere_add()
bpy.context.active_object.data.materials.append(mat)
bpy.ops.export_scene.gltf(filepath=out, export_format="GLTF_SEPARATE", use_selection=True)
"""


def blender_export(cycles, params: dict, folder: Path) -> dict:
    """Blender's glTF exporter's conversion of this Principled BSDF: the exported file's material."""
    cycles.write_native("principled", params, folder)
    out = folder / "exported.gltf"
    proc = subprocess.run([sys.executable, "-c", EXPORT, str(folder / "material.blend"), str(out)],
                          capture_output=True, text=True, timeout=600)
    if proc.returncode != 0 or not out.exists():
        raise SystemExit(f"Blender's glTF export failed: {proc.stderr[-1500:]}")
    doc = json.loads(out.read_text())
    mat = doc["materials"][0]
    return {"asset": {"version": "2.0"}, "materials": [mat], **({"extensionsUsed": sorted(mat["extensions"])}
                                                              if mat.get("extensions") else {})}


def errors(cycles, three, params: dict, ours: dict, exported: dict) -> dict[str, tuple[float, float, float]]:
    """Per scene: (ours, Blender's exporter, Cycles' noise) relative RMSE against Cycles."""
    out = {}
    for name, scene in SCENES.items():
        a, b = (cycles.render("principled", params, scene.with_(seed=s)) for s in (11, 12))
        ref, noise = (a + b) / 2, relative_rmse(a, b) / 2
        mine = three.render("gltf_pbr", ours, scene)
        theirs = three.render_document(exported, scene)
        out[name] = (relative_rmse(ref, mine), relative_rmse(ref, theirs), noise)
    return out


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--only", nargs="*", default=list(MATERIALS))
    args = ap.parse_args()
    reg = registry()
    rows = []
    with open_adapters(reg, ["cycles", "threejs"]) as pool, tempfile.TemporaryDirectory() as tmp:
        cycles, three = pool["cycles"], pool["threejs"]
        for name in args.only:
            src = load_material(ROOT / "configs" / "materials" / f"{name}.yaml")
            params = cycles.models["principled"].complete(src.params)
            outcome = remap_once(reg, pool, src, "threejs", "gltf_pbr")
            r = outcome.report
            ours = three.models["gltf_pbr"].complete(r.params)
            folder = Path(tmp) / name
            folder.mkdir()
            exported = blender_export(cycles, params, folder)
            errs = errors(cycles, three, params, ours, exported)
            rows.append((src.name or name, r, errs, exported["materials"][0]))
            print(f"{name}: ours {r.metrics.relative_rmse:.2%} {r.verdict}; " + ", ".join(
                f"{k} {v[0]:.2%} / exporter {v[1]:.2%} (noise {v[2]:.2%})" for k, v in errs.items()), flush=True)
    print()
    print("| material | remap: fit error, verdict, renders, seconds | probe: remap / Blender's exporter | "
          "studio: remap / Blender's exporter | Cycles' noise (probe, studio) | the exporter wrote |")
    print("|---|---|---|---|---|---|")
    for name, r, e, mat in rows:
        pbr = mat.get("pbrMetallicRoughness", {})
        wrote = (f"base {_rgb(pbr.get('baseColorFactor', [1, 1, 1, 1])[:3])}, metallic "
                 f"{pbr.get('metallicFactor', 1):.3g}, roughness {pbr.get('roughnessFactor', 1):.3g}"
                 + "".join(f", {k.replace('KHR_materials_', '')}" for k in sorted(mat.get("extensions", {}))))
        print(f"| {name} | {r.metrics.relative_rmse:.2%}, {r.verdict}, {r.renders}, {r.seconds:.1f} s | "
              f"{e['probe'][0]:.2%} / {e['probe'][1]:.2%} | {e['studio'][0]:.2%} / {e['studio'][1]:.2%} | "
              f"{e['probe'][2]:.2%}, {e['studio'][2]:.2%} | {wrote} |")
    return 0


def _rgb(v) -> str:
    return "(" + ", ".join(f"{float(x):.3g}" for x in v) + ")"


if __name__ == "__main__":
    np.seterr(all="ignore")
    raise SystemExit(main())
