"""One conversion from Blender at a time: what it is for (a remap, an export, an import), the tool's
process following it, its results, and what accepting them does to the open file. Nothing of the
file changes until a result is accepted (`Session.accept`), in one undoable step."""

from __future__ import annotations

import tempfile
from dataclasses import dataclass, field
from pathlib import Path

from . import blend, results
from .runner import Job, JobFailed, Refused, ToolMissing, tool_command

MODELS = (("principled", "Principled BSDF"), ("metallic", "Metallic BSDF"), ("glossy", "Glossy BSDF"),
          ("diffuse", "Diffuse BSDF"))
"""The Cycles models a material can be remapped to (the Cycles adapter's)."""


@dataclass(frozen=True)
class Export:
    label: str
    to: str
    library: str
    """The suffix of the library the export is."""


EXPORTS = {"GLTF": Export("glTF (judged in three.js)", "threejs", ".gltf"),
           "MITSUBA": Export("Mitsuba XML", "mitsuba", ".xml"),
           "MATERIALX": Export("MaterialX (OpenPBR, judged in MaterialX's renderer)", "materialx:open_pbr_surface", ".mtlx")}


@dataclass
class Remap:
    """Remapped to another Cycles model: accepted, in place of each material or beside it."""

    model: str
    in_place: bool
    accepts = True

    def title(self) -> str:
        return f"remap to {self.model}" + (" in place" if self.in_place else " as copies")

    def apply(self, rows: list[results.Row], libs: dict[str, Path]) -> str:
        import bpy

        names = [r.name for r in rows if r.converted]
        for name, new in blend.load_materials(libs[".blend"], names).items():
            old = bpy.data.materials.get(name)
            if self.in_place and old is not None:
                blend.replace(old, new)
            else:
                blend.keep_beside(new, name, self.model)
        return f"{len(names)} material(s) remapped to {self.model}" + (" in place" if self.in_place else "")


@dataclass
class Import:
    """Another renderer's materials, remapped to Cycles: accepted, added to the file."""

    file: Path
    accepts = True

    def title(self) -> str:
        return f"import {self.file.name}"

    def apply(self, rows: list[results.Row], libs: dict[str, Path]) -> str:
        added = blend.load_materials(libs[".blend"], [r.name for r in rows if r.converted])
        for new in added.values():
            new.use_fake_user = True  # no object uses it yet: kept when the file is saved
        return f"{len(added)} material(s) imported from {self.file.name}: " + ", ".join(m.name for m in added.values())


@dataclass
class Exported:
    """Written next to the .blend: nothing to accept."""

    export: Export
    accepts = False

    def title(self) -> str:
        return f"export to {self.export.label}"

    def apply(self, rows: list[results.Row], libs: dict[str, Path]) -> str:
        lib = libs.get(self.export.library)
        return f"wrote {lib}" if lib else f"no {self.export.library} was written: no material converted"


@dataclass
class Session:
    job: Job | None = None
    kind: object | None = None
    rows: list[results.Row] = field(default_factory=list)
    libs: dict[str, Path] = field(default_factory=dict)
    out: Path | None = None
    message: str = ""
    pending: bool = False
    checked: dict[str, list[str] | str] = field(default_factory=dict)
    """The tool's command, or why it cannot run, by the Python the preferences name."""

    def command(self, python: str) -> list[str]:
        """The tool's command; a failure is checked again each time (the user may have installed it since)."""
        if not isinstance(self.checked.get(python), list):
            try:
                self.checked[python] = tool_command(python)
            except ToolMissing as exc:
                self.checked[python] = str(exc)
        found = self.checked[python]
        if isinstance(found, str):
            raise ToolMissing(found)
        return found

    def start(self, command: list[str], kind, inputs: list[Path], to: str, out: Path, quality: str) -> None:
        if self.job is not None and self.job.running():
            raise Refused("a conversion is under way: wait for it or cancel it")
        self.discard()
        self.kind, self.out, self.message = kind, out, f"{kind.title()}: starting"
        self.job = Job.start(command, inputs, to, out, quality)

    def progress(self) -> tuple[int, int, str]:
        return self.job.progress() if self.job is not None else (0, 0, "")

    def finish(self) -> None:
        """The job's results read; an export's message said; a remap or an import waits to be accepted."""
        try:
            summary = self.job.summary()
        except JobFailed as exc:
            self.message, self.job = f"{self.kind.title()} failed: {exc}", None
            return
        self.rows, self.libs = results.rows(summary, self.out), results.libraries(summary, self.out)
        self.job = None
        counts = _counts(self.rows)
        if self.kind.accepts:
            self.pending = any(r.converted for r in self.rows)
            self.message = f"{self.kind.title()}: {counts}" + ("; accept to apply" if self.pending else "")
        else:
            self.message = f"{self.kind.title()}: {counts}; {self.kind.apply(self.rows, self.libs)}"

    def accept(self) -> str:
        if not self.pending:
            return "nothing to accept"
        library = self.libs.get(".blend")
        if library is None or not library.is_file():
            raise Refused("the conversion wrote no library.blend to accept from: see its report")
        try:
            self.message = self.kind.apply(self.rows, self.libs)
        except OSError as exc:  # a library.blend this Blender cannot read (written by a newer one)
            raise Refused(f"cannot read {library}: {exc}") from None
        self.pending = False
        return self.message

    def cancel(self) -> None:
        if self.job is not None:
            self.job.cancel()
            self.message, self.job = f"{self.kind.title()}: cancelled", None

    def discard(self) -> None:
        self.rows, self.libs, self.pending, self.message = [], {}, False, ""

    def lines(self) -> list[str]:
        """What the panel shows, as text (the test prints it)."""
        out = [self.message] if self.message else []
        if self.job is not None:
            done, of, title = self.progress()
            out.append(f"running: {done}/{of or '?'}" + (f", last {title}" if title else ""))
        out += [f"{r.name}: {r.line()}" for r in self.rows]
        return out


def _counts(rows: list[results.Row]) -> str:
    by: dict[str, int] = {}
    for r in rows:
        by[r.status] = by.get(r.status, 0) + 1
    return f"{len(rows)} material(s): " + ", ".join(f"{n} {s}" for s, n in sorted(by.items()))


def scratch() -> Path:
    """A folder of the tool's own for one remap or import (the user's files are not touched)."""
    return Path(tempfile.mkdtemp(prefix="brdf-remap-"))


SESSION = Session()
