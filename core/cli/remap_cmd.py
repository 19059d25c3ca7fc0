"""`remap --adapter A --model M --source MATERIAL.yaml --out DIR`: one material, one result."""

from __future__ import annotations

import argparse
import sys
from typing import TYPE_CHECKING

from ..errors import ConfigError
from ..schemas import format_value
from . import options

if TYPE_CHECKING:
    from ..report import Report

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
    p.add_argument("--source", required=True, metavar="MATERIAL.yaml", help="source material file")
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
    options.add_settings(p)
    options.add_common(p)
    return p


def run(args: argparse.Namespace) -> int:
    if args.table:
        from .table_cmd import lookup

        return lookup(args)
    for flag in ("adapter", "model"):
        if getattr(args, flag) is None:
            raise ConfigError("is required (the target's; or --table TABLE, which names it)", field=f"--{flag}")
    if args.no_render:
        raise ConfigError("goes with --table (a fit renders)", field="--no-render")
    from ..execute import adapter_pool
    from ..executors import workers
    from ..job import Job, Target, Where, model_of, resolve
    from ..plugins import collect_adapters
    from ..runner import Runner, Task
    from ..schemas import load_material, parse_fix
    from ..store import Store, owned
    from .progress import RenderProgress

    source = load_material(args.source)
    scene = options.scene_from(args)
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
              settings=settings, label=str(args.source))
    resolved = resolve(job, registry, Where(source_file=str(args.source)))
    header = (f"remap {source.adapter}:{source.model} -> {adapter}:{args.model}  ({scene.resolution}x"
              f"{scene.resolution}, {scene.spp} spp, scheme {settings.scheme}; fitting by default "
              f"{', '.join(resolved.free) or 'nothing'}{_carried_note(resolved.target_spec)})")
    with owned(args.out) as folder, workers() as w, adapter_pool(registry):
        runner = Runner(Store(folder), w, renderer_files=tuple(registry.loaded_files()), quiet=True,
                        render_progress=RenderProgress(not args.quiet, header), reuse=not args.force)
        (done,) = runner.run([Task("", resolved.job, str(args.source))])
    if done.redone and not args.quiet:
        print(f"note: the result that was in {folder} was replaced: {done.redone}", file=sys.stderr)
    print_report(done.report, folder, resumed=done.resumed)
    return 0


def format_params(params: dict, names: list[str] | None = None) -> str:
    return " ".join(f"{k}={format_value(tuple(v) if isinstance(v, list) else v)}" for k, v in params.items()
                    if names is None or k in names)


def _held_out(r: Report) -> str:
    """Each held-out condition's error, with its noise floor where that is not negligible."""
    if not r.validation:
        return "not checked (--validate none)" if not r.validation_skipped else "none could be rendered"
    parts = [f"{c.label} {c.error:.1%}" + (f" (noise {c.noise_floor:.1%})" if c.noise_floor >= 0.01 else "")
             for c in r.validation]
    levels: dict[tuple[int, int], list[str]] = {}
    for c in r.validation:
        if not c.given:
            levels.setdefault((c.resolution, c.spp), []).append(c.label)
    where = "; ".join(f"{', '.join(v) if len(levels) > 1 else 'each'} at {res} px {spp} spp"
                      for (res, spp), v in levels.items())
    skipped = "".join(f"; {k} skipped: {v}" for k, v in r.validation_skipped.items())
    return ", ".join(parts) + f"   ({where}; seeds the fit never saw{skipped})"


def _textures(t) -> str:
    """A textured source's maps and its textured check, each condition's error beside its noise."""
    maps = ", ".join(m.param for m in t.maps) or "none"
    checks = ", ".join(f"{c.condition} {c.error:.1%} (noise {c.noise_floor:.1%})" for c in t.checks) or \
        f"not rendered: {t.check_skipped}"
    return (f"{t.width} x {t.height} texels remapped texel by texel in {t.seconds:.2f} s; maps {maps}; textured "
            f"check at {t.checks[0].resolution if t.checks else '-'} px: {checks}")


def _verdict(r: Report) -> str:
    """The status and why (an unchecked result names the lights that judged it and those that could not)."""
    word = {"ok": "ok", "mismatch": "MISMATCH", "unreliable": "UNRELIABLE", "unchecked": "UNCHECKED"}[r.verdict]
    return word if r.reliable else f"{word}: {r.reason}"


def _start(r: Report) -> tuple[str, str]:
    lk = r.job.lookup
    if lk is not None:
        expected = f"; direct fits here reach about {lk.expected_error:.1%}" if lk.expected_error is not None else ""
        return "table", f"{lk.table} ({lk.method} map): nothing fitted{expected}" + (
            f"; clamped: {'; '.join(lk.outside)}" if lk.outside else "")
    if r.job.start is not None:
        return "start", "the job's own: " + format_params(r.start.params)
    return "start", ("the exporters' conversion: " + format_params(r.start.params) if r.start.informed
                     else "the target's defaults")


def print_report(r: Report, folder, resumed: bool) -> None:
    m = r.metrics
    rows = [
        ("params", format_params(r.params)),
        ("relative RMSE", f"{m.relative_rmse:.2%}   (noise floor {m.noise_floor:.2%})"),
        ("perceptual", f"{m.perceptual:.2f} mean ΔE_ITP"),
        *([("fit scene", r.fit_scene.why)] if r.fit_scene else []),
        ("held-out", _held_out(r)),
        *([("textures", _textures(r.textures))] if r.textures else []),
        _start(r),
        ("renders", f"{r.renders} target ({', '.join(f'{v} at {k}' for k, v in r.renders_by_resolution.items())})"
                    f" + {r.source_renders} source"),
        ("seconds", f"{r.seconds:.2f}" + ("   (the stored result of this same job: --force to fit again)"
                                          if resumed else "")),
        *([] if r.job.lookup else [("scheme", r.scheme if r.scheme == r.scheme_used
                                                 else f"{r.scheme} (used {r.scheme_used})")]),
        ("verdict", _verdict(r)),
        ("wrote", f"{folder}/ ({', '.join([f.name for f in r.files] + ['result.json'])})"),
    ]
    width = max(len(k) for k, _ in rows)
    for k, v in rows:
        print(f"{k:<{width}}  {v}")
