"""`remap adapters`, `remap schema`, `remap render`: look at what is installed, at the file
formats, and at one material."""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from ..data.errors import ConfigError
from ..data.schemas import format_value, ParamKind, Scale
from . import options


def adapters_parser() -> argparse.ArgumentParser:
    p = options.Parser(prog="remap adapters", description="List adapters and their models, each parameter "
                       "with its bounds.")
    p.add_argument("adapter", nargs="*", metavar="ADAPTER",
                   help="only these: installed names or renderer definition files (default: every installed one)")
    p.add_argument("--debug", action="store_true", help="show tracebacks")
    return p


def _parameter(p, spec=None) -> str:
    """One parameter as `remap adapters` shows it: name, kind, bounds or choices, default, and
    whether its renderer takes it as an image (a texture)."""
    if p.kind == ParamKind.CHOICE:
        return f"{p.name} ({' | '.join(map(str, p.choices))}; default {p.default})"
    scale = ", log" if p.scale == Scale.LOG else ""
    held = (", held unless the source has it" if p.fit_when_carried else ", held") if not p.fit else ""
    if p.fit_for:
        held += f"; tried where the source needs {' or '.join(n.value for n in p.fit_for)} and the fit leaves more " \
                "than the noise"
    image = ", an image too" if spec is not None and p.name in spec.texturable else ""
    return f"{p.name} ({p.kind} [{p.lower:g}, {p.upper:g}]{scale}{held}{image}; default {format_value(p.default)})"


def adapters(args: argparse.Namespace) -> int:
    from ..host.plugins import collect_adapters

    registry = collect_adapters()
    names = [registry.resolve(a, field_name="ADAPTER") for a in args.adapter] or registry.names()
    for name in names:
        entry = registry.get(name)
        reason = entry.unavailable_reason()
        print(f"{name}  [{entry.plugin}]  {getattr(entry.factory, 'summary', '')}")
        if reason:
            hint = getattr(entry.factory, "install_hint", "")
            print(f"  unavailable: {reason}" + (f"\n  install: {hint}" if hint else ""))
        else:
            try:
                env = entry.factory.environment()
            except Exception as exc:  # a broken plugin is listed with its error, not fatal
                env = {"environment": f"unknown ({exc})"}
            for k, v in env.items():
                print(f"  {k}: {v}")
        for mname, spec in sorted(entry.models.items()):
            lobes = "each lobe renders alone" if spec.has_lobes else "no lobe isolation"
            print(f"  model {mname} ({lobes}):")
            for p in spec.parameters:
                print(f"    {_parameter(p, spec)}")
    for plugin, err in sorted(registry.broken.items() if not args.adapter else ()):
        print(f"broken plugin {plugin}: {err}")
    return 0


def schema_parser() -> argparse.ArgumentParser:
    p = options.Parser(prog="remap schema", description="Print the JSON Schema of one of the file formats "
                                "(result.json by default), to validate what you read or write.")
    p.add_argument("name", nargs="?", default="report", help="report (result.json), material, scene, experiment, table-spec, table, "
                                                             "job, settings, or one a plugin adds (renderer)")
    p.add_argument("--debug", action="store_true", help="show tracebacks")
    return p


WRITTEN = frozenset({"report", "table", "convert", "lookup", "experiment-summary"})
"""The formats the tool writes (their schema as written, derived fields included); the others it reads."""


def collect_schemas(pm=None) -> dict[str, Any]:
    """File formats by name: the core's own and those plugins register (`remap schema NAME`). Here,
    beside the command, not in the plugin host: the host knows no file format."""
    from ..experiments.spec import Experiment
    from ..experiments.table import ExperimentSummary
    from ..library.records import ConvertSummary
    from ..tables.lookup import LookupRecord
    from ..job.job import Job
    from ..host.plugins import get_plugin_manager
    from ..job.report import Report
    from ..data.scene import ProbeScene
    from ..data.schemas import Material
    from ..data.settings import Settings
    from ..tables import Table, TableSpec

    out: dict[str, Any] = {"report": Report, "material": Material, "scene": ProbeScene, "experiment": Experiment,
                           "job": Job, "settings": Settings, "table": Table, "table-spec": TableSpec,
                           "convert": ConvertSummary, "lookup": LookupRecord, "experiment-summary": ExperimentSummary}
    pm = pm or get_plugin_manager()

    def register(name: str, model: Any) -> None:
        if name in out:
            raise ConfigError(f"file format {name!r} is registered twice")
        out[name] = model

    pm.hook.brdfremap_register_schemas(register=register)
    return out


