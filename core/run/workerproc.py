"""A persistent worker process that answers JSON lines: pay a renderer's start-up once.

Renderer-agnostic: adapters (Cycles, external renderers) own one. A crash or a hang becomes
a RenderError carrying the tail of the worker's stderr; a dead worker is restarted once."""

from __future__ import annotations

import atexit
import collections
import concurrent.futures
import json
import os
import queue
import signal
import subprocess
import threading
import time
import weakref
from typing import Any

from ..data.errors import RenderError, RenderTimeoutError


def _prctl():
    """libc's prctl, looked up once here, in the parent: a child forked while other threads run may
    only call it, not import or load anything (their locks may be held at the fork)."""
    try:
        import ctypes

        return ctypes.CDLL("libc.so.6", use_errno=True).prctl
    except (OSError, AttributeError):
        return None


_PRCTL = _prctl()


def die_with_parent() -> None:
    """In a child process about to exec a renderer: the kernel kills it when remap dies, even by
    kill -9 (Linux's parent-death signal; elsewhere a no-op)."""
    if _PRCTL is not None:
        _PRCTL(1, signal.SIGKILL)  # PR_SET_PDEATHSIG


_LIVE: "weakref.WeakSet[JsonLinesWorker]" = weakref.WeakSet()
_SPAWNER = concurrent.futures.ThreadPoolExecutor(max_workers=1, thread_name_prefix="brdfremap-spawn")
"""The one thread every worker process is started from. Linux's parent-death signal follows the thread
that forked the child, not its process: a worker (re)started from a thread that then ended (a request's
thread, a pool's retired thread) was killed with it. This thread lives as long as the process."""


@atexit.register
def _close_all() -> None:
    for w in list(_LIVE):
        w.close()


