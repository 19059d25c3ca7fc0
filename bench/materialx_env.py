"""MaterialX's environment lighting as the materialx adapter renders it: how far its filtered importance
sampling is from converged at the samples and map width the adapter uses, and what a render costs.

    python bench/materialx_env.py [--resolution 32] [--roughness 0.5 0.3 0.15 0.05]

An OpenPBR copper at each roughness under the studio and under the probe's disc, rendered by MaterialX's
GLSL with (samples, map width, supersampling) set as the adapter's constants, against MaterialX's own
image at 1024 samples from the full 512-column map (the reference, 8 to 40 times the cost). Prints the
relative RMSE and seconds per render of each setting, the adapter's in bold."""

from __future__ import annotations

import argparse
import time

import brdfremap.adapters.materialx.adapter as mxa
from brdfremap.core.data.metrics import relative_rmse
from brdfremap.core.data.scene import EnvironmentLight, ProbeScene

LIGHTS = {"studio": EnvironmentLight(type="environment", map="studio"),
          "probe disc": EnvironmentLight(type="environment", map="probe-disc", scale=30 / 5.2 ** 2)}
SETTINGS = ((64, 256), (256, 256), (128, 256), (256, 128))
"""(samples, map width) tried; the reference is (1024, 512)."""


def render(adapter, params: dict, scene: ProbeScene, samples: int, width: int) -> tuple:
    mxa.ENV_SAMPLES, mxa.ENV_WIDTH = samples, width
    adapter._images.clear()
    adapter._maps.clear()
    model = adapter.models["open_pbr_surface"]
    t0 = time.perf_counter()
    img = adapter.render(model, model.complete(params), scene)
    return img, time.perf_counter() - t0


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--resolution", type=int, default=32)
    ap.add_argument("--roughness", type=float, nargs="*", default=[0.5, 0.3, 0.15, 0.05])
    args = ap.parse_args()
    adapter = mxa.MaterialXAdapter()
    mine = (mxa.ENV_SAMPLES, mxa.ENV_WIDTH)
    print(f"supersampling {mxa.ENV_SUPERSAMPLE}² a pixel, {args.resolution} px; the adapter's setting: "
          f"{mine[0]} samples, map {mine[1]} columns")
    print("| light | roughness | reference | " + " | ".join(f"{s} samples, {w} columns" for s, w in SETTINGS) + " |")
    print("|---|---|---|" + "---|" * len(SETTINGS))
    try:
        for name, light in LIGHTS.items():
            scene = ProbeScene(lights=[light], resolution=args.resolution)
            for r in args.roughness:
                params = {"base_color": (0.95, 0.64, 0.54), "base_metalness": 1.0, "specular_roughness": r}
                ref, t_ref = render(adapter, params, scene, 1024, 512)
                cells = []
                for samples, width in SETTINGS:
                    img, t = render(adapter, params, scene, samples, width)
                    cell = f"{relative_rmse(img, ref):.2%}, {t:.1f} s"
                    cells.append(f"**{cell}**" if (samples, width) == mine else cell)
                print(f"| {name} | {r:g} | {t_ref:.1f} s | " + " | ".join(cells) + " |", flush=True)
    finally:
        adapter.close()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
