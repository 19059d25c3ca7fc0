"""`remap check`'s rows for adapters made wrong on purpose, each as a newcomer's adapter got it wrong: what
fails and its line, and how long the thirteen rows take. No renderer: each adapter is the white Lambertian a
correct renderer draws (the box-filtered analytic image) with one corruption, so the figures are the check's
own (tests/adapters/test_check_corrupted.py asserts the same cases).

    python bench/check_corrupted.py

Prints, per corruption, the rows that fail (and those not judged for them) with their lines, and the check's
wall time."""

from __future__ import annotations

import time

import numpy as np

from brdfremap.core.data.schemas import ModelSpec, ParamSpec
from brdfremap.core.host import check
from brdfremap.core.testing import analytic_lambert, box_filtered_lambert, sphere_hits

MODELS = {"lambert": ModelSpec(name="lambert", parameters=(ParamSpec(name="albedo", kind="rgb", default=(0.5,) * 3),))}
WHITE = ("lambert", {"albedo": (0.8, 0.8, 0.8)})


def _srgb(x):
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(np.maximum(x, 0.0031308), 1 / 2.4) - 0.055)


def _eight_bit(x, exposure=1.0):
    return np.round(np.clip(x * exposure, 0, 1) * 255) / 255 / exposure


def _no_falloff(scene, a):
    hits = sphere_hits(scene)
    d2 = ((np.asarray(scene.point_lights[0].position) - hits.position) ** 2).sum(-1)
    return box_filtered_lambert(scene, a) * d2[..., None]


CORRUPT = {
    "correct": lambda scene, a: box_filtered_lambert(scene, a),
    "clipped at 4": lambda scene, a: np.minimum(box_filtered_lambert(scene, a), 4.0),
    "8-bit at 1/64": lambda scene, a: _eight_bit(box_filtered_lambert(scene, a), 1 / 64),
    "8-bit sRGB, not linearised": lambda scene, a: _eight_bit(_srgb(box_filtered_lambert(scene, a))),
    "one ray at each pixel's centre": lambda scene, a: analytic_lambert(scene, a),
    "a light without 1/r² falloff": _no_falloff,
    "x pi": lambda scene, a: box_filtered_lambert(scene, a) * np.pi,
    "mirrored left-right": lambda scene, a: box_filtered_lambert(scene, a)[:, ::-1],
}


def main() -> int:
    for kind, corrupt in CORRUPT.items():
        def render(model, params, scene, lobe=None, corrupt=corrupt):
            return np.asarray(corrupt(scene, np.asarray(params["albedo"], np.float64)), np.float32)
        t = time.perf_counter()
        rows = check.run(render, MODELS, WHITE)
        seconds = time.perf_counter() - t
        failed = [r for r in rows if r.passed is False]
        waiting = [r.name.split(":")[0] for r in rows if r.passed is None]
        print(f"{kind}: {len(failed)} fail, {len(waiting)} not judged, {seconds:.1f} s")
        for r in failed:
            print(f"  FAIL {r.name.split(':')[0]}: {r.detail}")
        if waiting:
            print(f"  not judged: {', '.join(waiting)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
