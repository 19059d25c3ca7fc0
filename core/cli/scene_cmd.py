"""`remap scene export DIR`: the probe and its held-out conditions written for a renderer the tool
cannot drive (`core.images.export`)."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..data.errors import ConfigError
from . import options

DEFAULT_SPP = 64
"""The sheet's samples per pixel: each shot's two seeds then differ by about 1-2 % on a glossy metal in a
path tracer, a noise the fit and the verdict measure."""


def parser() -> argparse.ArgumentParser:
    p = options.Parser(prog="remap scene export", description="Write the probe scene and each held-out condition "
                       "in renderers' own formats (Mitsuba XML, USD), with the environment maps, a calibration "
                       "material and a sheet of what to render: for a renderer this tool cannot drive. Its images "
                       "are then a source: `remap --source-images DIR/renders/MATERIAL`.")
    p.add_argument("action", choices=("export",), help="export: write the scenes")
    p.add_argument("out", metavar="DIR", help="the folder to write (created; a folder exported before is updated, "
                                              "its renders kept)")
    p.add_argument("--format", action="append", metavar="NAME", help="only this format (repeatable; default every "
                                                                     "installed one)")
    options.add_scene(p)
    p.add_argument("--debug", action="store_true", help="show tracebacks")
    return p


def run(args: argparse.Namespace) -> int:
    from ..images.export import export

    scene = options.scene_from(args)
    if scene.views:
        raise ConfigError("has several views: export renders one view a shot; give a scene of one view",
                          field="--scene")
    spp = args.spp or DEFAULT_SPP
    done = export(Path(args.out), scene, spp, args.format)
    print(f"wrote {len(done.files)} files to {done.folder}: {len(done.manifest.shots)} shots "
          f"({', '.join(s.name for s in done.manifest.shots)}) in {', '.join(sorted(done.manifest.files))}, "
          f"{scene.resolution}x{scene.resolution} at {spp} spp")
    print(f"next: render them as {done.folder / 'SHEET.md'} says, then `remap --source-images "
          f"{done.folder / 'renders' / 'MATERIAL'} --adapter ADAPTER --model MODEL --out OUT`")
    return 0
