"""A renderer nobody can script, end to end: the probe exported, rendered outside the tool by scripts
that do not import it (Mitsuba loading the exported XML; Blender importing the exported USD and rendering
with Cycles), and each material fitted to Cycles' Principled BSDF from its images alone, beside the same
remap through the renderer's adapter. Prints one row a material and route: parameters, error, held-out
errors, verdict, seconds.

    python bench/images_outside.py OUT [--resolution 128] [--spp 64] [--only mitsuba|blender]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PY = sys.executable
MITSUBA = {  # the material as a Mitsuba user writes it, and the same as a material file of the tool
    "gold": ('<bsdf type="roughconductor" id="material"><string name="material" value="Au"/><string '
             'name="distribution" value="ggx"/><float name="alpha" value="0.2"/></bsdf>',
             {"adapter": "mitsuba", "model": "roughconductor", "params": {"material": "Au", "distribution": "ggx",
                                                                          "alpha": 0.2}}),
    "plastic": ('<bsdf type="roughplastic" id="material"><rgb name="diffuse_reflectance" value="0.1, 0.27, 0.36"/>'
                '<float name="alpha" value="0.1"/><string name="distribution" value="ggx"/></bsdf>',
                {"adapter": "mitsuba", "model": "roughplastic", "params": {
                    "diffuse_reflectance": [0.1, 0.27, 0.36], "alpha": 0.1, "distribution": "ggx"}}),
    "coated paint": ('<bsdf type="principled" id="material"><rgb name="base_color" value="0.6, 0.05, 0.05"/>'
                     '<float name="roughness" value="0.5"/><float name="clearcoat" value="1"/>'
                     '<float name="clearcoat_gloss" value="0.9"/></bsdf>',
                     {"adapter": "mitsuba", "model": "principled", "params": {
                         "base_color": [0.6, 0.05, 0.05], "roughness": 0.5, "clearcoat": 1.0,
                         "clearcoat_gloss": 0.9}}),
}
BLENDER = {  # a Principled BSDF by Blender's socket names, and the same as a material file of the tool
    "gold": ({"Base Color": [0.944, 0.776, 0.373], "Metallic": 1.0, "Roughness": 0.3},
             {"base_color": [0.944, 0.776, 0.373], "metallic": 1.0, "roughness": 0.3}),
    "plastic": ({"Base Color": [0.1, 0.27, 0.36], "Roughness": 0.25},
                {"base_color": [0.1, 0.27, 0.36], "roughness": 0.25}),
    "coated paint": ({"Base Color": [0.6, 0.05, 0.05], "Roughness": 0.5, "Coat Weight": 1.0, "Coat Roughness": 0.05},
                     {"base_color": [0.6, 0.05, 0.05], "roughness": 0.5, "coat_weight": 1.0, "coat_roughness": 0.05}),
}
SHOWN = ("base_color", "metallic", "roughness", "coat_weight", "coat_roughness", "specular_ior_level")


def run(cmd: list[str]) -> float:
    t0 = time.perf_counter()
    done = subprocess.run(cmd, capture_output=True, text=True)
    if done.returncode not in (0, 3):
        raise SystemExit(f"{' '.join(cmd)}\n{done.stderr[-3000:]}")
    return time.perf_counter() - t0


def render_mitsuba(export: Path, out: Path, material: str | None) -> float:
    args = [PY, str(ROOT / "examples/outside/render_mitsuba.py"), str(export / "mitsuba"), str(out)]
    if material:
        f = export / f"{out.name}.xml"
        f.write_text(f'<scene version="3.0.0">{material}</scene>')
        args += ["--material", str(f)]
    return run(args)


def render_blender(export: Path, out: Path, inputs: dict | None) -> float:
    out.mkdir(parents=True, exist_ok=True)
    extra = []
    if inputs is not None:
        f = export / f"{out.name}.json"
        f.write_text(json.dumps(inputs))
        extra = ["--material", str(f)]
    seconds = 0.0
    for scene in sorted((export / "usd").glob("*.usda")):
        if inputs is not None and scene.stem == "bright":
            continue
        for seed in (0, 1):
            seconds += run([PY, str(ROOT / "examples/outside/render_usd_blender.py"), str(scene),
                            str(out / f"{scene.stem}.seed{seed}.exr"), "--seed", str(seed), *extra])
    return seconds


def remap(args: list[str], out: Path) -> dict:
    seconds = run([PY, "-m", "brdfremap.core.cli", *args, "--adapter", "cycles", "--model", "principled",
                   "--out", str(out), "--quiet", "--force"])
    report = json.loads((out / "result.json").read_text())
    report["wall"] = seconds
    return report


def row(route: str, name: str, r: dict) -> str:
    p = r["params"]
    shown = " ".join(f"{k}={json.dumps(p[k])}" for k in SHOWN if k in p)
    held = ", ".join(f"{c['condition']} {c['error']:.1%}" for c in r["validation"])
    return (f"{name:13s} {route:22s} {r['metrics']['relative_rmse']:.2%}  [{held}]  {r['verdict']}  "
            f"{r['wall']:.0f} s\n    {shown}")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("out", type=Path)
    ap.add_argument("--resolution", type=int, default=128)
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--only", choices=("mitsuba", "blender"))
    a = ap.parse_args()
    export = a.out / "export"
    run([PY, "-m", "brdfremap.core.cli", "scene", "export", str(export), "--resolution", str(a.resolution),
         "--spp", str(a.spp)])
    rows = []
    if a.only in (None, "mitsuba"):
        m = export / "mitsuba-renders"
        m.mkdir(parents=True, exist_ok=True)
        (m / "scenes.json").write_text((export / "scenes.json").read_text())
        t = render_mitsuba(export, m / "calibration", None)
        print(f"mitsuba calibration rendered outside: {t:.1f} s", flush=True)
        for name, (xml, material) in MITSUBA.items():
            t = render_mitsuba(export, m / name, xml)
            (a.out / f"{name}.yaml").write_text(json.dumps(material))
            rows.append(row("mitsuba images", name, remap(["--source-images", str(m / name)], a.out / "mi" / name)))
            rows.append(row("mitsuba adapter", name, remap(["--source", str(a.out / f"{name}.yaml"), "--spp",
                                                            str(a.spp)], a.out / "ma" / name)))
            print(rows[-2] + "\n" + rows[-1], flush=True)
    if a.only in (None, "blender"):
        b = export / "blender-renders"
        b.mkdir(parents=True, exist_ok=True)
        (b / "scenes.json").write_text((export / "scenes.json").read_text())
        t = render_blender(export, b / "calibration", None)
        print(f"blender calibration rendered outside from the USD: {t:.1f} s", flush=True)
        for name, (inputs, params) in BLENDER.items():
            render_blender(export, b / name, inputs)
            (a.out / f"{name}-cycles.yaml").write_text(json.dumps({"adapter": "cycles", "model": "principled",
                                                                  "params": params}))
            rows.append(row("blender usd images", name, remap(["--source-images", str(b / name)], a.out / "bi" / name)))
            rows.append(row("cycles adapter (fit)", name, remap(["--source", str(a.out / f"{name}-cycles.yaml"),
                                                                 "--spp", str(a.spp), "--fit-same-model"],
                                                                a.out / "ba" / name)))
            print(rows[-2] + "\n" + rows[-1] + f"\n    truth: {json.dumps(params)}", flush=True)
    print("\n".join(rows))


if __name__ == "__main__":
    main()
