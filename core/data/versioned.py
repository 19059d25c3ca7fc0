"""The tool's own versioned JSON files read back, through one reader: a result's report and a remap
table. Each names its format, the versions this tool reads, and what to do with another; an edited
file is refused by its digest. (`convert.json`, `lookup.json` and `summary.json` carry a
`schema_version` too, for readers of them; the tool itself does not read them back.)"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TypeVar

from pydantic import BaseModel, ValidationError

from .configio import validation_message
from .errors import ConfigError

M = TypeVar("M", bound=BaseModel)


@dataclass(frozen=True)
class JsonFormat:
    """A versioned JSON format of the tool's."""

    kind: str
    """What it is called in a message: "report schema", "table format"."""
    reads: tuple[int, ...]
    """The versions read, oldest first; the last is the one written."""
    older: str
    """What to do with a file of an older version (or of none)."""
    missing: str = "file not found (check the path)"
    edited: str = "was edited after it was written (its digest does not match its content)"
    newer_error: type[ConfigError] = ConfigError

    @property
    def current(self) -> int:
        return self.reads[-1]

    def span(self) -> str:
        return str(self.current) if len(self.reads) == 1 else f"{self.reads[0]} to {self.current}"


def read_json(path: Path, fmt: JsonFormat) -> Any:
    """The JSON document in a file; a missing or unreadable one is one line naming it."""
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise ConfigError(fmt.missing, file=str(path)) from None
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise ConfigError(f"cannot read it as JSON: {exc}", file=str(path)) from None


def check_version(doc: dict, fmt: JsonFormat, file: str) -> None:
    """A version this tool reads, or a ConfigError saying which it is and what to do."""
    version = doc.get("schema_version")
    if not isinstance(version, int):
        raise ConfigError(f"written by an older brdf-remap (before {fmt.kind} {fmt.reads[0]}): {fmt.older}", file=file)
    if version > fmt.current:
        raise fmt.newer_error(f"written by a newer brdf-remap ({fmt.kind} {version}; this one reads {fmt.span()}): "
                              "upgrade brdf-remap to read it", file=file)
    if version not in fmt.reads:
        raise ConfigError(f"written by an older brdf-remap ({fmt.kind} {version}; this one reads {fmt.span()}): "
                          f"{fmt.older}", file=file)


def parse(doc: dict, model: type[M], fmt: JsonFormat, file: str, digest: str | None = None) -> M:
    """The model of a document whose version `check_version` accepted; where the format keeps a
    digest (``digest``: the name of the model's field), one that does not match is an edited file."""
    try:
        obj = model.model_validate(doc)
    except ValidationError as exc:
        field, msg = validation_message(exc)
        raise ConfigError(msg, file=file, field=field) from None
    if digest is not None and doc.get(digest) != getattr(obj, digest):
        raise ConfigError(fmt.edited, file=file)
    return obj
