"""The result store: one folder per job (a slot), each holding a complete result or none.

A slot holds `result.json` and the files it lists (images, the native material), with their
hashes, and the report its own digest: a result is found by its job's key and trusted only when
all of it matches. A new result is written into a staging folder first; the previous one is
moved aside into a backup folder, the new one moved in (`result.json` last), and the backup
removed. A kill at any moment leaves the previous result or the new one: a backup found at the
next run is put back unless the new result is whole. A full disk fails while staging, leaving
the previous result untouched. An output folder is owned by one run at a time (`owned`), and a
folder holding another program's `result.json` is not written into."""

from __future__ import annotations

import fcntl
import hashlib
import json
import os
import shutil
import tempfile
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Iterator

from ..data.atomic import why
from ..data.errors import ConfigError
from ..job.execute import IMAGES, Outcome
from ..job.report import NewerReportError, Report, read_report

RESULT = "result.json"
STAGING = ".staging-"
BACKUP = ".previous-"
LOCK = ".lock"


def check_folder(path: str | Path, flag: str = "--out") -> Path:
    """Create the output folder (and its parents) and prove it writable, before any render."""
    if str(path).strip() == "":
        raise ConfigError("is empty: give a folder to write into", field=flag)
    p = Path(path)
    try:
        if p.is_symlink() and not p.exists():
            raise ConfigError("is a symbolic link to nothing (a dangling or looping link): remove it or choose "
                              "another folder", field=f"{flag} {p}")
        if p.exists() and not p.is_dir():
            raise ConfigError("exists and is not a folder", field=f"{flag} {p}")
        p.mkdir(parents=True, exist_ok=True)
        tempfile.NamedTemporaryFile(prefix=".probe-", dir=p).close()
    except OSError as exc:
        raise ConfigError(f"cannot write here: {why(exc)}", field=f"{flag} {p}") from None
    for name in (RESULT, *IMAGES):
        if (p / name).is_dir():
            raise ConfigError(f"holds a folder named {name}, where the result goes: move it", field=f"{flag} {p}")
    return p


@contextmanager
def owned(path: str | Path, flag: str = "--out") -> Iterator[Path]:
    """The folder, checked and locked for this run: a second run into it gets a clear error
    (the lock is the kernel's, released however this process ends)."""
    folder = check_folder(path, flag)
    try:
        fd = os.open(folder / LOCK, os.O_RDWR | os.O_CREAT, 0o644)
    except OSError as exc:
        raise ConfigError(f"cannot take the folder's lock {folder / LOCK}: {why(exc)}", field=f"{flag} {folder}") \
            from None
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise ConfigError("another brdf-remap run is writing this folder; wait for it to finish or choose "
                              "another one", field=f"{flag} {folder}") from None
        check_not_owned(folder, flag)
        os.ftruncate(fd, 0)
        os.write(fd, f"{os.getpid()}\n".encode())
        _tidy(folder)
        yield folder
    finally:
        os.close(fd)


def check_not_owned(folder: Path, flag: str = "--out") -> None:
    """A folder inside one another run owns (a sweep's point) is that run's to write."""
    for parent in Path(folder).resolve().parents:
        lock = parent / LOCK
        if not lock.is_file():
            continue
        try:
            fd = os.open(lock, os.O_RDONLY)
        except OSError:
            continue
        try:
            fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
        except BlockingIOError:
            raise ConfigError(f"is inside {parent}, which another brdf-remap run is writing; wait for it to finish "
                              "or choose a folder outside it", field=f"{flag} {folder}") from None
        finally:
            os.close(fd)


@dataclass(frozen=True)
class Stored:
    """What a slot holds: a complete result, or why what is there cannot be used."""

    report: Report | None = None
    problem: str = ""
    """Why a result that is there cannot be used ("" when there is none, or it is whole)."""
    newer: bool = False
    """Written by a newer brdf-remap: neither read nor overwritten."""


