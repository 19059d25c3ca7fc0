"""Scratch folders of adapters (images a renderer writes, request files): in $BRDFREMAP_SCRATCH,
or /dev/shm where it is writable, each named after the process that owns it, so that a folder left by a process
that was killed (`kill -9`, a crash) is found and removed by the next one that starts."""

from __future__ import annotations

import os
import shutil
import tempfile
from pathlib import Path

from .errors import ConfigError

PREFIX = "brdfremap-"


def _base() -> str | None:
    """$BRDFREMAP_SCRATCH if set, else /dev/shm where writable (memory), else the temp folder."""
    chosen = os.environ.get("BRDFREMAP_SCRATCH")
    if chosen:
        return chosen
    shm = "/dev/shm"
    return shm if os.path.isdir(shm) and os.access(shm, os.W_OK) else None


def scratch_dir(kind: str) -> Path:
    """A fresh folder ``brdfremap-<kind>-<pid>-XXXX`` (after removing any whose process is gone)."""
    remove_orphans()
    base = _base()
    try:
        return Path(tempfile.mkdtemp(prefix=f"{PREFIX}{kind}-{os.getpid()}-", dir=base))
    except OSError as exc:
        raise ConfigError(f"cannot create a scratch folder in {base or tempfile.gettempdir()}: "
                          f"{exc.strerror or exc} (set BRDFREMAP_SCRATCH to a writable folder)") from None


def remove_orphans() -> list[Path]:
    """Remove the scratch folders whose owning process no longer runs; return them."""
    base = Path(_base() or tempfile.gettempdir())
    gone = []
    try:
        entries = list(base.glob(PREFIX + "*"))
    except OSError:
        return gone
    for p in entries:
        pid = _owner(p.name)
        stale = not _alive(pid) if pid is not None else _older_than(p, OLD_STYLE_AGE)
        if stale and p.is_dir():
            shutil.rmtree(p, ignore_errors=True)
            gone.append(p)
    return gone


OLD_STYLE_AGE = 24 * 3600
"""Folders named before they carried their process id: removed once a day old (no run lasts that)."""


def _older_than(p: Path, seconds: float) -> bool:
    import time

    try:
        return time.time() - p.stat().st_mtime > seconds
    except OSError:
        return False


def _owner(name: str) -> int | None:
    parts = name[len(PREFIX):].split("-")
    for part in parts[1:-1]:  # brdfremap-<kind>-<pid>-<random>; a kind may hold dashes
        if part.isdigit():
            return int(part)
    return None


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True  # another user's process: not ours to judge
    return True
