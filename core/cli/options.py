"""Flags shared by the commands, built from the models they fill: `Settings` (how a fit runs),
the scene overrides, and where jobs run. Defaults are read from the models, never restated."""

from __future__ import annotations

import argparse
import typing
from enum import Enum

from pydantic import ValidationError

from ..data.configio import validation_message
from ..data.errors import ConfigError
from ..data.scene import ProbeScene, load_scene
from ..data.settings import DEFAULTS, Settings

_METAVARS = {"starts": "N", "coarse": "N", "precise_spp": "K", "threshold": "FRACTION", "resolve_limit": "FRACTION", "jacobian_updates": "N"}


class Parser(argparse.ArgumentParser):
    """argparse whose usage errors are one line, like every other error of `remap`."""

    def error(self, message: str):  # type: ignore[override]
        self.exit(2, f"remap: error: {message} (see `{self.prog} --help`)\n")


_FLAGS = {"validation": "--validate"}


def flag(field: str) -> str:
    return _FLAGS.get(field, "--" + field.replace("_", "-"))


def add_settings(p: argparse.ArgumentParser) -> None:
    """One flag per `Settings` field, its help the field's description and its default shown."""
    g = p.add_argument_group("how the fit runs")
    for name, info in Settings.model_fields.items():
        text = f"{info.description.rstrip('.')} (default {getattr(DEFAULTS, name)})"
        kw: dict = {"dest": f"settings_{name}", "default": None, "help": text.replace("%", "%%")}
        kind = info.annotation
        choices = tuple(m.value for m in kind) if isinstance(kind, type) and issubclass(kind, Enum) else \
            typing.get_args(kind)
        if choices and all(isinstance(c, str) for c in choices):
            kw["choices"] = choices
        else:
            kw.update(type=type(info.default), metavar=_METAVARS.get(name, "X"))
        g.add_argument(flag(name), **kw)


def settings_from(args: argparse.Namespace, base: Settings = DEFAULTS) -> Settings:
    """The settings the flags give, the others as in ``base``."""
    given = {name: getattr(args, f"settings_{name}") for name in Settings.model_fields
             if getattr(args, f"settings_{name}", None) is not None}
    try:
        return Settings(**{**base.model_dump(), **given})
    except ValidationError as exc:
        field, msg = validation_message(exc)
        raise ConfigError(msg, field=flag(field)) from None


def add_scene(p: argparse.ArgumentParser) -> None:
    p.add_argument("--scene", metavar="SCENE.yaml", help="probe scene (default: the built-in probe, identical to "
                                                         "configs/scenes/default.yaml)")
    p.add_argument("--resolution", type=int, metavar="N", help="override the scene's resolution (pixels)")
    p.add_argument("--spp", type=int, metavar="N", help="override the scene's samples per pixel")
    p.add_argument("--seed", type=int, metavar="N", help="override the scene's sampler seed")


def scene_from(args: argparse.Namespace, base: ProbeScene | None = None) -> ProbeScene:
    """The scene the flags give (`--scene`, else ``base``, else the built-in probe), overridden."""
    scene = load_scene(args.scene) if args.scene else (base or ProbeScene())
    try:
        return scene.overridden(resolution=args.resolution, spp=args.spp, seed=args.seed)
    except ValidationError as exc:
        field, msg = validation_message(exc)
        raise ConfigError(msg, field=f"--{field}") from None


def add_workers(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("where the jobs run")
    g.add_argument("--jobs", type=int, default=1, metavar="N",
                   help="run N jobs at once in local worker processes (default 1: in this process)")
    g.add_argument("--scheduler", metavar="ADDRESS",
                   help="run the jobs on a Dask distributed cluster (e.g. tcp://host:8786); every worker needs "
                        "brdf-remap and the renderers installed")


def add_common(p: argparse.ArgumentParser) -> None:
    p.add_argument("--quiet", action="store_true", help="no progress lines")
    p.add_argument("--debug", action="store_true", help="show tracebacks")
