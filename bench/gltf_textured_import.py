"""A textured glTF material into Cycles: this tool's texel-by-texel remap against Blender's glTF importer.

    python bench/gltf_textured_import.py [FILE.glb] [--table TABLE] [--out DIR]

The first material of FILE (its base colour and metallic-roughness textures; without FILE, a
Principled BSDF of the demo's worn-copper colour and roughness images, metallic 1, exported by
Blender's own glTF exporter into DIR) is remapped to Cycles' Principled BSDF through TABLE (the
shipped glTF table unless given; `remap convert`, stored in DIR: a rerun reuses it). Then, on the probe
sphere under the textured check's two conditions (the scene's light; the studio environment):

- the glTF material, textured, rendered by three.js: the source, as a glTF viewer shows it;
- the remap's maps, textured, rendered by Cycles;
- the glTF's own maps and factors as the Principled BSDF's inputs, rendered by Cycles: what Blender's
  glTF importer builds (the base colour, roughness and metallic images as they are; IOR 1.5 and
  Specular IOR Level 0.5, glTF's F0 of 0.04).

Prints each Cycles image's error against three.js's, and Cycles' noise (two seeds)."""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
from common import ROOT, open_adapters, registry

from brdfremap.adapters.threejs.library import GltfReader
from brdfremap.core.data.metrics import relative_rmse
from brdfremap.core.data.scene import EnvironmentLight, ProbeScene
from brdfremap.core.data.textures import Texture, TextureMap, read_values

EXPORT = ROOT / "tests" / "data" / "gltf" / "export_worn_copper.py"
"""Blender's own glTF export of a textured Principled BSDF (a script run with bpy)."""
SCENES = {"scene's light": ProbeScene(resolution=128, spp=256),
          "studio": ProbeScene(lights=[EnvironmentLight(type="environment", map="studio")], resolution=64, spp=1024)}


def remapped(glb: Path, table: Path, out: Path) -> tuple[dict, dict[str, TextureMap]]:
    """The remap's Principled parameters and its maps (as written beside its result)."""
    subprocess.run([sys.executable, "-m", "brdfremap.core.cli", "convert", str(glb), "--to", "cycles:principled",
                    "--table", str(table), "--out", str(out), "--quiet"], check=True)
    row = json.loads((out / "convert.json").read_text())["materials"][0]
    folder = out / "materials" / row["slot"]
    result = json.loads((folder / "result.json").read_text())
    maps = {}
    for m in result["textures"]["maps"]:
        tex = Texture(file=str(folder / m["file"]), colorspace=m["colorspace"])
        maps[m["param"]] = TextureMap(read_values(tex, "rgb" if m["param"] == "base_color" else "scalar"))
    return result["textures"]["values"], maps


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("glb", type=Path, nargs="?")
    ap.add_argument("--table", type=Path, default=ROOT / "configs" / "tables" / "built" /
                    "threejs-gltf-to-cycles-principled.json")
    ap.add_argument("--out", type=Path, default=ROOT / "out" / "bench-gltf-import")
    args = ap.parse_args()
    if args.glb is None:
        args.out.mkdir(parents=True, exist_ok=True)
        args.glb = args.out / "worn-copper.glb"
        subprocess.run([sys.executable, str(EXPORT), str(ROOT / "examples" / "library" / "textures"), str(args.glb)],
                       check=True, capture_output=True)
    entry = GltfReader().read(args.glb)[0]
    src = entry.material
    kinds = {"base_color": "rgb", "roughness": "scalar", "metallic": "scalar"}
    given = {k: TextureMap(read_values(t, kinds[k]), t.filter) for k, t in src.textures.items()}
    ours, our_maps = remapped(args.glb, args.table, args.out / "remap")
    imported = {"base_color": src.params.get("base_color", (1.0, 1.0, 1.0)), "metallic": src.params.get("metallic", 1.0),
                "roughness": src.params.get("roughness", 1.0), "ior": 1.5, "specular_ior_level": 0.5}
    print(f"{entry.name}: textures {', '.join(sorted(given))}, {next(iter(given.values())).values.shape[1]} x "
          f"{next(iter(given.values())).values.shape[0]}")
    with open_adapters(registry(), ["cycles", "threejs"]) as pool:
        cycles, three = pool["cycles"], pool["threejs"]
        for name, scene in SCENES.items():
            ref = three.render_textured("gltf_pbr", src.params, given, scene)
            row = []
            for params, maps in ((ours, our_maps), (imported, given)):
                p = cycles.models["principled"].complete(params)
                a, b = (cycles.render_textured("principled", p, maps, scene.with_(seed=s)) for s in (11, 12))
                row.append((relative_rmse(ref, (a + b) / 2), relative_rmse(a, b) / 2))
            print(f"{name}: remap {row[0][0]:.2%}, Blender's importer {row[1][0]:.2%} (Cycles' noise {row[0][1]:.2%})",
                  flush=True)
    return 0


if __name__ == "__main__":
    np.seterr(all="ignore")
    raise SystemExit(main())
