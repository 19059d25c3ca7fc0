"""`remap convert INPUT... --to ADAPTER[:MODEL] --out DIR`: whole libraries from the files they live in."""

from __future__ import annotations

import argparse

from . import options

EXIT_SOME_FAILED = 1


def parser() -> argparse.ArgumentParser:
    p = options.Parser(prog="remap convert", description="Convert every material of scene and library files "
                       "(Mitsuba XML, Blender .blend, MaterialX .mtlx, glTF .gltf/.glb, brdf-remap YAML, or folders "
                       "of them) to "
                       "another renderer: one native library per target, and DIR/index.html showing each "
                       "material's remap and how close it is. An interrupted run resumes.")
    p.add_argument("inputs", nargs="+", metavar="INPUT", help="files (or folders of them) to read")
    p.add_argument("--to", required=True, metavar="ADAPTER[:MODEL]",
                   help="target adapter, and model (without one the adapter picks per material and says which)")
    p.add_argument("--out", required=True, metavar="DIR", help="output folder (created)")
    p.add_argument("--only", action="append", default=[], metavar="NAME",
                   help="convert only the materials of this name (repeatable)")
    p.add_argument("--table", action="append", default=[], metavar="TABLE",
                   help="a remap table (`remap table build`) through which textured materials of its source model "
                        "are remapped texel by texel (repeatable; without one, a texture's constant is used)")
    p.add_argument("--events", metavar="FILE",
                   help="also write each finished material as one JSON line to FILE (done, of, title, status, "
                        "error), for a program that follows the run: the Blender extension's progress bar")
    options.add_scene(p)
    options.add_settings(p)
    options.add_workers(p)
    options.add_common(p)
    return p


def run(args: argparse.Namespace) -> int:
    from ..data.errors import ConfigError
    from ..job.execute import adapter_pool
    from ..run.executors import workers
    from ..library.convert import Destination, convert
    from ..library.formats import collect_formats, expand_inputs, read_all
    from ..images.reader import images_scene
    from ..host.plugins import collect_adapters, get_plugin_manager

    pm = get_plugin_manager()
    registry, formats = collect_adapters(pm), collect_formats(pm)
    dest = Destination.parse(args.to, registry)
    inputs = expand_inputs(args.inputs, formats)
    scene, settings = options.scene_from(args, images_scene(inputs)), options.settings_from(args)
    entries = read_all(inputs, formats, keep_going=True)
    if args.only:
        missing = set(args.only) - {e.name for e in entries}
        if missing:
            raise ConfigError(f"no material named {sorted(missing)[0]!r} in the inputs (found: "
                              f"{', '.join(e.name for e in entries[:12])}{' …' if len(entries) > 12 else ''})",
                              field="--only")
        entries = [e for e in entries if e.name in args.only]
    tables = [_table(t) for t in args.table]
    with workers(args.jobs, args.scheduler) as w, adapter_pool(registry) as adapters:
        result = convert(entries, dest, args.out, registry, formats, w, adapters, scene=scene, settings=settings,
                         quiet=args.quiet, tables=tables, events=args.events)
    _print(result, args.out)
    return EXIT_SOME_FAILED if result.failed else 0


def _table(text: str):
    from ..library.convert import TableUse
    from ..tables import TableMap, read_table
    from ..tables.table import table_file

    table = read_table(text)
    return TableUse(str(table_file(text).resolve()), table, TableMap(table))


def _print(result, out) -> None:
    n = len(result.items)
    by = {}
    for i in result.items:
        by[i.status] = by.get(i.status, 0) + 1
    print(f"materials   {n}: " + ", ".join(f"{v} {k}" for k, v in sorted(by.items())))
    for i in result.failed:
        print(f"  {i.status}: {i.entry.name} ({i.entry.file}): {i.reason}")
    done = [i for i in result.items if i.done is not None and i.done.report is not None and not i.done.resumed]
    if done:
        jobs = {i.done.report.key: i.done.report.seconds for i in done}  # a job several materials share, once
        print(f"time        {result.seconds:.1f} s in all; {sum(jobs.values()) / len(done):.1f} s a material "
              f"remapped this run ({len(done)}, {len(jobs)} distinct jobs)")
    for note in result.library_notes:
        print(f"note        {note}")
    print(f"libraries   {', '.join(f'{out}/{p.name}' for p in result.libraries) or 'none'}")
    print(f"report      {out}/index.html")
