"""A Monte Carlo renderer's stand-in with the three faults LuxCoreRender's tile engine showed a new
user, for `remap check`'s diagnosis tests (tests/adapters/test_check_diagnosis.py).

    tile_renderer.py --scene SCENE_JSON --params PARAMS_JSON --out OUTPUT --spp N --seed S
                     [--ignore-seed] [--ignore-spp] [--shift-rows N] [--shift-columns N]

It renders the analytic Lambert sphere (`fake_renderer.image`) with the noise of N samples a pixel
(4 %/√N per pixel), its pattern drawn from the seed S. The faults: ``--ignore-seed`` draws it from
one fixed seed (every seed, the same image; its noise still there); ``--ignore-spp`` renders until
it is halted (a progressive engine whose halt condition is not the sample count: it never ends);
``--shift-rows`` / ``--shift-columns`` move the image down / right by whole pixels (a film a row off)."""

import argparse
import json
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))

import numpy as np  # noqa: E402
from fake_renderer import image, write  # noqa: E402

NOISE = 0.04
"""Per-pixel relative noise at one sample a pixel."""


def main() -> None:
    p = argparse.ArgumentParser()
    for name in ("--scene", "--params", "--out"):
        p.add_argument(name, required=True)
    p.add_argument("--spp", type=int, required=True)
    p.add_argument("--seed", type=int, required=True)
    p.add_argument("--ignore-seed", action="store_true")
    p.add_argument("--ignore-spp", action="store_true")
    p.add_argument("--shift-rows", type=int, default=0)
    p.add_argument("--shift-columns", type=int, default=0)
    args = p.parse_args()
    if args.ignore_spp:
        print("tile renderer: rendering until halted", file=sys.stderr, flush=True)
        while True:
            time.sleep(1)
    doc = json.loads(Path(args.scene).read_text())
    albedo = json.loads(Path(args.params).read_text())["params"]["albedo"]
    img = image(doc, np.asarray(albedo, np.float32))
    rng = np.random.default_rng([0 if args.ignore_seed else args.seed, args.spp])
    img = img * (1 + NOISE / np.sqrt(args.spp) * rng.standard_normal(img.shape))
    write(args.out, np.roll(img, (args.shift_rows, args.shift_columns), axis=(0, 1)))


if __name__ == "__main__":
    main()
