"""Where jobs run: in this process (the default), a local process pool (`--jobs N`), or a Dask
distributed cluster (`--scheduler ADDRESS`). Each is a `concurrent.futures.Executor`; the
runner keeps ``capacity`` jobs in flight and stores each result as it arrives."""

from __future__ import annotations

import concurrent.futures as cf
import multiprocessing
import os
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any, Callable, Iterator

from ..data.errors import ConfigError

MAX_JOBS = 256


class InlineExecutor(cf.Executor):
    """Runs each job when it is submitted, in this process (its adapters stay open across jobs)."""

    in_process = True

    def submit(self, fn: Callable[..., Any], /, *args: Any, **kwargs: Any) -> cf.Future:
        future: cf.Future = cf.Future()
        try:
            future.set_result(fn(*args, **kwargs))
        except BaseException as exc:  # handed to the caller through the future, as a pool would
            if isinstance(exc, (KeyboardInterrupt, SystemExit)):
                raise
            future.set_exception(exc)
        return future


@dataclass
class Workers:
    executor: cf.Executor
    capacity: int
    """Jobs worth keeping in flight."""
    where: str
    """In words, for progress lines: "this process", "2 local processes", "dask at ADDRESS"."""

    @property
    def in_process(self) -> bool:
        return getattr(self.executor, "in_process", False)


@contextmanager
def workers(jobs: int = 1, scheduler: str | None = None) -> Iterator[Workers]:
    if not 1 <= jobs <= MAX_JOBS:
        raise ConfigError(f"must be from 1 to {MAX_JOBS} (each job is a process with its own renderers)",
                          field="--jobs")
    if scheduler is not None and not scheduler.strip():
        raise ConfigError("is empty: give the scheduler's address (tcp://HOST:8786), or leave the flag out",
                          field="--scheduler")
    if scheduler and jobs > 1:
        raise ConfigError("give --jobs or --scheduler, not both (a cluster's size is its workers')", field="--jobs")
    if scheduler:
        with _dask(scheduler) as w:
            yield w
    elif jobs > 1:
        # spawn: a fresh interpreter per worker; forking a process that holds a renderer's
        # threads and native state is not safe.
        pool = cf.ProcessPoolExecutor(max_workers=jobs, mp_context=multiprocessing.get_context("spawn"),
                                      initializer=_watch_parent, initargs=(os.getpid(),))
        try:
            yield Workers(pool, jobs, f"up to {jobs} local processes")
        except BaseException:
            _stop(pool)
            raise
        pool.shutdown(wait=True)
    else:
        yield Workers(InlineExecutor(), 1, "this process")


def _stop(pool: cf.ProcessPoolExecutor) -> None:
    """Stop a pool at once (a signal, an error): its workers are ended, not waited for. Waiting
    would outlast any render under way (the third trial's SIGTERM left a sweep running: the
    interpreter joins the workers at exit, and they stop only once this process is gone). Their
    renderers follow them (a parent-death signal, a process group)."""
    procs = list((getattr(pool, "_processes", None) or {}).values())  # the stdlib offers no public handle
    pool.shutdown(wait=False, cancel_futures=True)
    for p in procs:
        try:
            p.terminate()
        except (OSError, ValueError, AttributeError):
            pass
    for p in procs:
        p.join(timeout=5)
        if p.is_alive():  # in a renderer's native code, where its signal handler cannot run yet
            p.kill()
            p.join(timeout=5)
    # The pool's manager thread is joined, without a timeout, when the interpreter exits: wake it
    # now (its workers are gone) and give it the time it needs to see so, rather than hang there.
    wake = getattr(pool, "_executor_manager_thread_wakeup", None)
    manager = getattr(pool, "_executor_manager_thread", None)
    try:
        if wake is not None:
            wake.wakeup()
    except (OSError, ValueError):
        pass
    if manager is not None:
        manager.join(timeout=10)


@contextmanager
def _dask(address: str) -> Iterator[Workers]:
    try:
        from distributed import Client
    except ImportError:
        raise ConfigError("needs dask.distributed: pip install 'distributed'", field="--scheduler") from None
    _probe(address)
    try:
        client = Client(address, timeout="20s")
    except (OSError, TimeoutError, ValueError) as exc:
        raise ConfigError(f"cannot reach the Dask scheduler: {exc}", field=f"--scheduler {address}") from None
    except Exception as exc:  # a service that is not Dask can make its protocol fail in any way
        raise ConfigError(f"the service there does not speak Dask's protocol ({type(exc).__name__})",
                          field=f"--scheduler {address}") from None
    try:
        # One job per worker process at a time (run_job holds a process lock): a renderer's state
        # is per process, and two jobs in threads of one process would share it.
        procs = len(client.nthreads())
        yield Workers(client.get_executor(pure=False), max(procs, 1), f"dask at {address} ({procs} workers)")
    finally:
        client.close()


def _watch_parent(parent: int) -> None:
    """In a pool worker: exit when the process that started it is gone (a `kill -9` of remap
    leaves no worker behind holding a renderer and its memory)."""
    import threading
    import time

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(1.0)
        os._exit(1)

    threading.Thread(target=watch, daemon=True, name="brdfremap-parent-watch").start()


def _probe(address: str, timeout: float = 10.0) -> None:
    """A TCP scheduler address must take a connection and greet first, as a Dask scheduler does
    (its handshake): a mistyped port on a web server would otherwise hang the client."""
    import socket
    from urllib.parse import urlsplit

    parts = urlsplit(address if "://" in address else f"tcp://{address}")
    if parts.scheme != "tcp":
        return
    field = f"--scheduler {address}"
    try:
        host, port = parts.hostname, parts.port
    except ValueError:
        raise ConfigError("expected tcp://HOST:PORT (the scheduler's address, e.g. tcp://10.0.0.5:8786)",
                          field=field) from None
    if not host or not port:
        raise ConfigError("expected tcp://HOST:PORT (the scheduler's address, e.g. tcp://10.0.0.5:8786)", field=field)
    try:
        with socket.create_connection((host, port), timeout=timeout) as s:
            s.settimeout(timeout)
            greeting = s.recv(16)
    except socket.timeout:
        raise ConfigError(f"something answers there but says nothing within {timeout:.0f} s: not a Dask scheduler "
                          "(check the port: a scheduler listens on 8786 by default)", field=field) from None
    except OSError as exc:
        raise ConfigError(f"cannot reach the Dask scheduler: {exc.strerror or exc}", field=field) from None
    if not greeting:
        raise ConfigError("the service there closed the connection: not a Dask scheduler", field=field)


def worker_deaths() -> tuple[type[BaseException], ...]:
    """The errors a pool or a cluster raises for a job whose worker process died."""
    from concurrent.futures.process import BrokenProcessPool

    out: list[type[BaseException]] = [BrokenProcessPool]
    try:
        from distributed import KilledWorker

        out.append(KilledWorker)
    except ImportError:
        pass
    return tuple(out)
