"""UsdPreviewSurface to Blender Cycles: this tool's remap against Blender's own USD importer.

    python bench/usd_compare.py [STAGE ...]      (default: tests/data/usd/previews.usda and the
                                                   USD Working Group's StandardShaderBall in
                                                   tests/data/usd/StandardShaderBall/)

For each UsdPreviewSurface material the USD reader lists (a variant that changes one is a material of
its own), the judge is three.js's USDLoader rendering the material (the `threejs:usd_preview_surface`
model, the source of every USD conversion here). Two Cycles Principled materials are compared with it:
the remap to `cycles:principled` (a full remap: its error, verdict, renders and seconds), and Blender's
conversion (the stage, its variant selected and flattened by usd-core, imported by
`bpy.ops.wm.usd_import` in a Blender process, its Principled BSDF's inputs read and rendered by the
Cycles adapter; an input it drives by an image as the image's mean, as the remap's source reads it).
Each is rendered in the fit's own scene (the probe, with a second view lit from behind where the fit
chose one), under the probe alone and under the studio environment (held out from the fit), each
Cycles image the mean of two seeds (their difference over two is its noise, printed). Prints a
Markdown table."""

from __future__ import annotations

import argparse
import json
import re
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from common import ROOT, open_adapters, registry, remap_once

from brdfremap.adapters.usd.reader import UsdReader
from brdfremap.adapters.usd.stage import open_stage
from brdfremap.core.data.metrics import relative_rmse
from brdfremap.core.data.scene import EnvironmentLight, ProbeScene

STAGES = [ROOT / "tests" / "data" / "usd" / "previews.usda",
          ROOT / "tests" / "data" / "usd" / "StandardShaderBall" / "standard_shader_ball_scene.usda"]
SCENES = {"probe": ProbeScene(spp=256), "studio": ProbeScene(lights=[EnvironmentLight(type="environment",
                                                                                       map="studio")],
                                                               resolution=64, spp=1024)}

IMPORT = """
import bpy, json, sys
sockets = json.loads(sys.argv[-2])
CHANNEL = {"Red": 0, "Green": 1, "Blue": 2, "Color": None}

def image_mean(node, channel):
    px = list(node.image.pixels)
    if not px:
        raise ValueError(f"image {node.image.filepath} is not there")
    rows = [px[i:i + 4] for i in range(0, len(px), 4)]
    if channel is None:
        return [sum(r[c] for r in rows) / len(rows) for c in range(3)]
    return sum(r[channel] for r in rows) / len(rows)

def value(i):
    # a socket an image drives (directly, or one channel through Separate Color): the image's mean
    if not i.is_linked:
        return i.default_value
    link = i.links[0]
    node, channel = link.from_node, CHANNEL.get(link.from_socket.name)
    if node.type == "SEPARATE_COLOR" and node.inputs[0].is_linked:
        node = node.inputs[0].links[0].from_node
    if node.type != "TEX_IMAGE" or node.image is None:
        raise ValueError(f"socket {i.name} is driven by a {node.type} it cannot read")
    return image_mean(node, channel)

bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.wm.usd_import(filepath=sys.argv[-1], import_all_materials=True)
out = {}
for m in bpy.data.materials:
    p = next((n for n in (m.node_tree.nodes if m.node_tree else []) if n.type == "BSDF_PRINCIPLED"), None)
    if p is not None:
        found = {k: p.inputs.get(s) for k, s in sockets.items()}  # a socket this Blender lacks: its default
        try:  # a material of the stage this bench does not compare may name an image that is not there
            values = {k: value(i) for k, i in found.items() if i is not None}
        except ValueError:
            continue
        out[m.name] = {k: (list(v)[:3] if hasattr(v, "__len__") else v) for k, v in values.items()}
print("IMPORTED", json.dumps(out))
"""


def flattened(stage_file: Path, label: str, out: Path) -> Path:
    """The stage with the variant ``set=name`` selected (or none), flattened into one layer."""
    stage = open_stage(stage_file)  # its composition warnings kept off the table
    if label:
        vset, name = label.split("=", 1)
        prim = next(p for p in stage.Traverse() if vset in p.GetVariantSets().GetNames())
        stage.SetEditTarget(stage.GetSessionLayer())
        prim.GetVariantSets().GetVariantSet(vset).SetVariantSelection(name)
    stage.Export(str(out))
    return out


def blender_import(path: Path, sockets: dict[str, str]) -> dict[str, dict]:
    """Blender's USD importer's Principled BSDF of every material of the file, as Principled parameters."""
    proc = subprocess.run([sys.executable, "-c", IMPORT, json.dumps(sockets), str(path)], capture_output=True,
                          text=True, timeout=600)
    if proc.returncode != 0 or "IMPORTED " not in proc.stdout:
        raise SystemExit(f"Blender's USD import failed: {proc.stderr[-1500:]}")
    got = json.loads(proc.stdout.split("IMPORTED ", 1)[1].splitlines()[0])
    return {name: {k: tuple(v) if isinstance(v, list) else v for k, v in values.items()} for name, values in got.items()}


