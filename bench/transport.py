"""Light transport of a transmissive sphere, Mitsuba against Cycles (and a smooth glass against
its analytic image): a smooth and a rough clear glass of IOR 1.5 (each adapter's `glasses`), and
a white Lambertian as the control, under the probe's point light and the studio environment.

    python bench/transport.py [--resolution 128] [--spp 128] [--out docs/measurements/transport.md]

Each material is rendered twice per renderer (two seeds); the noise floor of a comparison is the
renderers' own noise added in quadrature, and "beyond" is the part of the error it does not
explain (`metrics.beyond_noise`). A rough glass under a point light is lit through the sphere by
rare paths (a few bright samples): its images are also compared in 8 x 8 pixel blocks, where the
noise averages out and a difference in light transport does not. Environments at four times the
samples."""

from __future__ import annotations

import argparse
import time

import numpy as np
from brdfremap.core.data.metrics import beyond_noise, relative_rmse
from brdfremap.core.host.plugins import collect_adapters
from brdfremap.core.data.scene import EnvironmentLight, PointLight, ProbeScene
from brdfremap.core.testing import analytic_glass, sphere_hits

LIGHTS = {"probe (point light)": [PointLight()],
          "studio environment": [EnvironmentLight(type="environment", map="studio")]}
BLOCK = 8


def blocks(img: np.ndarray, k: int = BLOCK) -> np.ndarray:
    n = img.shape[0] // k * k
    return img[:n, :n].reshape(n // k, k, n // k, k, 3).mean(axis=(1, 3))


def pair(a, model: str, given: dict, scene: ProbeScene) -> tuple[np.ndarray, np.ndarray, float]:
    params = a.models[model].complete(given)
    t0 = time.perf_counter()
    first = a.render(model, params, scene)
    secs = time.perf_counter() - t0
    return first.astype(np.float64), a.render(model, params, scene.with_(seed=scene.seed + 1)).astype(np.float64), secs


def compare(x: tuple, y: tuple, view=lambda i: i) -> tuple[float, float]:
    """(error, noise floor) of the means of two render pairs."""
    mx, my = view((x[0] + x[1]) / 2), view((y[0] + y[1]) / 2)
    nx, ny = relative_rmse(view(x[0]), view(x[1])) / 2, relative_rmse(view(y[0]), view(y[1])) / 2
    return relative_rmse(mx, my), float(np.hypot(nx, ny))


def row(name: str, light: str, err: float, floor: float, extra: str = "") -> str:
    return f"| {name} | {light} | {err:.2%} | {floor:.2%} | {beyond_noise(err, floor):.2%} | {extra} |"


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--resolution", type=int, default=128)
    p.add_argument("--spp", type=int, default=128)
    p.add_argument("--out", help="also write the table (markdown) here")
    args = p.parse_args()
    reg = collect_adapters()
    adapters = {n: reg.create(n) for n in ("mitsuba", "cycles")}
    rows = ["| material | light | error | noise floor | beyond the noise | notes |", "|---|---|---|---|---|---|"]
    try:
        kinds = [("white Lambertian", {n: a.calibration for n, a in adapters.items()})]
        kinds += [(f"{k} glass (IOR 1.5)", {n: a.glasses[k] for n, a in adapters.items()}) for k in ("smooth", "rough")]
        for name, materials in kinds:
            for light, ls in LIGHTS.items():
                env = any(isinstance(x, EnvironmentLight) for x in ls)
                scene = ProbeScene(lights=ls, resolution=args.resolution, spp=args.spp * (4 if env else 1))
                got = {n: pair(a, *materials[n], scene) for n, a in adapters.items()}
                secs = f"s/render Mitsuba {got['mitsuba'][2]:.2f}, Cycles {got['cycles'][2]:.2f}"
                rows.append(row(f"{name}: Cycles vs Mitsuba", light, *compare(got["mitsuba"], got["cycles"]), secs))
                if name.startswith("rough"):
                    rows.append(row(f"{name}: Cycles vs Mitsuba, {BLOCK}x{BLOCK} blocks", light,
                                    *compare(got["mitsuba"], got["cycles"], blocks)))
                if name.startswith("smooth") and env:
                    inner = sphere_hits(scene).interior
                    exact = analytic_glass(scene, 1.5, supersample=6)[inner].astype(np.float64)
                    for n in adapters:
                        img = got[n]
                        rows.append(row(f"{name}: {n} vs analytic", light, relative_rmse(exact, (img[0] + img[1])[inner] / 2),
                                        relative_rmse(img[0][inner], img[1][inner]) / 2, "interior pixels"))
                for r in rows[-(1 + 2 * (name.startswith("smooth") and env) + name.startswith("rough")):]:
                    print(r, flush=True)
    finally:
        for a in adapters.values():
            a.close()
    if args.out:
        with open(args.out, "w") as f:
            f.write("\n".join(rows) + "\n")


if __name__ == "__main__":
    main()
