"""Atomic file writes: a reader never sees half a file; an interrupted run leaves the old one."""

from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path
from typing import Any


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


_MODE = 0o666 & ~_umask()
"""What a file created with open() would get: results are meant to be shared (mkstemp gives 0600)."""


def temp_beside(path: Path) -> Path:
    """A fresh temporary file in the same folder (so os.replace is atomic), same suffix, with the
    permissions the umask gives a new file."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=path.suffix, dir=path.parent)
    os.fchmod(fd, _MODE)
    os.close(fd)
    return Path(tmp)


def write_text_atomic(path: Path, text: str) -> Path:
    tmp = temp_beside(path)
    try:
        tmp.write_text(text, encoding="utf-8")
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)
    return Path(path)


def write_bytes_atomic(path: Path, data: bytes) -> Path:
    tmp = temp_beside(path)
    try:
        tmp.write_bytes(data)
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)
    return Path(path)


def write_json_atomic(path: Path, doc: Any) -> Path:
    return write_text_atomic(path, json.dumps(doc, indent=2, default=float, ensure_ascii=False) + "\n")
