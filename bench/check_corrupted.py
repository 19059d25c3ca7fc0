"""`remap check`'s rows for adapters made wrong on purpose, each as a newcomer's adapter got it wrong: what
fails and its line, and how long the thirteen rows take. No renderer: each adapter is the white Lambertian a
correct renderer draws (the box-filtered analytic image) with one corruption, so the figures are the check's
own (tests/adapters/test_check_corrupted.py asserts the same cases).

    python bench/check_corrupted.py

Prints, per corruption, the rows that fail (and those not judged for them) with their lines, and the check's
wall time."""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the tests' corrupted renderers, not a copy of them

from brdfremap.core.host import check  # noqa: E402
from brdfremap.core.testing import box_filtered_lambert, sphere_hits  # noqa: E402
from tests.adapters.test_check_corrupted import CORRUPT as ISSUE, MODELS, WHITE  # noqa: E402


def _no_falloff(scene, a):
    hits = sphere_hits(scene)
    d2 = ((np.asarray(scene.point_lights[0].position) - hits.position) ** 2).sum(-1)
    return box_filtered_lambert(scene, a) * d2[..., None]


CORRUPT = {**ISSUE, "a light without 1/r² falloff": _no_falloff,
           "x pi": lambda scene, a: box_filtered_lambert(scene, a) * np.pi,
           "mirrored left-right": lambda scene, a: box_filtered_lambert(scene, a)[:, ::-1]}
"""The issue's four (and the correct renderer) as the tests write them, and three usual mistakes more."""


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
