"""Atomic file writes: a reader never sees half a file; an interrupted run leaves the old one.

A write goes to a hidden temporary file beside its target (`.NAME.XXXXXXXX.ext`) and is renamed
over it; a write that fails (a full disk) is one ConfigError naming the file and the reason, and
leaves the previous file as it was. Temporary files a killed run left beside a target are
removed the next time that target is written."""

from __future__ import annotations

import errno
import json
import os
import re
import tempfile
from pathlib import Path
from typing import Any

from .errors import ConfigError


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


_MODE = 0o666 & ~_umask()
"""What a file created with open() would get: results are meant to be shared (mkstemp gives 0600)."""


def why(exc: OSError) -> str:
    """An OS error's reason in words."""
    if exc.errno == errno.ENOSPC:
        return "no space left on the device"
    if exc.errno == errno.ENAMETOOLONG:
        return "the name is too long for the filesystem"
    return exc.strerror or str(exc)


def temp_beside(path: Path) -> Path:
    """A fresh temporary file in the same folder (so os.replace is atomic), same suffix, with the
    permissions the umask gives a new file; stale ones of the same target are removed first."""
    path = Path(path)
    remove_stale_temps(path)
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=path.suffix, dir=path.parent)
        os.fchmod(fd, _MODE)
        os.close(fd)
    except OSError as exc:
        raise ConfigError(f"cannot write: {why(exc)}", file=str(path)) from None
    return Path(tmp)


def remove_stale_temps(path: Path) -> None:
    """The `.NAME.XXXXXXXX.ext` files a killed write left beside ``path``."""
    pattern = re.compile(rf"^\.{re.escape(path.stem)}\.[A-Za-z0-9_]{{8}}{re.escape(path.suffix)}$")
    try:
        for p in path.parent.iterdir():
            if pattern.match(p.name) and p.is_file():
                p.unlink(missing_ok=True)
    except OSError:
        pass


def write_bytes_atomic(path: Path, data: bytes) -> Path:
    tmp = temp_beside(path)
    try:
        tmp.write_bytes(data)
        os.replace(tmp, path)
    except OSError as exc:
        raise ConfigError(f"cannot write: {why(exc)} (the previous file, if any, is kept)", file=str(path)) from None
    finally:
        tmp.unlink(missing_ok=True)
    return Path(path)


def write_text_atomic(path: Path, text: str) -> Path:
    return write_bytes_atomic(path, text.encode("utf-8"))


def write_json_atomic(path: Path, doc: Any) -> Path:
    return write_text_atomic(path, json.dumps(doc, indent=2, default=float, ensure_ascii=False) + "\n")
