"""The `remap` command. Bad input prints one line naming the file and field, and exits 2."""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from pathlib import Path

import numpy as np

from . import interrupt
from .errors import ConfigError, RemapError

EXIT_USAGE = 2

USAGE_EPILOG = """\
other commands:
  remap adapters                          list adapters, their models, and why one is unavailable
  remap sweep EXPERIMENT.yaml --out DIR   remap a family of source materials; CSV, plots, cliffs
  remap roundtrip EXPERIMENT.yaml --out DIR   remap there and back; recovered vs original

examples:
  remap --adapter mitsuba --model roughconductor --fix distribution=ggx \\
        --source configs/materials/gold.yaml --out out/gold-ggx
"""


def _remap_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="remap",
        description="Remap a material to another renderer's BRDF model by matching rendered images "
        "(Sztrajman et al., MAM 2017).",
        epilog=USAGE_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("--adapter", required=True, help="target adapter (see `remap adapters`)")
    p.add_argument("--model", required=True, help="target material model of that adapter")
    p.add_argument("--source", required=True, metavar="MATERIAL.yaml", help="source material file")
    p.add_argument("--out", required=True, metavar="DIR", help="output folder (created)")
    p.add_argument("--scene", metavar="SCENE.yaml", help="probe scene (default: the built-in probe, "
                   "identical to configs/scenes/default.yaml)")
    p.add_argument("--scheme", choices=("auto", "one", "two", "three"), default="auto",
                   help="remap scheme (default auto: two-stage when the target's lobes divide its parameters, "
                        "else one-stage)")
    p.add_argument("--resolution", type=int, help="override the scene's resolution (pixels)")
    p.add_argument("--spp", type=int, help="override the scene's samples per pixel")
    p.add_argument("--seed", type=int, help="override the scene's sampler seed")
    p.add_argument("--fix", action="append", default=[], metavar="NAME=VALUE",
                   help="hold a target parameter at a value (repeatable), e.g. --fix distribution=ggx")
    p.add_argument("--method", choices=("trf", "dogbox"), default="trf",
                   help="least-squares method (default trf, the paper's Trust Region Reflective)")
    p.add_argument("--coarse", type=int, default=32, metavar="N",
                   help="resolution of the coarse level where most iterations run (default 32; 0: off)")
    p.add_argument("--starts", type=int, default=4, help="initial points tried per stage (default 4)")
    p.add_argument("--start", choices=("informed", "defaults"), default="informed",
                   help="first start: the exporters' conversion of the source where both adapters read one "
                        "(default), or the target model's defaults")
    p.add_argument("--precise-spp", type=int, default=4, metavar="K",
                   help="a fit that ends within 3x the render noise is polished at K times the samples "
                        "(default 4; 1: never)")
    p.add_argument("--threshold", type=float, default=0.05,
                   help="relative RMSE above which a result is flagged unreliable (default 0.05)")
    p.add_argument("--quiet", action="store_true", help="no progress lines")
    p.add_argument("--debug", action="store_true", help="show tracebacks")
    return p


def _adapters_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="remap adapters", description="List adapters and their models.")
    p.add_argument("--debug", action="store_true", help="show tracebacks")
    return p


def _experiment_parser(kind: str) -> argparse.ArgumentParser:
    what = {"sweep": "Sweep one source parameter, remap every point, and write a CSV, plots and the cliffs found.",
            "roundtrip": "Remap every point of a sweep to the target and back; plot recovered against original."}
    p = argparse.ArgumentParser(prog=f"remap {kind}", description=what[kind] + " An interrupted run resumes: "
                                "finished points in DIR are reused when their inputs are unchanged.")
    p.add_argument("experiment", metavar="EXPERIMENT.yaml", help="experiment file (see configs/experiments/)")
    p.add_argument("--out", required=True, metavar="DIR", help="output folder (created)")
    p.add_argument("--quiet", action="store_true", help="no progress lines")
    p.add_argument("--debug", action="store_true", help="show tracebacks")
    return p


