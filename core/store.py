"""The result store: one folder per job (a slot), each holding a complete result or none.

A slot holds `result.json` and the files it lists (images, the native material), with their
hashes: a result is found by its job's key and trusted only when every file matches. Files
are written into a fresh folder beside them first and moved in after, `result.json` last: a
full disk or a kill leaves the previous result (or none), never a mixed one. An output folder
is owned by one run at a time (`owned`)."""

from __future__ import annotations

import errno
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

from .errors import ConfigError
from .execute import Outcome
from .report import NewerReportError, Report, read_report

RESULT = "result.json"
STAGING = ".staging-"
LOCK = ".lock"


def check_folder(path: str | Path, flag: str = "--out") -> Path:
    """Create the output folder (and its parents) and prove it writable, before any render."""
    if str(path).strip() == "":
        raise ConfigError("is empty: give a folder to write into", field=flag)
    p = Path(path)
    if p.is_symlink() and not p.exists():
        raise ConfigError("is a symbolic link to nothing (a dangling or looping link): remove it or choose another "
                          "folder", field=f"{flag} {p}")
    if p.exists() and not p.is_dir():
        raise ConfigError("exists and is not a folder", field=f"{flag} {p}")
    try:
        p.mkdir(parents=True, exist_ok=True)
        probe = tempfile.NamedTemporaryFile(prefix=".probe-", dir=p)
        probe.close()
    except OSError as exc:
        raise ConfigError(f"cannot write here: {_why(exc)}", field=f"{flag} {p}") from None
    return p


@contextmanager
def owned(path: str | Path, flag: str = "--out") -> Iterator[Path]:
    """The folder, checked and locked for this run: a second run into it gets a clear error
    (the lock is the kernel's, released however this process ends)."""
    folder = check_folder(path, flag)
    fd = os.open(folder / LOCK, os.O_RDWR | os.O_CREAT, 0o644)
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise ConfigError("another brdf-remap run is writing this folder; wait for it to finish or choose "
                              "another one", field=f"{flag} {folder}") from None
        _check_parents(folder, flag)
        os.ftruncate(fd, 0)
        os.write(fd, f"{os.getpid()}\n".encode())
        _remove_staging(folder)
        yield folder
    finally:
        os.close(fd)


def _check_parents(folder: Path, flag: str) -> None:
    """A folder inside one another run owns (a sweep's point) is that run's to write."""
    for parent in folder.resolve().parents:
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

    def save(self, slot: str, outcome: Outcome) -> list[Path]:
        """Write the outcome's files and its report into the slot; return the paths written."""
        folder = self.folder(slot)
        try:
            folder.mkdir(parents=True, exist_ok=True)
            _remove_staging(folder)
            staging = Path(tempfile.mkdtemp(prefix=STAGING, dir=folder))
        except OSError as exc:
            raise ConfigError(f"cannot write: {_why(exc)}", file=str(folder)) from None
        try:
            return self._swap_in(folder, staging, outcome)
        finally:
            shutil.rmtree(staging, ignore_errors=True)

    def _swap_in(self, folder: Path, staging: Path, outcome: Outcome) -> list[Path]:
        doc = json.dumps(outcome.report.document(), indent=2, ensure_ascii=False) + "\n"
        for name, data in [*outcome.files.items(), (RESULT, doc.encode())]:
            _write(staging / name, data, folder / name)
        previous = _listed_files(folder)
        try:
            (folder / RESULT).unlink(missing_ok=True)  # the old result must not vouch for what follows
            for name in outcome.files:
                os.replace(staging / name, folder / name)
            for name in previous - set(outcome.files):
                (folder / name).unlink(missing_ok=True)  # a file of the old result this one has not
            os.replace(staging / RESULT, folder / RESULT)
        except OSError as exc:
            raise ConfigError(f"cannot move the result into place: {_why(exc)} (rerun to redo it)",
                              file=str(folder)) from None
        return [folder / n for n in outcome.files] + [folder / RESULT]


def _write(path: Path, data: bytes, shown: Path) -> None:
    try:
        with open(path, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
    except OSError as exc:
        raise ConfigError(f"cannot write: {_why(exc)} (the previous result, if any, is kept)",
                          file=str(shown)) from None


def _listed_files(folder: Path) -> set[str]:
    try:
        doc = json.loads((folder / RESULT).read_text(encoding="utf-8"))
        names = {f["name"] if isinstance(f, dict) else f for f in doc.get("files", [])}
    except (OSError, ValueError, TypeError, KeyError, AttributeError):
        return set()
    return {n for n in names if isinstance(n, str) and n and "/" not in n and n not in (".", "..")}


def _matches(path: Path, sha256: str, size: int) -> bool:
    try:
        if path.stat().st_size != size:
            return False
        return hashlib.sha256(path.read_bytes()).hexdigest() == sha256
    except OSError:
        return False


def _remove_staging(folder: Path) -> None:
    """Staging folders left by a run that was killed (safe: this run owns the folder)."""
    try:
        for p in folder.glob(STAGING + "*"):
            shutil.rmtree(p, ignore_errors=True)
    except OSError:
        pass


def _why(exc: OSError) -> str:
    if exc.errno == errno.ENOSPC:
        return "no space left on the device"
    return exc.strerror or str(exc)
