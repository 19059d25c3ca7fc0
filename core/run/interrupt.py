"""Signals that stop a run: Ctrl-C (SIGINT), SIGTERM and SIGHUP, remembered and honoured even
when native code swallows them.

A KeyboardInterrupt raised while Mitsuba is calling back into Python (a Python BSDF) can be
caught and dropped inside the renderer; a sweep then ran on to the end as if nothing had been
pressed. The CLI installs these handlers; long loops call ``check()`` between units of work.
Which signal came decides the exit status (130, 143, 129), however the stop travelled."""

from __future__ import annotations

import signal
import threading

_requested = threading.Event()
_signal: list[int] = []


class Terminated(BaseException):
    """SIGTERM or SIGHUP: stop as Ctrl-C does (finished work is kept)."""


def install() -> None:
    """Route SIGINT, SIGTERM and SIGHUP through the remembering handlers (main thread only)."""
    if threading.current_thread() is not threading.main_thread():
        return
    _requested.clear()
    _signal.clear()

    def handler(signum, frame):
        _requested.set()
        _signal.append(signum)
        if signum == signal.SIGINT:
            raise KeyboardInterrupt
        raise Terminated

    for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
        signal.signal(sig, handler)


def check() -> None:
    """Raise the stop again if a signal came, even if its first raise was swallowed."""
    if _requested.is_set():
        if _signal and _signal[0] != signal.SIGINT:
            raise Terminated
        raise KeyboardInterrupt


def exit_status() -> int:
    """128 + the signal that stopped the run (Ctrl-C when none is known)."""
    return 128 + (_signal[0] if _signal else signal.SIGINT)