class JsonLinesWorker:
    def __init__(self, argv: list[str], *, name: str, env: dict[str, str] | None = None,
                 start_timeout: float = 120.0, request_timeout: float = 600.0, cwd: str | None = None):
        self.argv, self.name, self.env, self.cwd = list(argv), name, env, cwd
        self.start_timeout, self.request_timeout = start_timeout, request_timeout
        self.proc: subprocess.Popen | None = None
        self.hello: dict[str, Any] = {}
        self.restarts = 0
        self._lines: queue.Queue = queue.Queue()
        self._stderr: collections.deque[str] = collections.deque(maxlen=40)
        self._next_id = 0
        self._lock = threading.Lock()
        _LIVE.add(self)

    # -- lifecycle ---------------------------------------------------------------------
    def start(self) -> dict[str, Any]:
        self._lines = queue.Queue()
        self._stderr.clear()
        try:
            self.proc = _SPAWNER.submit(
                subprocess.Popen, self.argv, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                text=True, bufsize=1, env=self.env, cwd=self.cwd, start_new_session=True,
                preexec_fn=die_with_parent).result()
        except OSError as exc:
            raise RenderError(f"cannot start {self.argv[0]!r}: {exc}", where=self.name) from exc
        threading.Thread(target=self._pump_answers, args=(self.proc.stdout, self._lines), daemon=True).start()
        self._stderr_pump = threading.Thread(target=self._pump_stderr, args=(self.proc.stderr, self._stderr),
                                             daemon=True)
        self._stderr_pump.start()
        try:
            self.hello = self._read(self.start_timeout, "start")
        except RenderTimeoutError as exc:  # a slow start, not a render that never ends
            raise RenderError(exc.message, where=self.name) from None
        if not self.hello.get("ok"):
            err = self.hello.get("error", "no greeting")
            self.close()
            raise RenderError(f"worker failed to start: {err}{self._tail()}", where=self.name)
        return self.hello

    @staticmethod
    def _pump_answers(stream, lines: queue.Queue) -> None:
        for line in stream:
            lines.put(line.rstrip("\n"))
        lines.put(None)  # end of stream: the worker is gone

    @staticmethod
    def _pump_stderr(stream, tail: collections.deque) -> None:
        for line in stream:
            tail.append(line.rstrip("\n"))

    def alive(self) -> bool:
        return self.proc is not None and self.proc.poll() is None

    def close(self) -> None:
        proc, self.proc = self.proc, None
        if proc is None:
            return
        try:
            if proc.poll() is None:
                try:
                    proc.stdin.write(json.dumps({"op": "quit"}) + "\n")
                    proc.stdin.flush()
                    proc.stdin.close()
                    proc.wait(timeout=5)
                except (OSError, ValueError, subprocess.TimeoutExpired):
                    self._kill(proc)
        finally:
            for s in (proc.stdin, proc.stdout, proc.stderr):
                try:
                    s.close()
                except Exception:
                    pass

    @staticmethod
    def _kill(proc: subprocess.Popen) -> None:
        try:
            os.killpg(proc.pid, signal.SIGKILL)  # the whole group: renderers spawn helpers
        except (ProcessLookupError, PermissionError):
            proc.kill()
        proc.wait()

    # -- requests ----------------------------------------------------------------------
    def _tail(self, n: int = 8) -> str:
        lines = [line for line in self._stderr if line.strip()][-n:]
        return ("\n  stderr: " + "\n  stderr: ".join(lines)) if lines else ""

    def _read(self, timeout: float, what: str, want_id: int | None = None) -> dict[str, Any]:
        """The next answer (with ``want_id``: the answer to that request; any other JSON line is
        stray output, kept for the error message)."""
        deadline = time.monotonic() + timeout
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                if self.proc is not None:
                    self._kill(self.proc)
                raise RenderTimeoutError(f"no answer to {what} within {timeout:.0f} s (worker killed){self._tail()}",
                                         seconds=timeout, where=self.name)
            try:
                line = self._lines.get(timeout=min(left, 0.5))
            except queue.Empty:
                continue
            if line is None:
                code = self.proc.wait() if self.proc else None
                # The process is gone; let its last stderr lines arrive before quoting them.
                self._stderr_pump.join(timeout=2.0)
                raise _WorkerDied(f"worker exited (code {code}) during {what}{self._tail()}", where=self.name)
            line = line.strip()
            try:
                doc = json.loads(line)
            except (json.JSONDecodeError, RecursionError):  # RecursionError: a stray line of [[[[...
                doc = None
            if not isinstance(doc, dict):
                self._stderr.append(line)  # stray output: keep it for the error message
                continue
            if want_id is not None and not (isinstance(doc, dict) and doc.get("id") == want_id):
                self._stderr.append(f"(stray line on stdout) {line[:200]}")
                continue
            return doc

    def request(self, msg: dict[str, Any], timeout: float | None = None) -> dict[str, Any]:
        """Send one request and wait for its answer. A dead worker is restarted once."""
        with self._lock:
            for attempt in (0, 1):
                self._next_id += 1
                payload = {"id": self._next_id, **msg}
                try:
                    if not self.alive():
                        # Started here, inside the retry: a worker that dies while it starts
                        # (killed, out of memory) gets its one restart too.
                        if self.hello or attempt:  # it ran before, or died while starting
                            self.restarts += 1
                        self.start()
                    proc = self.proc
                    if proc is None:  # closed from another thread (the adapter shutting down)
                        raise RenderError("the worker was closed", where=self.name)
                    proc.stdin.write(json.dumps(payload) + "\n")
                    proc.stdin.flush()
                    answer = self._read(timeout or self.request_timeout, msg.get("op", "request"), self._next_id)
                except (_WorkerDied, BrokenPipeError, OSError, ValueError) as exc:  # ValueError: a closed pipe
                    self.proc = None
                    if attempt:
                        raise RenderError(exc.message if isinstance(exc, _WorkerDied) else
                                          f"worker pipe broke: {exc}{self._tail()}", where=self.name) from None
                    continue
                if not answer.get("ok"):
                    raise RenderError(f"{answer.get('error', 'failed')}{self._tail(4)}", where=self.name)
                return answer
        raise RenderError("worker unavailable", where=self.name)


class _WorkerDied(RenderError):
    pass
