"""The Blender extension's matched glTF export against Blender's own glTF exporter, of one file.

    python bench/extension_export.py [--quality DEFAULT|DRAFT]

A `.blend` of the four Cycles Principled materials of `configs/materials/cycles-*.yaml` (copper, gold,
red plastic, coated paint), each on a sphere, is exported twice in one Blender process: by the
extension, installed from its zip as a user installs it (`brdf_remap.export`, target glTF: every
material remapped to three.js and judged, written next to the file), and by Blender's own
`bpy.ops.export_scene.gltf` (the Principled inputs written as they are: the fixed rules this tool
replaces). Each material of both files is rendered by three.js (GLTFLoader, as a viewer reads it)
and compared with Cycles' rendering of the original under the probe and under the studio
environment (held out of the fit), each Cycles image the mean of two seeds. Prints a Markdown table
and the export's wall time."""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from common import ROOT, open_adapters, registry

from brdfremap.adapters.threejs.library import material_document
from brdfremap.core.data.metrics import relative_rmse
from brdfremap.core.data.scene import EnvironmentLight, ProbeScene
from brdfremap.core.data.schemas import load_material

sys.path.insert(0, str(ROOT / "extension"))
import build  # noqa: E402  the extension's build script

MATERIALS = ("cycles-copper", "cycles-gold", "cycles-red-plastic", "cycles-coated-paint")
SCENES = {"probe": ProbeScene(spp=256), "studio": ProbeScene(lights=[EnvironmentLight(type="environment",
                                                                                       map="studio")],
                                                               resolution=64, spp=1024)}

DRIVER = """
import bpy, json, sys, time
zip_path, blend, python, quality, sockets = sys.argv[-5:]
bpy.ops.wm.read_factory_settings(use_empty=True)
for i, (name, inputs) in enumerate(json.loads(sockets).items()):
    m = bpy.data.materials.new(name)
    if m.node_tree is None:
        m.use_nodes = True
    p = next(n for n in m.node_tree.nodes if n.type == "BSDF_PRINCIPLED")
    for socket, value in inputs.items():
        sock = p.inputs.get(socket)  # a socket this Blender lacks is left out
        if sock is not None:
            sock.default_value = [*value, 1.0][:len(sock.default_value)] if isinstance(value, list) else value
    bpy.ops.mesh.primitive_uv_sphere_add(location=(3.0 * i, 0.0, 0.0))
    bpy.context.object.data.materials.append(m)
bpy.ops.wm.save_as_mainfile(filepath=blend)
bpy.ops.extensions.package_install_files(filepath=zip_path, repo="user_default", enable_on_install=True)
prefs = bpy.context.preferences.addons["bl_ext.user_default.brdf_remap"].preferences
prefs.python, prefs.quality = python, quality
bpy.ops.wm.open_mainfile(filepath=blend)
t0 = time.perf_counter()
bpy.ops.brdf_remap.export(target="GLTF", scope="ALL")
took = time.perf_counter() - t0
bpy.ops.export_scene.gltf(filepath=blend.replace(".blend", "-blender.gltf"), export_format="GLTF_SEPARATE")
print("SECONDS", took)
"""


def sockets(cycles, name: str) -> tuple[str, dict, dict]:
    """The material's name, its complete Principled parameters, and its Principled BSDF's socket values."""
    src = load_material(ROOT / "configs" / "materials" / f"{name}.yaml")
    spec = cycles.models["principled"]
    params = spec.complete(src.params)
    values = {s: list(params[p]) if isinstance(params[p], (list, tuple)) else params[p] for p, s in spec.inputs.items()}
    return src.name or name, params, values


def export(folder: Path, quality: str, materials: dict[str, dict]) -> float:
    zip_path = build.build(folder / "dist")
    env = {**os.environ, "BLENDER_USER_RESOURCES": str(folder / "blender-user")}
    proc = subprocess.run([sys.executable, "-c", DRIVER, str(zip_path), str(folder / "scene.blend"), sys.executable,
                           quality, json.dumps(materials)], capture_output=True, text=True, timeout=7200, env=env)
    if "SECONDS " not in proc.stdout:
        raise SystemExit(f"the export failed: {(proc.stdout + proc.stderr)[-2000:]}")
    return float(proc.stdout.split("SECONDS ", 1)[1].split()[0])


def by_name(path: Path) -> dict[str, dict]:
    doc = json.loads(path.read_text())
    return {m["name"]: material_document(doc, i) for i, m in enumerate(doc["materials"])}


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quality", default="DEFAULT", choices=("DEFAULT", "DRAFT"))
    args = ap.parse_args()
    reg = registry()
    with open_adapters(reg, ["cycles", "threejs"]) as pool, tempfile.TemporaryDirectory() as tmp:
        cycles, three = pool["cycles"], pool["threejs"]
        found = [sockets(cycles, m) for m in MATERIALS]
        seconds = export(Path(tmp), args.quality, {name: values for name, _, values in found})
        ours = by_name(Path(tmp) / "scene.brdf-remap" / "threejs" / "library.gltf")
        theirs = by_name(Path(tmp) / "scene-blender.gltf")
        summary = json.loads((Path(tmp) / "scene.brdf-remap" / "threejs" / "convert.json").read_text())
        verdicts = {m["name"]: m for m in summary["materials"]}
        rows = [(name, verdicts[name], errors(cycles, three, params, ours[name], theirs[name]))
                for name, params, _ in found]
    print(f"the extension's export: {seconds:.1f} s for {len(rows)} materials ({args.quality.lower()} quality)")
    print()
    print("| material | extension: fit error, verdict | probe: extension / Blender's exporter | "
          "studio: extension / Blender's exporter | Cycles' noise (probe, studio) |")
    print("|---|---|---|---|---|")
    for name, v, e in rows:
        print(f"| {name} | {v['relative_rmse']:.2%}, {v['status']} | {e['probe'][0]:.2%} / {e['probe'][1]:.2%} | "
              f"{e['studio'][0]:.2%} / {e['studio'][1]:.2%} | {e['probe'][2]:.2%}, {e['studio'][2]:.2%} |")
    return 0


def errors(cycles, three, params: dict, ours: dict, theirs: dict) -> dict[str, tuple[float, float, float]]:
    """Per scene: (the extension's file, Blender's exporter's, Cycles' noise) relative RMSE against Cycles."""
    out = {}
    for name, scene in SCENES.items():
        a, b = (cycles.render("principled", params, scene.with_(seed=s)) for s in (11, 12))
        ref, noise = (a + b) / 2, relative_rmse(a, b) / 2
        out[name] = (relative_rmse(ref, three.render_document(ours, scene)),
                     relative_rmse(ref, three.render_document(theirs, scene)), noise)
    return out


if __name__ == "__main__":
    np.seterr(all="ignore")
    raise SystemExit(main())
