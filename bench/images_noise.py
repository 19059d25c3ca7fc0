"""The render noise of one image estimated from the image itself (`core.images.noise`, what a source of
images given with one seed a shot is judged with) against two seeds' difference, shot by shot.

    python bench/images_noise.py EXPORT/renders/MATERIAL [...]
"""

from __future__ import annotations

import sys
from pathlib import Path

from brdfremap.core.data.imageio import read_image
from brdfremap.core.data.metrics import relative_rmse
from brdfremap.core.images.noise import estimated_noise


def main() -> None:
    for folder in map(Path, sys.argv[1:]):
        for first in sorted(folder.glob("*.seed0.exr")):
            second = first.with_name(first.name.replace(".seed0.", ".seed1."))
            if not second.is_file():
                continue
            a, b = read_image(first), read_image(second)
            measured, estimate = relative_rmse(a, b), estimated_noise(a)
            print(f"{folder.name:14s} {first.name.split('.')[0]:12s} measured {measured:7.2%}  estimated {estimate:7.2%}"
                  f"  ratio {estimate / measured if measured else float('nan'):5.2f}")


if __name__ == "__main__":
    main()