def errors(cycles, three, source: dict, ours: dict, theirs: dict, fit: ProbeScene) -> dict[str, tuple[float, float, float]]:
    """Per scene (the fit's own, at 256 spp, and the two of SCENES): (ours, Blender's importer, Cycles'
    noise) relative RMSE against three.js's render."""
    out = {}
    for name, scene in {"fit": fit.with_(spp=256), **SCENES}.items():
        ref = _views(three, "usd_preview_surface", source, scene)
        pair = []
        for params in (ours, theirs):
            a, b = (_views(cycles, "principled", params, scene.with_(seed=s)) for s in (11, 12))
            pair.append(((a + b) / 2, relative_rmse(a, b) / 2))
        out[name] = (relative_rmse(ref, pair[0][0]), relative_rmse(ref, pair[1][0]), pair[1][1])
    return out


def _views(adapter, model: str, params: dict, scene: ProbeScene) -> np.ndarray:
    """The scene's views, one render each (adapters render one view at a time), stacked as the fit's."""
    return np.concatenate([adapter.render(model, params, view) for view in scene.view_scenes()], axis=0)


def materials(stages: list[Path]):
    """(stage, variant label, prim name, entry) of every UsdPreviewSurface material."""
    for stage in stages:
        for e in UsdReader().read(stage):
            if e.material is None or e.material.model != "usd_preview_surface":
                continue
            m = re.fullmatch(r"(.*?)(?: \[(.+)\])?", e.name)
            yield stage, m.group(2) or "", m.group(1).rsplit("/", 1)[-1], e


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("stages", nargs="*", type=Path, default=[s for s in STAGES if s.is_file()])
    args = ap.parse_args()
    reg = registry()
    rows = []
    with open_adapters(reg, ["cycles", "threejs"]) as pool, tempfile.TemporaryDirectory() as tmp:
        cycles, three = pool["cycles"], pool["threejs"]
        principled, preview = cycles.models["principled"], three.models["usd_preview_surface"]
        seen: dict[str, str] = {}
        for i, (stage, label, prim, entry) in enumerate(materials(args.stages)):
            source = preview.complete(entry.material.params)
            same = seen.setdefault(json.dumps(source, sort_keys=True), entry.name)
            if same != entry.name:  # the shader ball's three examples as the stage opens: all defaults
                print(f"{entry.name}: the same inputs as {same}", flush=True)
                continue
            outcome = remap_once(reg, pool, entry.material, "cycles", "principled")
            r = outcome.report
            imported = blender_import(flattened(stage, label, Path(tmp) / f"s{i}.usda"), principled.inputs)
            theirs = principled.complete(imported[prim])
            fit = r.fit_scene.scene if r.fit_scene is not None else SCENES["probe"]
            errs = errors(cycles, three, source, principled.complete(r.params), theirs, fit)
            rows.append((f"{stage.stem}: {entry.name}", r, errs, theirs))
            print(f"{entry.name}: ours {r.metrics.relative_rmse:.2%} {r.verdict}; " + ", ".join(
                f"{k} {v[0]:.2%} / importer {v[1]:.2%} (noise {v[2]:.2%})" for k, v in errs.items()), flush=True)
    table(rows)
    return 0


def table(rows) -> None:
    print()
    print("| material | remap: fit error, verdict, renders, seconds | the fit's scene: remap / Blender's importer | "
          "probe: remap / importer | studio: remap / importer | Cycles' noise (probe, studio) | the importer made |")
    print("|---|---|---|---|---|---|---|")
    for name, r, e, p in rows:
        made = (f"base {_rgb(p['base_color'])}, metallic {p['metallic']:.3g}, roughness {p['roughness']:.3g}, "
                f"IOR {p['ior']:.3g}, specular tint {_rgb(p['specular_tint'])}"
                + (f", coat {p['coat_weight']:.3g}" if p["coat_weight"] else "")
                + (f", alpha {p['alpha']:.3g}" if p["alpha"] < 1 else ""))
        print(f"| {name} | {r.metrics.relative_rmse:.2%}, {r.verdict}, {r.renders}, {r.seconds:.1f} s | "
              f"{e['fit'][0]:.2%} / {e['fit'][1]:.2%} | {e['probe'][0]:.2%} / {e['probe'][1]:.2%} | {e['studio'][0]:.2%} / {e['studio'][1]:.2%} | "
              f"{e['probe'][2]:.2%}, {e['studio'][2]:.2%} | {made} |")


def _rgb(v) -> str:
    return "(" + ", ".join(f"{float(x):.3g}" for x in v) + ")"


if __name__ == "__main__":
    np.seterr(all="ignore")
    raise SystemExit(main())
