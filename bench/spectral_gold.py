"""A spectral gold read as Mitsuba reads it, and remapped to Cycles: the colour at each step.

    python bench/spectral_gold.py [--out DIR]

The gold of tests/data/scenes/spectral.xml (eta and k as 20 wavelength:value pairs each): the
reader's RGB against Mitsuba's own (`mi.traverse` after loading the file in `scalar_rgb`, in a
process of its own), against the reading before spectra were integrated (each spectrum's mean,
a grey); then `remap convert` to Cycles, and the source, the fitted Cycles material and the grey
reading rendered under the studio environment (256 spp, 128²): each sphere's mean colour and the
relative RMSE against the source."""

from __future__ import annotations

import argparse
import json
import re
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from brdfremap.core.data.metrics import relative_rmse
from brdfremap.core.host.plugins import collect_adapters
from brdfremap.core.data.scene import EnvironmentLight, ProbeScene
from brdfremap.core.testing import sphere_hits

ROOT = Path(__file__).resolve().parents[1]
FILE = ROOT / "tests" / "data" / "scenes" / "spectral.xml"
NAME = "spectral gold"
MITSUBA_READS = """
import json, sys, mitsuba as mi
mi.set_variant("scalar_rgb")
mi.set_log_level(mi.LogLevel.Error)  # Mitsuba logs to stdout, where the answer goes
p = mi.traverse(mi.load_file(sys.argv[1]))
print(json.dumps({k: [float(x) for x in p[f"{sys.argv[2]}.{k}.value"]] for k in ("eta", "k")}))
"""


def shown(v) -> str:
    return "(" + ", ".join(f"{x:.3f}" for x in v) + ")"


def grey_reading() -> dict:
    """What the reader gave before: each spectrum's mean, in every channel."""
    text = FILE.read_text()
    out = {}
    for name in ("eta", "k"):
        block = re.search(rf'id="{NAME}".*?name="{name}" value="([^"]+)"', text, re.S).group(1)
        vals = [float(p.split(":")[1]) for p in re.split(r"[,\s]+", block) if ":" in p]
        out[name] = (sum(vals) / len(vals),) * 3
    return out


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", help="keep the conversion here (default: a temporary folder)")
    args = p.parse_args()
    from brdfremap.core.library.formats import collect_formats, read_all

    entry = next(e for e in read_all([FILE], collect_formats()) if e.name == NAME)
    mine = {k: list(entry.material.params[k]) for k in ("eta", "k")}
    theirs = json.loads(subprocess.run([sys.executable, "-c", MITSUBA_READS, str(FILE), NAME], capture_output=True,
                                       text=True, check=True).stdout)
    grey = grey_reading()
    for k in ("eta", "k"):
        print(f"{k:<4} reader {shown(mine[k])}  Mitsuba scalar_rgb {shown(theirs[k])}  "
              f"largest difference {max(abs(a - b) for a, b in zip(mine[k], theirs[k])):.1e}  (before: {shown(grey[k])})")
    out = Path(args.out or tempfile.mkdtemp(prefix="spectral-gold-"))
    subprocess.run([sys.executable, "-m", "brdfremap.core.cli", "convert", str(FILE), "--only", NAME, "--to", "cycles",
                    "--out", str(out), "--quiet"], check=True)
    summary = json.loads((out / "convert.json").read_text())
    row = summary["materials"][0]
    fitted = json.loads((out / "materials" / row["slot"] / "result.json").read_text())
    print(f"remap to cycles:{row['model']}: {row['relative_rmse']:.2%}, verdict {row['status']}")
    reg = collect_adapters()
    mitsuba, cycles = reg.create("mitsuba"), reg.create("cycles")
    scene = ProbeScene(lights=[EnvironmentLight(type="environment", map="studio")], resolution=128, spp=256)
    inner = sphere_hits(scene).interior
    try:
        src_params = mitsuba.models["roughconductor"].complete(entry.material.params)
        source = mitsuba.render("roughconductor", src_params, scene)
        images = {"source (the spectral gold)": source,
                  f"Cycles {row['model']} fitted": cycles.render(row["model"], fitted["params"], scene),
                  "the grey reading (before)": mitsuba.render("roughconductor", {**src_params, **grey}, scene)}
    finally:
        mitsuba.close()
        cycles.close()
    print("under the studio environment, 256 spp, 128 px: each sphere's mean colour, and its difference from the source")
    for label, img in images.items():
        mean = img[inner].mean(axis=0)
        print(f"  {label:<30} mean RGB {shown(mean)}  relative RMSE {relative_rmse(source, img):.1%}")


if __name__ == "__main__":
    main()
