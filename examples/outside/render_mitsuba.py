"""Render the scenes of `remap scene export` with Mitsuba 3, as any Mitsuba user would: no brdf-remap here.

    python render_mitsuba.py EXPORT/mitsuba OUT_FOLDER [--material MY_BSDF.xml] [--shot probe ...] [--spp N]
    python render_mitsuba.py EXPORT/mitsuba/probe.xml OUT.exr --seed 0

A folder renders each scene in it (but `bright`, which is the calibration's alone, unless no
``--material`` is given) with seeds 0 and 1 as SHOT.seed0.exr and SHOT.seed1.exr, as the export's
SHEET.md asks. ``--material`` is a file holding a `<bsdf id="material">` (in a `<scene version="3.0.0">`);
without it each scene's own `material.xml` (the white Lambertian of the calibration) is rendered."""

import argparse
from pathlib import Path

import mitsuba as mi


def render(scene_file: Path, out: Path, seed: int, material: str | None, spp: int | None) -> None:
    text = scene_file.read_text()
    if material:
        text = text.replace('<include filename="material.xml"/>', f'<include filename="{Path(material).resolve()}"/>')
    given = {"seed": str(seed)} | ({"spp": str(spp)} if spp else {})
    scene = mi.load_string(text, **given)
    mi.Bitmap(mi.render(scene, seed=seed)).write(str(out))


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("scenes", help="a scene file, or the export's mitsuba folder")
    p.add_argument("out", help="an EXR file, or a folder for SHOT.seed0.exr and SHOT.seed1.exr")
    p.add_argument("--seed", type=int, default=0, help="for one scene file")
    p.add_argument("--spp", type=int)
    p.add_argument("--material")
    p.add_argument("--shot", action="append", help="only these shots (a folder)")
    p.add_argument("--variant", default="scalar_rgb")
    args = p.parse_args()
    mi.set_variant(args.variant)
    source = Path(args.scenes).resolve()
    # The files a scene names (material.xml, the environment map) are found beside it.
    mi.file_resolver().prepend(str(source if source.is_dir() else source.parent))
    if not source.is_dir():
        render(source, Path(args.out), args.seed, args.material, args.spp)
        return
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    for scene_file in sorted(source.glob("*.xml")):
        shot = scene_file.stem
        if shot == "material" or (args.shot and shot not in args.shot) or (shot == "bright" and args.material):
            continue
        for seed in (0, 1):
            render(scene_file, out / f"{shot}.seed{seed}.exr", seed, args.material, args.spp)


if __name__ == "__main__":
    main()
