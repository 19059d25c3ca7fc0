"""`remap --adapter A --model M --source MATERIAL.yaml --out DIR`: one material, one result."""

from __future__ import annotations

import argparse
import sys

from ..data.errors import ConfigError
from . import options
from .show import print_report

USAGE_EPILOG = """\
other commands:
  remap convert INPUT... --to ADAPTER[:MODEL] --out DIR   whole libraries (.xml, .blend, .mtlx), index.html
  remap adapters                          list adapters, their models, and why one is unavailable
  remap render MATERIAL.yaml --out IMAGE.exr   render one material on the probe, no fit
  remap sweep EXPERIMENT.yaml --out DIR   remap a family of source materials; CSV, plots, cliffs
  remap roundtrip EXPERIMENT.yaml --out DIR   remap there and back; recovered vs original
  remap schema [report|material|scene|experiment|...]   the JSON Schema of a file format

examples:
  remap --adapter mitsuba --model roughconductor --fix distribution=ggx \\
        --source configs/materials/gold.yaml --out out/gold-ggx
"""


def _carried_note(spec) -> str:
    """The header's word on parameters fitted only when the source has them (a coat, a sheen)."""
    return " + coat, sheen, anisotropy if the source has them" if any(
        p.fit_when_carried for p in spec.parameters) else ""


def parser() -> argparse.ArgumentParser:
    p = options.Parser(
        prog="remap",
        description="Remap a material to another renderer's BRDF model by matching rendered images "
        "(Sztrajman et al., MAM 2017).",
        epilog=USAGE_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("--adapter", help="target adapter (see `remap adapters`), or a renderer definition file "
                                     "(renderer.yaml); required unless --table gives it")
    p.add_argument("--model", help="target material model of that adapter; required unless --table gives it")
    given = p.add_mutually_exclusive_group(required=True)
    given.add_argument("--source", metavar="MATERIAL.yaml", help="source material file")
    given.add_argument("--source-images", metavar="DIR", help="a source given as images: the scenes of `remap scene "
                                                              "export` rendered elsewhere (DIR/renders/MATERIAL)")
    p.add_argument("--out", required=True, metavar="DIR", help="output folder (created)")
    p.add_argument("--table", metavar="TABLE", help="read the target's parameters from a remap table (`remap table "
                                                    "build`) instead of fitting them: rendered and judged, or not "
                                                    "rendered with --no-render")
    p.add_argument("--no-render", action="store_true", help="with --table: no render at all; write the "
                                                            "parameters and the native material")
    options.add_scene(p)
    p.add_argument("--fix", action="append", default=[], metavar="NAME=VALUE",
                   help="hold a target parameter at a value (repeatable), e.g. --fix distribution=ggx")
    p.add_argument("--force", action="store_true", help="fit again even if DIR holds the result of this same job")
    p.add_argument("--fit-same-model", action="store_true",
                   help="fit a source to its own model of the same renderer all the same (a test of the optimiser, "
                        "whose answer is known); without it the source's parameters are the result, unfitted")
    options.add_settings(p)
    options.add_common(p)
    return p


def images_source(folder: str):
    """A source given as images (`core.images.folder`): its calibration checked first, each failure one line."""
    from ..data.schemas import Material
    from ..images.calibrate import checked

    images = checked(folder)
    return Material(adapter="images", model="", name=images.folder.name, native=images.native())


def images_scene(folder: str):
    """The job's scene of a source given as images: the export's probe shot."""
    from ..images.folder import ImageFolder

    return ImageFolder.open(folder).probe_scene


def run(args: argparse.Namespace) -> int:
    if args.source_images and (args.table or args.scene):
        flag = "--table" if args.table else "--scene"
        raise ConfigError(f"does not go with --source-images: images are of the export's scenes, fitted "
                          f"{'' if args.table else 'on its probe '}as they are", field=flag)
    if args.table:
        from .table_cmd import lookup

        return lookup(args)
    for flag in ("adapter", "model"):
        if getattr(args, flag) is None:
            raise ConfigError("is required (the target's; or --table TABLE, which names it)", field=f"--{flag}")
    if args.no_render:
        raise ConfigError("goes with --table (a fit renders)", field="--no-render")
    from ..job.execute import adapter_pool
    from ..run.executors import workers
    from ..job.job import Job, Target, Where, model_of, resolve
    from ..host.plugins import collect_adapters
    from ..run.runner import Runner, Task
    from ..data.schemas import load_material, parse_fix
    from ..run.store import Store, owned
    from .progress import RenderProgress

    source = load_material(args.source) if args.source else images_source(args.source_images)
    label = args.source or args.source_images
    scene = options.scene_from(args, images_scene(args.source_images) if args.source_images else None)
    settings = options.settings_from(args)
    registry = collect_adapters()
    adapter = registry.resolve(args.adapter)
    spec = model_of(registry, adapter, args.model, None, "--")
    fixed: dict = {}
    for text in args.fix:
        name, value = parse_fix(text, spec)
        if name in fixed:
            raise ConfigError("given twice: keep one", field=f"--fix {name}")
        fixed[name] = value
    job = Job(source=source, target=Target(adapter=adapter, model=args.model, fix=fixed), scene=scene,
              settings=settings, label=str(label), fit_same_model=args.fit_same_model)
    resolved = resolve(job, registry, Where(source_file=str(label)))
    header = (f"remap {source.adapter}:{source.model} -> {adapter}:{args.model}  ({scene.resolution}x"
              f"{scene.resolution}, {scene.spp} spp, scheme {settings.scheme}; fitting by default "
              f"{', '.join(resolved.free) or 'nothing'}{_carried_note(resolved.target_spec)})")
    with owned(args.out) as folder, workers() as w, adapter_pool(registry) as adapters:
        runner = Runner(Store(folder), w, adapters, quiet=True, render_progress=RenderProgress(not args.quiet, header),
                        reuse=not args.force)
        (done,) = runner.run([Task("", resolved, str(label))])
    if done.redone and not args.quiet:
        print(f"note: the result that was in {folder} was replaced: {done.redone}", file=sys.stderr)
    print_report(done.report, folder, resumed=done.resumed)
    return 0
