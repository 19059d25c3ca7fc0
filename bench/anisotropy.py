"""The anisotropy probe (issue 20): the tangent frame's axes across renderers, the Cycles mesh probe
against the exact sphere, and what the mesh costs; and the cross-process determinism of Mitsuba's
coated principled, which a fit along a flat direction amplifies.

    python bench/anisotropy.py

Prints figures only (no assertion): relative RMSE, seconds, max pixel difference."""

from __future__ import annotations

import subprocess
import sys
import time

import numpy as np

from brdfremap.core.data.appearance import anisotropy_from_alphas
from brdfremap.core.data.metrics import relative_rmse
from brdfremap.core.host.plugins import collect_adapters
from brdfremap.core.data.scene import PointLight, ProbeScene

COATED = {"base_color": [0.9, 0.6, 0.5], "metallic": 0.95, "clearcoat": 0.99, "clearcoat_gloss": 0.999}


def axes(m, c) -> None:
    sc = ProbeScene(resolution=128, spp=64)
    src = m.render("roughconductor", m.models["roughconductor"].complete(
        {"distribution": "ggx", "material": "Al", "anisotropy": "anisotropic", "alpha_u": 0.05, "alpha_v": 0.3}), sc)
    alpha, aniso, _ = anisotropy_from_alphas(0.3, 0.05)
    for rot in (0.0, 0.25):
        p = c.models["principled"].complete({"distribution": "ggx", "base_color": [0.91, 0.92, 0.92], "metallic": 1.0,
                                             "roughness": alpha ** 0.5, "anisotropic": aniso,
                                             "anisotropic_rotation": rot})
        print(f"Mitsuba alpha_u 0.05 / alpha_v 0.3 against Cycles anisotropic {aniso:.3f} rotation {rot}: "
              f"{relative_rmse(src, c.render('principled', p, sc)):.2%}")


def mesh_against_point(c) -> None:
    sc = ProbeScene(resolution=128, spp=256)
    for name, given in (("metal r 0.2", {"metallic": 1.0, "roughness": 0.2}),
                        ("dielectric r 0.5", {"metallic": 0.0, "roughness": 0.5})):
        p = c.models["principled"].complete(given)
        point = c.render("principled", p, sc)
        other = c.render("principled", p, sc.with_(seed=sc.seed + 1))
        mesh = c.render("principled", {**p, "anisotropic": 1e-9}, sc)  # any anisotropy: the mesh probe
        print(f"{name}: mesh against point {relative_rmse(point, mesh):.3%}, point seed to seed "
              f"{relative_rmse(point, other):.3%} (128², 256 spp)")


def timing(c) -> None:
    p = c.models["principled"].complete({})
    for i in range(2):
        sc = ProbeScene(resolution=128, spp=128, lights=[PointLight(theta=30 + 10 * i)])
        t = time.perf_counter()
        c.render("principled", p, sc)
        new = time.perf_counter() - t
        t = time.perf_counter()
        c.render("principled", {**p, "roughness": 0.31}, sc)
        point = time.perf_counter() - t
        t = time.perf_counter()
        c.render("principled", {**p, "anisotropic": 0.5}, sc)
        first_mesh = time.perf_counter() - t
        t = time.perf_counter()
        c.render("principled", {**p, "anisotropic": 0.6}, sc)
        mesh = time.perf_counter() - t
        print(f"Cycles 128², 128 spp: new scene {new:.2f} s, point {point:.2f} s, first mesh render {first_mesh:.2f} s, "
              f"mesh {mesh:.2f} s (mesh / point {mesh / point:.2f})")


def coated_once(path: str) -> None:
    m = collect_adapters().create("mitsuba")
    np.save(path, m.render("principled", m.models["principled"].complete(COATED), ProbeScene(resolution=64, spp=128)))


def determinism() -> None:
    import tempfile
    from pathlib import Path

    with tempfile.TemporaryDirectory() as d:
        paths = [str(Path(d) / f"{i}.npy") for i in range(2)]
        for p in paths:
            subprocess.run([sys.executable, __file__, "--coated", p], check=True, capture_output=True)
        a, b = (np.load(p) for p in paths)
    print(f"Mitsuba principled, clearcoat 0.99, two processes: max pixel difference {np.abs(a - b).max():.3g}")


def main() -> int:
    if len(sys.argv) == 3 and sys.argv[1] == "--coated":
        coated_once(sys.argv[2])
        return 0
    reg = collect_adapters()
    m, c = reg.create("mitsuba"), reg.create("cycles")
    try:
        axes(m, c)
        mesh_against_point(c)
        timing(c)
    finally:
        c.close()
    determinism()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
