"""Calibration of every light type in both renderers: a white Lambertian (albedo 0.8) against the
analytic radiance (`core.testing.analytic_lambert`) and Mitsuba against Cycles.

    python bench/lights.py [--resolution 128] [--spp 256] [--out docs/measurements/lights.md]

Each light of the held-out validation set (`core.job.validation`) and the probe's own, two point
lights at once, a constant environment and the built-in studio are rendered at the given
samples (environments at four times as many). Errors are relative RMSE over the pixels whose
whole footprint is on the sphere (a renderer box-filters the silhouette, the analytic image does
not). A second seed measures each renderer's own noise, so a bias shows as the error beyond it."""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
from brdfremap.core.data.metrics import relative_rmse
from brdfremap.core.host.plugins import collect_adapters
from brdfremap.core.data.scene import EnvironmentLight, PointLight, ProbeScene
from brdfremap.core.testing import analytic_lambert, sphere_hits
from brdfremap.core.job.validation import CONDITIONS, place_disc

WHITE = {"mitsuba": ("diffuse", {"reflectance": 0.8}), "cycles": ("diffuse", {"color": 0.8})}


def lights() -> list[tuple[str, list]]:
    out = [("probe (point, 45 degrees)", [PointLight()])]
    out += [(f"{c.label} (validation)", list(c.lights)) for c in CONDITIONS if c.disc]
    probe = ProbeScene()
    out += [(f"{d.label} (validation, for sharp materials)", [place_disc(d.lights[0], probe)])
            for d in (c.as_disc() for c in CONDITIONS if c.disc)]
    out += [("two point lights (45 and 100 degrees)", [PointLight(), PointLight(theta=100.0, phi=10.0, intensity=15.0)]),
            ("constant environment (radiance 0.35)", [EnvironmentLight(type="environment", map="constant", scale=0.35)]),
            ("studio environment (validation)", [EnvironmentLight(type="environment", map="studio")])]
    return out


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--resolution", type=int, default=128)
    p.add_argument("--spp", type=int, default=256)
    p.add_argument("--out", help="also write the table (markdown) here")
    args = p.parse_args()
    reg = collect_adapters()
    adapters = {n: reg.create(n) for n in WHITE}
    rows = ["| light | Mitsuba vs analytic | (its noise) | Cycles vs analytic | (its noise) | Cycles vs Mitsuba | seconds M / C |",
            "|---|---|---|---|---|---|---|"]
    try:
        for name, ls in lights():
            env = any(isinstance(x, EnvironmentLight) for x in ls)  # discs too: Cycles samples them as a world
            scene = ProbeScene(lights=ls, resolution=args.resolution, spp=args.spp * (4 if env else 1))
            inner = sphere_hits(scene).interior
            ref = analytic_lambert(scene, 0.8)[inner]
            img, noise, secs = {}, {}, {}
            for n, a in adapters.items():
                model, given = WHITE[n]
                params = a.models[model].complete(given)
                t0 = time.perf_counter()
                img[n] = a.render(model, params, scene)[inner]
                secs[n] = time.perf_counter() - t0
                noise[n] = relative_rmse(img[n], a.render(model, params, scene.with_(seed=1))[inner]) / np.sqrt(2)
            m, c = img["mitsuba"], img["cycles"]
            rows.append(f"| {name} | {relative_rmse(ref, m):.2%} | {noise['mitsuba']:.2%} | {relative_rmse(ref, c):.2%} "
                        f"| {noise['cycles']:.2%} | {relative_rmse(m, c):.2%} | {secs['mitsuba']:.2f} / "
                        f"{secs['cycles']:.2f} |")
            print(rows[-1], flush=True)
    finally:
        for a in adapters.values():
            a.close()
    head = (f"White Lambertian (albedo 0.8), {args.resolution}x{args.resolution}, {args.spp} spp "
            f"({4 * args.spp} for environments), interior pixels; `python bench/lights.py`.\n")
    text = head + "\n" + "\n".join(rows) + "\n"
    print(text)
    if args.out:
        Path(args.out).write_text(text)
        print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
