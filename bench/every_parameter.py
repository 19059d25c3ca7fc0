"""Issue 20's round trips: materials that use the Principled BSDF's coat, sheen, anisotropy and
transmission, authored for Cycles, remapped to Mitsuba's principled and back; and Mitsuba's
anisotropic roughconductor to Cycles' Principled BSDF.

    python bench/every_parameter.py [--out DIR] [--only NAME] [--validate held-out|none]

Each step is a `remap` run as a user runs it; the back step's source is the forward step's
fitted material. Prints, per step: error, noise floor, renders, seconds, verdict, and the
parameters that carry the layer (coat, sheen, anisotropy, transmission)."""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples" / "every_parameter"
ROUND_TRIPS = ("coat_copper", "car_paint", "brushed_al", "sheen_fabric", "glass")
ONE_WAY = {"al_aniso": ("cycles", "principled"), "brushed_al": ("mitsuba", "roughconductor")}
"""Mitsuba's anisotropic roughconductor to Cycles; and the brushed aluminium, whose quarter-turn
rotation Mitsuba's principled cannot express (it has no rotation), to the anisotropic
roughconductor, which can (alpha_u and alpha_v swapped)."""
SHOWN = ("metallic", "roughness", "anisotropic", "anisotropic_rotation", "coat_weight", "coat_roughness", "clearcoat",
         "clearcoat_gloss", "sheen_weight", "sheen", "transmission_weight", "spec_trans", "specular",
         "specular_ior_level", "alpha_u", "alpha_v")


def remap(source: Path, adapter: str, model: str, out: Path, validate: str) -> dict:
    cmd = [sys.executable, "-m", "brdfremap.core.cli", "--adapter", adapter, "--model", model, "--source",
           str(source), "--out", str(out), "--quiet", "--validate", validate]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode not in (0, 1) or not (out / "result.json").exists():
        raise SystemExit(f"{' '.join(cmd)}\n{proc.stderr}")
    return json.loads((out / "result.json").read_text())


def as_source(result: dict, path: Path) -> Path:
    """A fitted result as a material file, for the next step."""
    t = result["target"]
    path.write_text(yaml.safe_dump({"adapter": t["adapter"], "model": t["model"], "params": result["params"]}))
    return path


def row(name: str, step: str, r: dict) -> str:
    m = r["metrics"]
    shown = {k: v for k, v in r["params"].items() if k in SHOWN}
    vals = ", ".join(f"{k}={v:.3g}" for k, v in shown.items() if isinstance(v, (int, float)))
    return (f"| {name} | {step} | {m['relative_rmse']:.1%} | {m['noise_floor']:.1%} | {r['renders']} | "
            f"{r['seconds']:.0f} | {r['verdict']} | {vals} |")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=ROOT / "out" / "every_parameter")
    ap.add_argument("--only", default="")
    ap.add_argument("--validate", default="held-out", choices=("held-out", "none"))
    args = ap.parse_args()
    print("| material | step | error | noise floor | renders | s | verdict | layer parameters |")
    print("|---|---|---|---|---|---|---|---|")
    for name in ROUND_TRIPS:
        if args.only and name != args.only:
            continue
        src = EXAMPLES / f"{name}.yaml"
        fwd = remap(src, "mitsuba", "principled", args.out / name / "to_mitsuba", args.validate)
        print(row(name, "Cycles → Mitsuba principled", fwd), flush=True)
        back_src = as_source(fwd, args.out / name / "mitsuba.yaml")
        back = remap(back_src, "cycles", "principled", args.out / name / "back_to_cycles", args.validate)
        print(row(name, "→ back to Cycles Principled", back), flush=True)
    for name, (adapter, model) in ONE_WAY.items():
        if args.only and name != args.only:
            continue
        r = remap(EXAMPLES / f"{name}.yaml", adapter, model, args.out / name / f"to_{adapter}_{model}", args.validate)
        src = yaml.safe_load((EXAMPLES / f"{name}.yaml").read_text())["adapter"]
        print(row(name, f"{src} → {adapter} {model}", r), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
