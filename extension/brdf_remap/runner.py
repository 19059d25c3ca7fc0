"""brdf-remap run in a process of its own (`remap convert`), from Blender: how to find the tool, one
conversion started, followed, cancelled and read. No bpy here: Blender's Python need not have the
tool installed, and nothing here blocks Blender's interface."""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import tempfile
from dataclasses import dataclass
from pathlib import Path

QUALITY = {"DRAFT": ["--resolution", "32", "--spp", "8"], "DEFAULT": []}
"""Render settings each quality passes to `remap convert` (draft: a first look in seconds)."""


class Refused(Exception):
    """A conversion cannot start: one line saying what to do."""


class ToolMissing(Refused):
    """brdf-remap cannot be run: one line saying what to set."""


class JobFailed(Exception):
    """The conversion stopped without a summary: its last line of output."""


def tool_command(python: str = "") -> list[str]:
    """The command that runs brdf-remap: the Python the preferences name (or $BRDF_REMAP_PYTHON)
    with `-m brdfremap.core.cli`, else `remap` on the PATH."""
    python = python or os.environ.get("BRDF_REMAP_PYTHON", "")
    if python:
        if not Path(python).is_file():
            raise ToolMissing(f"no Python at {python}: name the Python of a brdf-remap installation in the "
                              "add-on's preferences")
        try:  # run from a folder of no package: Python puts the current folder first on its path
            probe = subprocess.run([python, "-c", "import brdfremap"], capture_output=True, timeout=60,
                                   cwd=tempfile.gettempdir())
        except (OSError, subprocess.SubprocessError) as exc:
            raise ToolMissing(f"cannot run {python}: {exc}; name the Python of a brdf-remap installation in the "
                              "add-on's preferences") from None
        if probe.returncode != 0:
            raise ToolMissing(f"{python} has no brdf-remap: install it there (pip install /path/to/brdf-remap) "
                              "or name another Python in the add-on's preferences")
        return [python, "-m", "brdfremap.core.cli"]
    remap = shutil.which("remap")
    if remap:
        return [remap]
    raise ToolMissing("brdf-remap not found: name the Python of its installation in the add-on's preferences "
                      "(e.g. /path/to/brdf-remap/.venv/bin/python)")


@dataclass
class Job:
    """One `remap convert` running in a process of its own, its output in ``out``."""

    out: Path
    process: subprocess.Popen
    log: Path

    @classmethod
    def start(cls, command: list[str], inputs: list[Path], to: str, out: Path, quality: str = "DEFAULT",
              only: tuple[str, ...] = ()) -> "Job":
        out = Path(out)
        log = out / "extension.log"
        argv = [*command, "convert", "--to", to, "--out", str(out), "--events", str(out / "events.jsonl"),
                "--quiet", *QUALITY[quality]]
        for name in only:
            argv += ["--only", name]
        argv += ["--", *map(str, inputs)]  # a file named like an option is a file
        try:
            out.mkdir(parents=True, exist_ok=True)
            for old in ("convert.json", "events.jsonl"):  # a previous run's, in an export's folder
                (out / old).unlink(missing_ok=True)
            with log.open("w", encoding="utf-8") as f:  # the child keeps its own handle
                process = subprocess.Popen(argv, stdout=f, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                                           cwd=out, start_new_session=True)  # cancelled with its renderers
        except OSError as exc:
            raise Refused(f"cannot start the conversion in {out}: {exc.strerror or exc}") from None
        return cls(out, process, log)

    def progress(self) -> tuple[int, int, str]:
        """(done, of, the last finished material's title) of the pass under way; (0, 0, "") before any."""
        try:
            lines = (self.out / "events.jsonl").read_text(encoding="utf-8").splitlines()
        except OSError:
            return 0, 0, ""
        for line in reversed(lines):  # the last one may be half written
            try:
                last = json.loads(line)
                return last["done"], last["of"], last["title"]
            except (ValueError, KeyError, TypeError):
                continue
        return 0, 0, ""

    def running(self) -> bool:
        return self.process.poll() is None

    def wait(self, timeout: float | None = None) -> None:
        self.process.wait(timeout)

    def cancel(self) -> None:
        """Stops the conversion and every process it started; what finished stays stored (a rerun
        resumes it)."""
        if self.running():
            try:
                os.killpg(self.process.pid, signal.SIGTERM)
                self.process.wait(3)
            except ProcessLookupError:
                return
            except subprocess.TimeoutExpired:
                os.killpg(self.process.pid, signal.SIGKILL)
                self.process.wait(3)

    def summary(self) -> dict:
        """`convert.json`: every material's verdict, error and folder; JobFailed with the tool's last
        line where it wrote none."""
        try:
            return json.loads((self.out / "convert.json").read_text(encoding="utf-8"))
        except (OSError, ValueError):
            raise JobFailed(self.last_line() or f"remap convert stopped (exit {self.process.returncode})") from None

    def last_line(self) -> str:
        try:
            lines = [x for x in self.log.read_text(encoding="utf-8", errors="replace").splitlines() if x.strip()]
        except OSError:
            return ""
        return lines[-1] if lines else ""
