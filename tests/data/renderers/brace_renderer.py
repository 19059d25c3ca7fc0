"""A command-line renderer whose scene language uses braces, for the renderer-definition tests.

    brace_renderer.py SCENE_JSON SCENE_FILE OUTPUT [--pixels float|half] [--misname]
                      [--scale F] [--mirror] [--clip]

It reads the probe's geometry from SCENE_JSON and the material from SCENE_FILE, written in its
own language: blocks in braces, `#` comments (which may hold braces too), and one line
`albedo = R G B` inside `material { ... }`. It renders the analytic Lambert sphere and writes
OUTPUT (EXR, or Radiance HDR by its suffix) with 32-bit or half-float pixels; ``--misname``
writes OUTPUT.png instead, as a renderer that appends its own suffix does. The faults `remap
check` must name: ``--scale`` (wrong units), ``--mirror`` (left and right swapped), ``--clip``
(values clipped at 1, as an 8-bit image is)."""

import argparse
import json
import re
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))

import numpy as np  # noqa: E402
from fake_renderer import image  # noqa: E402


def albedo(scene_text: str) -> list[float]:
    body = re.sub(r"#[^\n]*", "", scene_text)
    block = re.search(r"material\s*\{([^{}]*)\}", body)
    if block is None:
        sys.exit("brace renderer: no material { ... } block")
    m = re.search(r"albedo\s*=\s*([-\d.eE+]+)\s+([-\d.eE+]+)\s+([-\d.eE+]+)", block.group(1))
    if m is None:
        sys.exit(f"brace renderer: no 'albedo = R G B' in the material block: {block.group(1).strip()!r}")
    return [float(x) for x in m.groups()]


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("scene_json")
    p.add_argument("scene_file")
    p.add_argument("output")
    p.add_argument("--pixels", choices=["float", "half"], default="float")
    p.add_argument("--misname", action="store_true")
    p.add_argument("--scale", type=float, default=1.0)
    p.add_argument("--mirror", action="store_true")
    p.add_argument("--clip", action="store_true")
    p.add_argument("--copy-scene", help="also copy the filled scene file here (what the tests read back)")
    p.add_argument("--log", help="append this render's start and end times here (concurrency tests)")
    p.add_argument("--sleep", type=float, default=0.0, help="seconds to wait, as a renderer on its I/O does")
    args = p.parse_args()
    import time

    t0 = time.time()
    time.sleep(args.sleep)
    if args.copy_scene:
        Path(args.copy_scene).write_text(Path(args.scene_file).read_text())
    doc = json.loads(Path(args.scene_json).read_text())
    pixels = image(doc, np.asarray(albedo(Path(args.scene_file).read_text()), np.float32)) * args.scale
    if args.mirror:
        pixels = pixels[:, ::-1]
    if args.clip:
        pixels = np.minimum(pixels, 1.0)
    import OpenImageIO as oiio

    path = args.output + (".png" if args.misname else "")
    h, w, c = pixels.shape
    kind = args.pixels if path.endswith(".exr") else "float"
    if path.endswith(".png"):  # 8-bit sRGB, as a renderer's PNG output is
        x = np.clip(pixels, 0.0, 1.0)
        pixels, kind = np.where(x <= 0.0031308, x * 12.92, 1.055 * x ** (1 / 2.4) - 0.055), "uint8"
    out = oiio.ImageOutput.create(path)
    out.open(path, oiio.ImageSpec(w, h, c, kind))
    out.write_image(np.ascontiguousarray(pixels, np.float32))
    out.close()
    if args.log:
        with open(args.log, "a") as f:
            f.write(f"{t0} {time.time()}\n")


if __name__ == "__main__":
    main()
