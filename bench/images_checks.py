"""The images of a source made wrong on purpose, each as a user's renderer would get it wrong: what the
check before the fit says of each (one line each; nothing is fitted).

    python bench/images_checks.py EXPORT/renders/MATERIAL

EXPORT is a `remap scene export` folder whose renders/calibration and renders/MATERIAL hold good images
(bench/images_outside.py or examples/outside/render_mitsuba.py make them). Each corruption is applied to
a copy (the calibration's images, or the material's where that is the point)."""

from __future__ import annotations

import shutil
import sys
import tempfile
from pathlib import Path

import numpy as np

from brdfremap.core.data.errors import ConfigError
from brdfremap.core.data.imageio import read_image, write_exr
from brdfremap.core.images.calibrate import checked


def srgb(x: np.ndarray) -> np.ndarray:
    x = np.clip(x, 0, None)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def eight_bit(x: np.ndarray) -> np.ndarray:
    return np.round(np.clip(x / 64.0, 0, 1) * 255) / 255 * 64  # stored in 8 bits at 1/64, the exposure undone


CORRUPTIONS = {
    "flipped left-right": ("calibration", lambda a: a[:, ::-1]),
    "upside down": ("calibration", lambda a: a[::-1]),
    "one row shifted": ("calibration", lambda a: np.roll(a, 1, axis=0)),
    "half a column shifted": ("calibration", lambda a: (a + np.roll(a, 1, axis=1)) / 2),
    "sRGB-encoded": ("calibration", srgb),
    "gamma 2.2": ("calibration", lambda a: np.power(np.clip(a, 0, None), 1 / 2.2)),
    "clipped at 1": ("calibration", lambda a: np.minimum(a, 1.0)),
    "8-bit at 1/64": ("calibration", eight_bit),
    "exposed x2": ("calibration", lambda a: a * 2),
    "in watts (x4pi)": ("calibration", lambda a: a * 4 * np.pi),
    "a grey world seen": ("material", lambda a: np.where(a.sum(axis=2, keepdims=True) > 0, a, 0.05)),
    "denoiser ringing": ("material", lambda a: a - 0.001),
}


def main() -> None:
    material = Path(sys.argv[1]).resolve()
    export = material.parents[1]
    try:
        checked(material)
        print(f"{'as rendered':24s} passes")
    except ConfigError as exc:
        print(f"{'as rendered':24s} FAILS: {exc}")
    for name, (which, change) in CORRUPTIONS.items():
        with tempfile.TemporaryDirectory() as tmp:
            copy = Path(tmp) / "export"
            shutil.copytree(export, copy, ignore=shutil.ignore_patterns("mitsuba", "usd", "maps"))
            folder = copy / material.relative_to(export).parent / (which if which == "calibration" else material.name)
            for f in folder.glob("*.exr"):
                write_exr(f, change(read_image(f)).astype(np.float32))
            try:
                checked(copy / material.relative_to(export))
                print(f"{name:24s} MISSED: passes")
            except ConfigError as exc:
                lines = str(exc).split("\n")[1:]
                print(f"{name:24s} " + "\n{:24s} ".format("").join(x.strip() for x in lines))
    with tempfile.TemporaryDirectory() as tmp:
        copy = Path(tmp) / "export"
        shutil.copytree(export, copy, ignore=shutil.ignore_patterns("mitsuba", "usd", "maps"))
        shutil.rmtree(copy / material.relative_to(export).parent / "calibration")
        folder = checked(copy / material.relative_to(export))
        print(f"{'calibration missing':24s} fitted, and the result says: "
              f"{[f.message for f in _bound(folder).native_findings()][0][:110]}...")


def _bound(folder):
    from brdfremap.adapters.images.adapter import BoundImages

    return BoundImages(folder)


if __name__ == "__main__":
    main()
