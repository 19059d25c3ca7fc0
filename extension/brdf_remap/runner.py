"""brdf-remap run in a process of its own (`remap convert`), from Blender: how to find the tool, one
conversion started, followed, cancelled and read. No bpy here: Blender's Python need not have the
tool installed, and nothing here blocks Blender's interface."""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
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
        probe = subprocess.run([python, "-c", "import brdfremap"], capture_output=True, timeout=120)
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
        out.mkdir(parents=True, exist_ok=True)
        log = out / "extension.log"
        argv = [*command, "convert", *map(str, inputs), "--to", to, "--out", str(out), "--events",
                str(out / "events.jsonl"), "--quiet", *QUALITY[quality]]
        for name in only:
            argv += ["--only", name]
        with log.open("w", encoding="utf-8") as f:  # the child keeps its own handle
            process = subprocess.Popen(argv, stdout=f, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                                       start_new_session=True)  # its renderers' processes are cancelled with it
        return cls(out, process, log)

    def progress(self) -> tuple[int, int, str]:
        """(done, of, the last finished material's title) of the pass under way; (0, 0, "") before any."""
        try:
            lines = (self.out / "events.jsonl").read_text(encoding="utf-8").splitlines()
        except OSError:
            return 0, 0, ""
        last = json.loads(lines[-1]) if lines and lines[-1].strip() else None
        return (last["done"], last["of"], last["title"]) if last else (0, 0, "")

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
            except ProcessLookupError:
                return
            try:
                self.process.wait(20)
            except subprocess.TimeoutExpired:
                os.killpg(self.process.pid, signal.SIGKILL)

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
