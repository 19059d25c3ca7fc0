"""Atomic file writes: a reader never sees half a file; an interrupted run leaves the old one."""

from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path
from typing import Any


def temp_beside(path: Path) -> Path:
    """A fresh temporary file in the same folder (so os.replace is atomic), same suffix."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=path.suffix, dir=path.parent)
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
