"""The materialx adapter's calibration: a white Lambertian (albedo 0.8) written in MaterialX (Standard
Surface, specular 0) against Mitsuba's and Cycles' and against the analytic radiance, box-filtered as a
pixel integrates it, under every light the verdicts judge by.

    python bench/materialx_calibration.py [--resolution 64] [--spp 1024]

The probe light, the held-out grazing, rim and head lights, the studio environment and the probe's disc.
Errors are relative RMSE over the whole image, the silhouette included."""

from __future__ import annotations

import argparse
import time

from common import open_adapters, registry

from brdfremap.core.data.metrics import relative_rmse
from brdfremap.core.data.scene import EnvironmentLight, PointLight, ProbeScene
from brdfremap.core.job.validation import CONDITIONS
from brdfremap.core.testing import analytic_lambert

WHITE = {"mitsuba": ("diffuse", {"reflectance": 0.8}), "cycles": ("diffuse", {"color": 0.8})}


def conditions() -> list[tuple[str, list]]:
    return [("probe", [PointLight()])] + [(c.label, list(c.lights)) for c in CONDITIONS] + [
        ("probe's disc", [EnvironmentLight(type="environment", map="probe-disc", scale=30 / 5.2 ** 2)])]


def analytic(scene: ProbeScene) -> object:
    k = 16 if scene.environment is None else 4  # an environment's irradiance costs a map per pixel
    n = scene.resolution
    return analytic_lambert(scene.overridden(resolution=n * k), 0.8).reshape(n, k, n, k, 3).mean(axis=(1, 3))


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--resolution", type=int, default=64)
    ap.add_argument("--spp", type=int, default=1024)
    args = ap.parse_args()
    reg = registry()
    print("| light | MaterialX vs analytic | vs Mitsuba | vs Cycles | Mitsuba vs Cycles | MaterialX s/render |")
    print("|---|---|---|---|---|---|")
    with open_adapters(reg, ["materialx", "mitsuba", "cycles"]) as pool:
        mx = pool["materialx"]
        white = mx.models[mx.calibration[0]].complete(mx.calibration[1])
        for name, lights in conditions():
            scene = ProbeScene(lights=lights, resolution=args.resolution, spp=args.spp)
            t0 = time.perf_counter()
            img = mx.render(mx.calibration[0], white, scene)
            seconds = time.perf_counter() - t0
            other = {n: pool[n].render(m, reg.get(n).models[m].complete(p), scene) for n, (m, p) in WHITE.items()}
            print(f"| {name} | {relative_rmse(analytic(scene), img):.2%} | {relative_rmse(other['mitsuba'], img):.2%} | "
                  f"{relative_rmse(other['cycles'], img):.2%} | {relative_rmse(other['mitsuba'], other['cycles']):.2%} | "
                  f"{seconds:.2f} |", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