class Store:
    """Results under ``root``, one slot (a relative folder name; "" for ``root`` itself) per job."""

    def __init__(self, root: str | Path):
        self.root = Path(root)

    def folder(self, slot: str) -> Path:
        return self.root / slot if slot else self.root

    def inspect(self, slot: str) -> Stored:
        """The slot's complete result, or why what is there cannot be used."""
        folder = self.folder(slot)
        _recover(folder)
        if not (folder / RESULT).exists():
            return Stored()
        try:
            report = read_report(folder / RESULT)
        except NewerReportError as exc:
            return Stored(problem=str(exc), newer=True)
        except ConfigError as exc:
            return Stored(problem=str(exc))
        for f in report.files:
            if not _matches(folder / f.name, f.sha256, f.bytes):
                return Stored(problem=f"{folder / f.name} is missing or does not match its result.json")
        return Stored(report)

    def find(self, slot: str, key: str) -> Report | None:
        """The slot's result if it is whole and of the job with this key."""
        report = self.inspect(slot).report
        return report if report is not None and report.key == key else None

    def tidy(self, slot: str) -> None:
        """What a killed write left in the slot (a staging folder; the result was whole before the
        kill, or its swap is put back), for a run that owns the store and reuses the result there."""
        _tidy(self.folder(slot))

    def save(self, slot: str, outcome: Outcome) -> list[Path]:
        """Write the outcome's files and its report into the slot; return the paths written."""
        folder = self.folder(slot)
        try:
            folder.mkdir(parents=True, exist_ok=True)
            _tidy(folder)
            ours, previous = _previous(folder / RESULT)  # read once: whose it is, and what it lists
            if not ours:
                raise ConfigError(f"holds a {RESULT} that brdf-remap did not write: not replaced (choose another "
                                  "folder)", file=str(folder))
            staging = Path(tempfile.mkdtemp(prefix=STAGING, dir=folder))
        except OSError as exc:
            raise ConfigError(f"cannot write: {why(exc)}", file=str(folder)) from None
        try:
            return self._swap_in(folder, staging, outcome, previous)
        finally:
            shutil.rmtree(staging, ignore_errors=True)

    def _swap_in(self, folder: Path, staging: Path, outcome: Outcome, previous: dict | None) -> list[Path]:
        doc = json.dumps(outcome.report.document(), indent=2, ensure_ascii=False) + "\n"
        for name, data in [*outcome.files.items(), (RESULT, doc.encode())]:
            _write(staging / name, data, folder / name)
        moving = folder
        try:
            backup = Path(tempfile.mkdtemp(prefix=BACKUP, dir=folder))
            for name in [RESULT, *sorted(_listed_files(folder, previous))]:
                if (folder / name).is_file():
                    os.replace(folder / name, backup / name)  # the previous result, aside, whole
            for name in [*outcome.files, RESULT]:
                moving = folder / name
                os.replace(staging / name, moving)
            shutil.rmtree(backup, ignore_errors=True)
        except OSError as exc:
            raise ConfigError(f"cannot move the result into place: {why(exc)} (the previous result is put back at "
                              "the next run)", file=str(moving)) from None
        return [folder / n for n in outcome.files] + [folder / RESULT]


def _write(path: Path, data: bytes, shown: Path) -> None:
    try:
        with open(path, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
    except OSError as exc:
        raise ConfigError(f"cannot write: {why(exc)} (the previous result, if any, is kept)",
                          file=str(shown)) from None


def _previous(path: Path) -> tuple[bool, dict | None]:
    """Whether the result.json there (if any) was written by brdf-remap (this format, or the one
    before it), and its document where it was and could be read."""
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        return True, None
    except (OSError, ValueError):
        return True, None  # unreadable or half-written: ours to replace (nothing else writes this name here)
    if not isinstance(doc, dict):
        return False, None
    tool = doc.get("tool")
    ours = (isinstance(tool, str) and tool.split(" ", 1)[0] == "brdf-remap") or {"engine", "metrics", "options"} <= set(doc)
    return ours, doc if ours else None


def _listed_files(folder: Path, doc: dict | None) -> set[str]:
    """The files the previous brdf-remap result (its document ``doc``) owns beside its result.json:
    those it lists with their hash, and only while they still have it. A listed name alone proves
    nothing (a result.json can be written by anyone): a file that is not byte for byte what
    brdf-remap wrote is never moved aside, hence never deleted."""
    if doc is None:
        return set()
    try:
        records = [(f["name"], f["sha256"], f["bytes"]) for f in doc.get("files", []) if isinstance(f, dict)]
    except (OSError, ValueError, TypeError, KeyError, AttributeError):
        return set()
    return {n for n, sha, size in records
            if isinstance(n, str) and n and "/" not in n and n not in (".", "..", RESULT)
            and isinstance(sha, str) and isinstance(size, int) and _matches(folder / n, sha, size)}


def _matches(path: Path, sha256: str, size: int) -> bool:
    try:
        if path.stat().st_size != size:
            return False
        return hashlib.sha256(path.read_bytes()).hexdigest() == sha256
    except OSError:
        return False


def _recover(folder: Path) -> None:
    """A swap a kill interrupted: if the new result did not become whole, the previous one is
    put back from its backup; the backup goes either way."""
    try:
        backups = sorted(folder.glob(BACKUP + "*"))
    except OSError:
        return
    for backup in backups:
        new = folder / RESULT
        whole = new.exists() and _complete(folder)
        if not whole:
            for f in backup.iterdir():
                os.replace(f, folder / f.name)
        shutil.rmtree(backup, ignore_errors=True)


def _complete(folder: Path) -> bool:
    try:
        report = read_report(folder / RESULT)
    except ConfigError:
        return False
    return all(_matches(folder / f.name, f.sha256, f.bytes) for f in report.files)


def _tidy(folder: Path) -> None:
    """Staging folders left by a run that was killed; a backup of an interrupted swap put back
    (safe: this run owns the folder)."""
    _recover(folder)
    try:
        for p in folder.glob(STAGING + "*"):
            shutil.rmtree(p, ignore_errors=True)
    except OSError:
        pass