class Progress:
    """Stage, renders so far and current error, on stderr; throttled when not a terminal."""

    def __init__(self, enabled: bool):
        self.enabled = enabled
        self.tty = sys.stderr.isatty()
        self.stage = None
        self.last = 0.0
        self.t0 = time.perf_counter()

    def __call__(self, stage: str, renders: int, error: float) -> None:
        if not self.enabled:
            return
        now = time.perf_counter()
        err = "" if math.isnan(error) else f"  error {error:7.3%}"
        line = f"  [{now - self.t0:6.1f}s] {stage:<14} renders {renders:4d}{err}"
        if self.tty:
            end = "\n" if stage != self.stage and self.stage is not None else ""
            sys.stderr.write(("\n" if end else "\r") + line)
            if stage == "final":
                sys.stderr.write("\n")
            sys.stderr.flush()
        elif stage != self.stage or now - self.last > 2.0 or stage == "final":
            print(line, file=sys.stderr, flush=True)
            self.last = now
        self.stage = stage


def _fmt_params(params: dict, names: list[str] | None = None) -> str:
    from .schemas import format_value

    return " ".join(f"{k}={format_value(v)}" for k, v in params.items() if names is None or k in names)


def cmd_remap(args: argparse.Namespace) -> int:
    from pydantic import ValidationError

    from .configio import validation_message
    from .plugins import collect_adapters
    from .remap import RemapOptions
    from .scene import ProbeScene, load_scene
    from .schemas import load_material, parse_fix
    from .session import open_adapters, prepare, run, write_outputs

    if args.starts < 1:
        raise ConfigError("must be at least 1", field="--starts")
    if args.precise_spp < 1:
        raise ConfigError("must be at least 1 (1: no polish at more samples)", field="--precise-spp")
    if not 0 < args.threshold < 10:
        raise ConfigError("must be a positive fraction such as 0.05", field="--threshold")
    source = load_material(args.source)
    scene = load_scene(args.scene) if args.scene else ProbeScene()
    overrides = {k: v for k, v in (("resolution", args.resolution), ("spp", args.spp), ("seed", args.seed))
                 if v is not None}
    try:
        scene = ProbeScene.model_validate({**scene.model_dump(), **overrides})
    except ValidationError as exc:
        field, msg = validation_message(exc)
        raise ConfigError(msg, field=f"--{field}") from exc
    registry = collect_adapters()
    args.adapter = registry.resolve(args.adapter)
    entry = registry.get(args.adapter)
    if args.model not in entry.models:
        raise ConfigError(f"adapter {args.adapter!r} has no model {args.model!r} (models: "
                          f"{', '.join(sorted(entry.models))})", field="--model")
    spec = entry.models[args.model]
    fixed = dict(parse_fix(f, spec) for f in args.fix)
    if args.coarse < 0 or 0 < args.coarse < 8:
        raise ConfigError("must be 0 (off) or at least 8", field="--coarse")
    options = RemapOptions(scheme=args.scheme, starts=args.starts, threshold=args.threshold, method=args.method,
                           coarse_resolution=args.coarse or None, informed_start=args.start == "informed",
                           precise_spp=args.precise_spp)
    job = prepare(registry, source, str(args.source), args.adapter, args.model, scene, fixed, options)
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise ConfigError("exists and is not a folder", field=f"--out {out}")
    progress = Progress(not args.quiet)
    if not args.quiet:
        print(f"remap {job.source.adapter}:{source.model} -> {args.adapter}:{args.model}  "
              f"({scene.resolution}x{scene.resolution}, {scene.spp} spp, scheme {args.scheme}; "
              f"fitting {', '.join(job.free) or 'nothing'})", file=sys.stderr, flush=True)
    with open_adapters(registry, [job.source.adapter, args.adapter]) as adapters:
        outcome = run(job, registry, adapters, progress)
        files = write_outputs(outcome, out, adapters[args.adapter])
    r = outcome.result
    rows = [
        ("params", _fmt_params(spec.active(r.params))),
        ("relative RMSE", f"{r.relative_rmse:.2%}   (noise floor {outcome.noise_floor:.2%})"),
        ("perceptual", f"{r.perceptual:.2f} mean ΔE_ITP"),
        ("start", "the exporters' conversion: " + _fmt_params(outcome.start) if outcome.start
                  else "the target's defaults"),
        ("renders", f"{r.renders} target ({', '.join(f'{v} at {k}' for k, v in outcome.renders_by_resolution.items())})"
                    f" + {outcome.source_renders} source"),
        ("seconds", f"{r.seconds:.2f}"),
        ("scheme", r.scheme if r.scheme == r.scheme_used else f"{r.scheme} (used {r.scheme_used})"),
        ("reliable", ("yes" if r.reliable else "NO") + ("" if r.reliable else f": {r.reason}")),
        ("wrote", f"{out}/ ({', '.join(p.name for p in files)})"),
    ]
    width = max(len(k) for k, _ in rows)
    for k, v in rows:
        print(f"{k:<{width}}  {v}")
    return 0


