"""Ctrl-C that native code may swallow: the request is remembered and honoured at the next check.

A KeyboardInterrupt raised while Mitsuba is calling back into Python (a Python BSDF) can be
caught and dropped inside the renderer; a sweep then ran on to the end as if nothing had been
pressed. The CLI installs this handler; long loops call ``check()`` between units of work."""

from __future__ import annotations

import signal
import threading

_requested = threading.Event()


class Terminated(BaseException):
    """SIGTERM: stop as Ctrl-C does (finished work is kept), and exit 143."""


def install() -> None:
    """Route SIGINT (and SIGTERM) through the remembering handler (main thread only; elsewhere a no-op)."""
    if threading.current_thread() is not threading.main_thread():
        return
    _requested.clear()

    def handler(signum, frame):
        _requested.set()
        raise KeyboardInterrupt

    def terminate(signum, frame):
        _requested.set()
        raise Terminated

    signal.signal(signal.SIGINT, handler)
    signal.signal(signal.SIGTERM, terminate)


def check() -> None:
    """Raise KeyboardInterrupt if Ctrl-C was pressed, even if its first raise was swallowed."""
    if _requested.is_set():
        raise KeyboardInterrupt
