"""Render a scene of `remap scene export` with Mitsuba 3, as any Mitsuba user would: no brdf-remap here.

    python render_mitsuba.py EXPORT/mitsuba/probe.xml OUT.exr --seed 0 [--material MY_BSDF.xml] [--spp N]

``--material`` is a file holding a `<bsdf id="material">` (in a `<scene version="3.0.0">`); without it the
scene's own `material.xml` (the white Lambertian of the calibration) is rendered."""

import argparse
from pathlib import Path

import mitsuba as mi


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("scene")
    p.add_argument("out")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--spp", type=int)
    p.add_argument("--material")
    p.add_argument("--variant", default="scalar_rgb")
    args = p.parse_args()
    mi.set_variant(args.variant)
    scene_file = Path(args.scene).resolve()
    text = scene_file.read_text()
    if args.material:
        text = text.replace('<include filename="material.xml"/>',
                            f'<include filename="{Path(args.material).resolve()}"/>')
    given = {"seed": str(args.seed)} | ({"spp": str(args.spp)} if args.spp else {})
    # Loaded from its folder, so that the files it names (material.xml, the environment map) are found.
    mi.file_resolver().prepend(str(scene_file.parent))
    scene = mi.load_string(text, **given)
    image = mi.render(scene, seed=args.seed)
    mi.Bitmap(image).write(args.out)


if __name__ == "__main__":
    main()
