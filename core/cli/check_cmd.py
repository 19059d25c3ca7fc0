"""`remap check ADAPTER [--model M]`: the adapter contract from the command line (`core.host.check`)."""

from __future__ import annotations

import argparse

from ..data.errors import ConfigError
from . import options
from ..data.scene import LightType


def parser() -> argparse.ArgumentParser:
    p = options.Parser(prog="remap check", description="Check that an adapter keeps the conventions every "
                       "renderer must share (images, units, orientation, determinism, seeds, lobes, precision, light "
                       "through a glass); exit 0 only when every check passes.")
    p.add_argument("adapter", metavar="ADAPTER", help="an installed adapter's name, or a renderer definition file")
    p.add_argument("--model", action="append", help="check only this model (repeatable; default: every model)")
    p.add_argument("--debug", action="store_true", help="show tracebacks")
    return p


def run(args: argparse.Namespace) -> int:
    from ..host.check import run as run_checks
    from ..host.protocol import plugin_call
    from ..host.plugins import collect_adapters

    registry = collect_adapters()
    name = registry.resolve(args.adapter, field_name="ADAPTER")
    entry = registry.get(name, field_name="ADAPTER")
    reason = entry.unavailable_reason()
    if reason:
        raise ConfigError(f"adapter {name!r} is unavailable: {reason}", field="ADAPTER")
    unknown = [m for m in args.model or [] if m not in entry.models]
    if unknown:
        raise ConfigError(f"adapter {name!r} has no model {unknown[0]!r} (models: {', '.join(sorted(entry.models))})",
                          field="--model")
    models = {m: s for m, s in entry.models.items() if not args.model or m in args.model}
    white = getattr(entry.factory, "calibration", None)
    if white is not None:
        white = (white[0], entry.models[white[0]].complete(white[1], file=f"adapter {name!r}", prefix="calibration.params"))
    glass = getattr(entry.factory, "glasses", {}).get("smooth")
    if glass is not None:
        glass = (glass[0], entry.models[glass[0]].complete(glass[1], file=f"adapter {name!r}", prefix="glasses.smooth"))
    mirror = getattr(entry.factory, "mirror", None)
    if mirror is not None:
        mirror = (mirror[0], entry.models[mirror[0]].complete(mirror[1], file=f"adapter {name!r}", prefix="mirror"))
    adapter = registry.create(name)
    try:
        rows = run_checks(lambda model, params, scene, lobe=None: plugin_call(
                              adapter.render, f"adapter {name!r}", adapter.models[model], params, scene, lobe), models,
                          white, glass, LightType.ENVIRONMENT in entry.light_types,
                          entry.factory.transmission_limit, mirror)
    finally:
        adapter.close()
    width = max(len(r.name) for r in rows)
    print(f"remap check {name}: {len(models)} model(s)")
    for r in rows:
        mark = "limit" if r.by_design else {True: "pass", False: "FAIL", None: "not run"}[r.passed]
        label = "why" if r.by_design else "fix"
        print(f"  {mark:<7} {r.name:<{width}}  {r.detail}" + (f"\n  {'':<7} {'':<{width}}  {label}: {r.fix}"
                                                               if r.fix and not r.passed else ""))
    failed = [r for r in rows if not r.passed and not r.by_design]
    limits = [r for r in rows if r.by_design]
    print("all checks pass" if not failed and not limits else
          f"{len(failed)} of {len(rows)} checks do not pass" if failed else
          f"every other check passes; {len(limits)} is a limit of the renderer's design, said above (a glass "
          "remapped to or from it is judged beyond the two renderers' own difference on a glass)")
    return 0 if not failed else 1
