"""Library file formats as plugins: readers turn a file into named source materials, writers turn
converted materials into one native library file.

A reader or writer is registered through the plugin host (`brdfremap_register_formats`), the
built-ins exactly as a third party's. Readers never render; one that needs a renderer's own
libraries to parse a file (a `.blend`) runs them in a worker process of its own."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol

from ..data.errors import ConfigError
from .entries import Converted, Entry, Reader
from .yaml_reader import YamlReader
from ..images.reader import image_folders
from .image_reader import ImagesReader
from ..data.schemas import ParamKind

__all__ = ["Converted", "Entry", "Reader", "Writer", "Formats", "collect_formats", "expand_inputs", "read_all",
           "clip_into"]


class Writer(Protocol):
    name: str
    adapter: str
    """The target adapter whose materials it writes."""
    models: tuple[str, ...]
    """The target models it writes (empty: all)."""

    def write(self, folder: Path, items: list[Converted]) -> list[Path]:
        """Write one library file (or a few) of these materials into ``folder``; return them."""


@dataclass
class Formats:
    readers: list[Any] = field(default_factory=list)
    writers: list[Any] = field(default_factory=list)
    broken: dict[str, str] = field(default_factory=dict)

    def reader_for(self, path: Path) -> Any | None:
        """The reader of this file: the first of its ending that accepts it, else the first of
        its ending (whose error then says what the file is)."""
        mine = [r for r in self.readers if path.suffix.lower() in r.suffixes]
        return next((r for r in mine if r.accepts(path)), mine[0] if mine else None)

    def writers_for(self, adapter: str, models: set[str]) -> list[Any]:
        return [w for w in self.writers if w.adapter == adapter and (not w.models or models & set(w.models))]

    @property
    def suffixes(self) -> set[str]:
        return {s for r in self.readers for s in r.suffixes if s}  # "": a folder (of images)


def collect_formats(pm=None) -> Formats:
    """Every registered reader and writer (the core's YAML reader first)."""
    from ..host.plugins import get_plugin_manager

    pm = pm or get_plugin_manager()
    formats = Formats(readers=[YamlReader(), ImagesReader()])
    for impl in pm.hook.brdfremap_register_formats.get_hookimpls():
        try:
            impl.function(register_reader=formats.readers.append, register_writer=formats.writers.append)
        except Exception as exc:  # a broken plugin is listed with its error, not fatal
            formats.broken[impl.plugin_name] = f"{type(exc).__name__}: {exc}"
    return formats


def expand_inputs(paths: list[str], formats: Formats) -> list[Path]:
    """The files to read: each given file, and the files of a given folder whose ending a reader
    knows (sorted). A missing path is a ConfigError naming it."""
    out: list[Path] = []
    for text in paths:
        p = Path(text)
        if not p.exists():
            raise ConfigError("not found (check the path)", file=text)
        if p.is_dir() and image_folders(p):  # one material's images, or the folders of several
            out += image_folders(p)
        elif p.is_dir():
            found = sorted(f for f in p.iterdir() if f.is_file() and f.suffix.lower() in formats.suffixes
                           and formats.reader_for(f).accepts(f))
            if not found:
                raise ConfigError(f"holds no file this tool reads ({', '.join(sorted(formats.suffixes))})", file=text)
            out += found
        else:
            out.append(p)
    return list(dict.fromkeys(out))


def read_all(paths: list[Path], formats: Formats, *, keep_going: bool = False) -> list[Entry]:
    """Every material of every file, names made unique (a second 'gold' becomes 'file/gold'). A file
    no reader knows is a ConfigError; so is a file that cannot be read, unless ``keep_going``: then
    it is one unreadable entry (named after the file) whose problem is the error, and the other
    files are read all the same."""
    entries: list[Entry] = []
    for p in paths:
        reader = formats.reader_for(p)
        if reader is None:
            raise ConfigError(f"no reader for this kind of file (known endings: {', '.join(sorted(formats.suffixes))})",
                              file=str(p))
        try:
            entries += reader.read(p)
        except ConfigError as exc:
            if not keep_going:
                raise
            entries.append(Entry(name=p.stem, file=str(p), problem=str(exc), unreadable=True))
    return _unique(entries)


def _unique(entries: list[Entry]) -> list[Entry]:
    counts: dict[str, int] = {}
    for e in entries:
        counts[e.name] = counts.get(e.name, 0) + 1
    out, taken = [], set()
    for e in entries:
        name = e.name if counts[e.name] == 1 else f"{Path(e.file).stem}/{e.name}"
        n, candidate = 1, name
        while candidate in taken:
            n += 1
            candidate = f"{name} ({n})"
        taken.add(candidate)
        out.append(e if candidate == e.name else e.model_copy(update={"name": candidate}))
    return out


def clip_into(spec, params: dict) -> list[str]:
    """Move a read value the model's bounds do not reach to the bound, in place, and say so; a
    choice the model does not have is a ConfigError (the material cannot be converted)."""
    notes = []
    for name, v in list(params.items()):
        p = spec.param(name)
        if p.kind == ParamKind.CHOICE:
            if v not in p.choices:
                shown = ", ".join(p.choices[:8]) + (" …" if len(p.choices) > 8 else "")
                raise ConfigError(f"{name} {v!r} is not one of the {spec.name!r} model's choices ({shown})")
            continue
        given = tuple(v) if isinstance(v, (list, tuple)) else v
        clipped = p.clip(given)
        if clipped != given:
            notes.append(f"{name} {_shown(given)} is outside the {spec.name!r} model's bounds [{p.lower:g}, "
                         f"{p.upper:g}]: read as {_shown(clipped)}")
        params[name] = clipped
    return notes


def _shown(v) -> str:
    return "(" + ", ".join(f"{x:.4g}" for x in v) + ")" if isinstance(v, tuple) else f"{v:.4g}"