def cmd_adapters(args: argparse.Namespace) -> int:
    from .plugins import collect_adapters

    registry = collect_adapters()
    for name in registry.names():
        entry = registry.get(name)
        reason = entry.unavailable_reason()
        print(f"{name}  [{entry.plugin}]  {getattr(entry.factory, 'summary', '')}")
        if reason:
            hint = getattr(entry.factory, "install_hint", "")
            print(f"  unavailable: {reason}" + (f"\n  install: {hint}" if hint else ""))
        else:
            try:
                env = entry.factory.environment()
            except Exception as exc:
                env = {"environment": f"unknown ({exc})"}
            for k, v in env.items():
                print(f"  {k}: {v}")
        for mname, spec in sorted(entry.models.items()):
            params = ", ".join(p.name for p in spec.parameters)
            lobes = "lobes" if spec.has_lobes else "no lobe isolation"
            print(f"  model {mname}: {params}  ({lobes})")
    for plugin, err in sorted(registry.broken.items()):
        print(f"broken plugin {plugin}: {err}")
    return 0


def cmd_experiment(kind: str, args: argparse.Namespace) -> int:
    from .experiments import load_experiment, run_experiment
    from .plugins import collect_adapters

    exp = load_experiment(args.experiment)
    if exp.kind != kind:
        raise ConfigError(f"is a {exp.kind} experiment: run it with `remap {exp.kind}`", file=args.experiment,
                          field="kind")
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise ConfigError("exists and is not a folder", field=f"--out {out}")
    registry = collect_adapters()

    def progress(line: str) -> None:
        if not args.quiet:
            print(line, file=sys.stderr, flush=True)

    r = run_experiment(exp, args.experiment, out, registry, progress)
    rows = r.rows
    legs = [x.forward for x in rows] + [x.back for x in rows if x.back is not None]
    print(f"experiment     {exp.name}" + (f"  ({exp.figure})" if exp.figure else ""))
    print(f"points         {len(rows)}  ({r.resumed} remaps resumed from {out}/points)")
    print(f"flagged        {sum(x.flagged for x in rows)}  (unreliable "
          f"{sum(x.forward.unstable or (x.back is not None and x.back.unstable) for x in rows)}, "
          f"after a cliff {sum(bool(x.cliff) for x in rows)}); above the error threshold by model mismatch "
          f"alone: {sum(x.mismatch for x in rows)}")
    print(f"cliffs         {len(r.cliffs)}")
    for c in r.cliffs:
        print(f"  {c['why'][0]}")
    if r.fit:
        f = r.fit
        print(f"round trip     slope {f['slope']:.4f}, intercept {f['intercept']:.4f}, R² {f['r2']:.5f}, "
              f"RMS from unit line {f['rms_from_unit_line']:.4f} over {f['points']} unflagged values")
    print(f"median error   {np.median([x.forward.relative_rmse for x in rows]):.2%} (forward)")
    print(f"renders        {sum(leg.renders for leg in legs if not leg.resumed)} target renders this run")
    print(f"seconds        {r.seconds:.1f}")
    print(f"wrote          {out}/ ({', '.join(p.name for p in r.files)})")
    return 0


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    debug = "--debug" in argv
    interrupt.install()
    try:
        if argv and argv[0] == "adapters":
            return cmd_adapters(_adapters_parser().parse_args(argv[1:]))
        if argv and argv[0] in ("sweep", "roundtrip"):
            return cmd_experiment(argv[0], _experiment_parser(argv[0]).parse_args(argv[1:]))
        return cmd_remap(_remap_parser().parse_args(argv))
    except RemapError as exc:
        if debug:
            raise
        print(f"remap: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt:
        print("remap: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # `remap ... | head`: the reader left; results are already written
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0


if __name__ == "__main__":
    sys.exit(main())
