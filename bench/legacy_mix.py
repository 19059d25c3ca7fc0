"""Blender's legacy materials (a Mix Shader of a Diffuse and a Glossy BSDF, its factor a Fresnel, a Layer
Weight or a constant) remapped to the Principled BSDF, each rendered by Cycles as the file holds it: the
fit's error under the probe and the studio beside what Blender's own conversion gives (its glTF exporter,
the only one it has, which writes such a material as a Principled BSDF's values; the glTF read back as
Principled and rendered the same way).

    python bench/legacy_mix.py [--out OUT] [--resolution 64] [--spp 64]

Renders: the conversion's (`remap convert`), then per material the source, the fit and the exporter's
Principled under the probe and the studio (six more renders)."""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import textwrap
from pathlib import Path

from common import ROOT

MAKE = textwrap.dedent('''
    import sys, bpy
    bpy.ops.wm.read_factory_settings(use_empty=True)
    def mix(name, factor):
        m = bpy.data.materials.new(name); m.use_nodes = True; m.use_fake_user = True
        t = m.node_tree
        for n in list(t.nodes):
            if n.type != "OUTPUT_MATERIAL": t.nodes.remove(n)
        out = next(n for n in t.nodes if n.type == "OUTPUT_MATERIAL")
        d = t.nodes.new("ShaderNodeBsdfDiffuse"); d.inputs["Color"].default_value = (0.5, 0.12, 0.05, 1)
        g = t.nodes.new("ShaderNodeBsdfAnisotropic"); g.inputs["Roughness"].default_value = 0.25
        mx = t.nodes.new("ShaderNodeMixShader")
        t.links.new(d.outputs[0], mx.inputs[1]); t.links.new(g.outputs[0], mx.inputs[2])
        t.links.new(mx.outputs[0], out.inputs["Surface"])
        if isinstance(factor, float):
            mx.inputs[0].default_value = factor
        elif factor == "fresnel":
            f = t.nodes.new("ShaderNodeFresnel"); f.inputs["IOR"].default_value = 1.45
            t.links.new(f.outputs[0], mx.inputs[0])
        else:
            lw = t.nodes.new("ShaderNodeLayerWeight"); lw.inputs["Blend"].default_value = 0.3
            t.links.new(lw.outputs[factor], mx.inputs[0])
        bpy.ops.mesh.primitive_uv_sphere_add(); bpy.context.object.data.materials.append(m)
        bpy.context.object.name = name
    mix("fresnel 1.45", "fresnel"); mix("layer weight fresnel", "Fresnel"); mix("layer weight facing", "Facing")
    mix("constant 0.2", 0.2)
    bpy.ops.wm.save_as_mainfile(filepath=sys.argv[-2])
    bpy.ops.export_scene.gltf(filepath=sys.argv[-1], export_format="GLTF_SEPARATE")
''')


def exporter_principled(gltf: Path) -> dict[str, dict]:
    """Each material as Blender's glTF exporter wrote it, as Principled values (linear base colour,
    metallic, roughness; what the importer would make)."""
    doc = json.loads(gltf.read_text())
    out = {}
    for m in doc.get("materials", []):
        pbr = m.get("pbrMetallicRoughness", {})
        out[m["name"]] = {"base_color": tuple(pbr.get("baseColorFactor", [1, 1, 1, 1])[:3]),
                          "metallic": float(pbr.get("metallicFactor", 1.0)),
                          "roughness": float(pbr.get("roughnessFactor", 1.0))}
    return out


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=ROOT / "out" / "legacy-mix")
    ap.add_argument("--resolution", type=int, default=64)
    ap.add_argument("--spp", type=int, default=64)
    args = ap.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    blend, gltf = args.out / "legacy.blend", args.out / "legacy.gltf"
    made = subprocess.run([sys.executable, "-c", MAKE, str(blend), str(gltf)], capture_output=True, text=True)
    if made.returncode != 0:
        raise SystemExit(made.stderr[-2000:])
    conv = args.out / "converted"
    subprocess.run([sys.executable, "-m", "brdfremap.core.cli", "convert", str(blend), "--to", "cycles:principled",
                    "--out", str(conv), "--resolution", str(args.resolution), "--quiet"], check=False)
    from brdfremap.adapters.cycles.adapter import CyclesAdapter
    from brdfremap.adapters.cycles.library import BlendReader
    from brdfremap.core.data.metrics import relative_rmse
    from brdfremap.core.data.scene import EnvironmentLight, ProbeScene

    rows = {m["name"]: m for m in json.loads((conv / "convert.json").read_text())["materials"]}
    exported = exporter_principled(gltf)
    entries = {e.name: e for e in BlendReader().read(blend)}
    probe = ProbeScene().with_(resolution=args.resolution, spp=args.spp)
    studio = probe.model_copy(update={"lights": [EnvironmentLight(type="environment", map="studio")]})
    model = CyclesAdapter.models["principled"]
    print("| material | verdict | fit: probe / studio | Blender's glTF exporter: probe / studio | exporter's values |")
    print("|---|---|---|---|---|")
    with CyclesAdapter() as cy:
        for name, e in entries.items():
            fitted = json.loads((conv / "materials" / rows[name]["slot"] / "result.json").read_text())["params"]
            fitted = model.complete({k: tuple(v) if isinstance(v, list) else v for k, v in fitted.items()})
            ex = model.complete(exported.get(name, {}))
            errs = []
            for params in (fitted, ex):
                errs.append(tuple(relative_rmse(cy.render_native(e.material.native, sc), cy.render(model, params, sc))
                                  for sc in (probe, studio)))
            shown = ", ".join(f"{k} {v}" for k, v in exported.get(name, {}).items())
            print(f"| {name} | {rows[name]['status']} | {errs[0][0]:.1%} / {errs[0][1]:.1%} | "
                  f"{errs[1][0]:.1%} / {errs[1][1]:.1%} | {shown or 'not exported'} |")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
