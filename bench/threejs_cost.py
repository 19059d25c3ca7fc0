"""What a three.js render costs: the page's start-up (Chromium, three.js, its shaders), a render of the
probe at each resolution, and an environment's first use (three.js's PMREM) and later ones.

    python bench/threejs_cost.py [--reps 20] [--edges]

Prints the median of --reps renders of a glossy dielectric at each size (after one warm-up). With
--edges, how the supersampling (`SUPERSAMPLE`) decides the sphere's edge: a white Lambertian under the
rim light (a crescent along the edge) at each supersampling against Mitsuba's at 1024 spp, over every
pixel and over the sphere's interior, with the render time."""

from __future__ import annotations

import argparse
import statistics
import time

import brdfremap.adapters.threejs.adapter as three
from brdfremap.adapters.threejs.adapter import SUPERSAMPLE, ThreeJsAdapter
from brdfremap.core.data.metrics import relative_rmse
from brdfremap.core.data.scene import EnvironmentLight, PointLight, ProbeScene
from brdfremap.core.testing import sphere_hits


def timed(fn) -> float:
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--reps", type=int, default=20)
    ap.add_argument("--edges", action="store_true")
    args = ap.parse_args()
    if args.edges:
        return edges()
    a = ThreeJsAdapter()
    params = a.models["gltf_pbr"].complete({"base_color": (0.6, 0.1, 0.05), "metallic": 0.0, "roughness": 0.3})
    try:
        first = timed(lambda: a.render("gltf_pbr", params, ProbeScene(resolution=32)))
        print(f"page start-up {a.page.startup_seconds:.2f} s; first render (shaders compiled) {first:.2f} s in all")
        print(f"supersampled {SUPERSAMPLE}x{SUPERSAMPLE} per pixel")
        for res in (64, 128, 256):
            scene = ProbeScene(resolution=res)
            a.render("gltf_pbr", params, scene)
            t = statistics.median(timed(lambda: a.render("gltf_pbr", params, scene)) for _ in range(args.reps))
            print(f"probe {res}x{res}: {1000 * t:.0f} ms a render (median of {args.reps})")
        studio = ProbeScene(lights=[EnvironmentLight(type="environment", map="studio")], resolution=64)
        once = timed(lambda: a.render("gltf_pbr", params, studio))
        t = statistics.median(timed(lambda: a.render("gltf_pbr", params, studio)) for _ in range(args.reps))
        print(f"studio 64x64: first {once:.2f} s (the map prefiltered by PMREM), then {1000 * t:.0f} ms a render")
    finally:
        a.close()
    return 0


def edges() -> int:
    from brdfremap.adapters.mitsuba.adapter import MitsubaAdapter

    scene = ProbeScene(lights=[PointLight(theta=120.0)], resolution=128, spp=1024)
    inner = sphere_hits(scene).interior
    with MitsubaAdapter() as m, ThreeJsAdapter() as a:
        ref = m.render("diffuse", m.models["diffuse"].complete({"reflectance": 0.8}), scene)
        white = a.models["gltf_pbr"].complete(a.calibration[1])
        print("white Lambertian, rim light, 128 px, against Mitsuba at 1024 spp")
        for ss in (2, 4, 8, 12):
            three.SUPERSAMPLE = ss
            a.render("gltf_pbr", white, scene)
            t = statistics.median(timed(lambda: a.render("gltf_pbr", white, scene)) for _ in range(5))
            img = a.render("gltf_pbr", white, scene)
            print(f"supersampling {ss:2d}x{ss:<2d} every pixel {relative_rmse(ref, img):6.2%}  interior "
                  f"{relative_rmse(ref[inner], img[inner]):6.2%}  {1000 * t:5.0f} ms a render")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