def schema(args: argparse.Namespace) -> int:
    known = collect_schemas()
    if args.name not in known:
        raise ConfigError(f"unknown file format {args.name!r} (known: {', '.join(sorted(known))})", field="NAME")
    mode = "serialization" if args.name in WRITTEN else "validation"
    doc = known[args.name].model_json_schema(mode=mode)
    doc = {"$schema": "https://json-schema.org/draft/2020-12/schema", **doc}
    print(json.dumps(doc, indent=2, ensure_ascii=False))
    return 0


def render_parser() -> argparse.ArgumentParser:
    p = options.Parser(prog="remap render", description="Render one material on the probe scene, without "
                                "fitting anything: a linear float EXR (or an sRGB PNG preview for a .png name).")
    p.add_argument("material", metavar="MATERIAL.yaml", help="material file (adapter, model, params)")
    p.add_argument("--out", required=True, metavar="IMAGE.exr", help="image to write (.exr, or .png for a preview)")
    options.add_scene(p)
    p.add_argument("--lobe", choices=("diffuse", "specular"), help="render one lobe alone")
    options.add_common(p)
    return p


def render(args: argparse.Namespace) -> int:
    from ..data.imageio import display_exposure, preview, write_exr, write_png
    from ..job.job import model_of
    from ..host.plugins import collect_adapters
    from ..host.protocol import check_image
    from ..data.schemas import load_material

    out = _image_path(args.out)
    material = load_material(args.material)
    scene = options.scene_from(args)
    registry = collect_adapters()
    spec = model_of(registry, material.adapter, material.model, args.material, "")
    params = spec.complete(material.params, file=args.material)
    if args.lobe and args.lobe not in spec.lobes:
        raise ConfigError(f"model {spec.name!r} cannot render its lobes alone", field="--lobe")
    if args.lobe and spec.lobes[args.lobe].empty:
        raise ConfigError(f"model {spec.name!r} has no {args.lobe} lobe (it would render black)", field="--lobe")
    problem = registry.get(material.adapter).scene_problem(scene)
    if problem:
        raise ConfigError(f"adapter {material.adapter!r} cannot render the scene {scene.name!r}: it {problem}: use a "
                          "scene it can render", field="--scene")
    t0 = time.perf_counter()
    adapter = registry.create(material.adapter)
    who = f"adapter {material.adapter!r} model {material.model!r}"
    try:  # a scene of several views: each rendered alone, stacked top to bottom
        img = np.concatenate([check_image(adapter.render(spec, params, view, args.lobe), view, who)
                              for view in scene.view_scenes()])
    finally:
        adapter.close()
    try:
        if out.suffix.lower() == ".png":
            write_png(out, preview(img, display_exposure(img)))
        else:
            write_exr(out, img)
    except OSError as exc:
        raise ConfigError(f"cannot write: {exc.strerror or exc}", file=str(out)) from None
    if not args.quiet:
        print(f"wrote {out} ({scene.resolution}x{scene.resolution}, {scene.spp} spp, seed {scene.seed}; "
              f"{time.perf_counter() - t0:.2f} s; brightest pixel {float(img.max()):.4g})", file=sys.stderr)
    return 0


def _image_path(text: str) -> Path:
    """The file to write, checked before any render: a link is written through (kept), a
    dangling one refused; its folder created and proved writable."""
    import tempfile

    from ..data.atomic import why
    from ..run.store import check_not_owned

    out = Path(text)
    if out.suffix.lower() not in (".exr", ".png"):
        raise ConfigError("must end in .exr (linear float) or .png (an sRGB preview)", field=f"--out {text}")
    try:
        if out.is_symlink():
            if not out.exists():
                raise ConfigError("is a symbolic link to nothing: remove it or give another name",
                                  field=f"--out {text}")
            out = Path(os.path.realpath(out))
        if out.is_dir():
            raise ConfigError("is a folder: give an image file name", field=f"--out {text}")
        out.parent.mkdir(parents=True, exist_ok=True)
        tempfile.NamedTemporaryFile(prefix=".probe-", dir=out.parent).close()
    except OSError as exc:
        raise ConfigError(f"cannot write into its folder: {why(exc)}", field=f"--out {text}") from None
    check_not_owned(out.parent, "--out")  # a result folder another run is writing
    return out
