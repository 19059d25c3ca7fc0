"""The `remap` command. Bad input prints one line naming the file and field, and exits 2.

Each command lives in its own module (`remap_cmd`, `experiment_cmd`, `tools`); this one only
dispatches and turns the errors a user should read into one line."""

from __future__ import annotations

import os
import sys
import traceback

from ..data.errors import ConfigError, RemapError
from ..run import interrupt

EXIT_USAGE = 2
COMMANDS = ("convert", "table", "render", "scene", "sweep", "roundtrip", "schema", "adapters", "check")


def _dispatch(argv: list[str]) -> int:
    from . import check_cmd, convert_cmd, experiment_cmd, remap_cmd, scene_cmd, table_cmd, tools

    handlers = {
        "adapters": lambda rest: tools.adapters(tools.adapters_parser().parse_args(rest)),
        "schema": lambda rest: tools.schema(tools.schema_parser().parse_args(rest)),
        "check": lambda rest: check_cmd.run(check_cmd.parser().parse_args(rest)),
        "render": lambda rest: tools.render(tools.render_parser().parse_args(rest)),
        "table": table_cmd.run,
        "scene": lambda rest: scene_cmd.run(scene_cmd.parser().parse_args(rest)),
        "convert": lambda rest: convert_cmd.run(convert_cmd.parser().parse_args(rest)),
        **{kind: (lambda rest, kind=kind: experiment_cmd.run(kind, experiment_cmd.parser(kind).parse_args(rest)))
           for kind in ("sweep", "roundtrip")},
    }
    head, rest = (argv[0], argv[1:]) if argv else ("", [])
    if head in handlers:
        return handlers[head](rest)
    if head and head.lstrip("-") == head:  # a word where a command goes, not a flag of the one-material form
        raise ConfigError(f"unknown command {head!r} (commands: {', '.join(COMMANDS)}; or `remap --adapter A --model M "
                          "--source MATERIAL.yaml --out DIR` for one material; see `remap --help`)")
    return remap_cmd.run(remap_cmd.parser().parse_args(argv))


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    debug = "--debug" in argv
    interrupt.install()
    try:
        return _dispatch(argv)
    except RemapError as exc:
        if debug:
            traceback.print_exc()
        print(f"remap: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except (KeyboardInterrupt, interrupt.Terminated):
        # A signal may come back as either (a renderer turned it into its own error and the next
        # check raised it again): the signal that came decides what is said and the status.
        status = interrupt.exit_status()
        print("remap: interrupted" if status == 130 else "remap: terminated", file=sys.stderr)
        return status
    except BrokenPipeError:  # `remap ... | head`: the reader left; results are already written
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except OSError as exc:  # stdout or stderr gone (`remap ... > /dev/full`): results are already written
        try:
            print(f"remap: error: cannot write the output: {exc.strerror or exc}", file=sys.stderr)
        except OSError:
            pass
        return EXIT_USAGE


if __name__ == "__main__":
    sys.exit(main())
