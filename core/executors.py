"""Where jobs run: in this process (the default), a local process pool (`--jobs N`), or a Dask
distributed cluster (`--scheduler ADDRESS`). Each is a `concurrent.futures.Executor`; the
runner keeps ``capacity`` jobs in flight and stores each result as it arrives."""

from __future__ import annotations

import concurrent.futures as cf
import multiprocessing
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any, Callable, Iterator

from .errors import ConfigError


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
    if jobs < 1:
        raise ConfigError("must be at least 1", field="--jobs")
    if scheduler and jobs > 1:
        raise ConfigError("give --jobs or --scheduler, not both (a cluster's size is its workers')", field="--jobs")
    if scheduler:
        with _dask(scheduler) as w:
            yield w
    elif jobs > 1:
        # spawn: a fresh interpreter per worker; forking a process that holds a renderer's
        # threads and native state is not safe.
        pool = cf.ProcessPoolExecutor(max_workers=jobs, mp_context=multiprocessing.get_context("spawn"))
        try:
            yield Workers(pool, jobs, f"{jobs} local processes")
        finally:
            pool.shutdown(wait=True, cancel_futures=True)
    else:
        yield Workers(InlineExecutor(), 1, "this process")


@contextmanager
def _dask(address: str) -> Iterator[Workers]:
    try:
        from distributed import Client
    except ImportError:
        raise ConfigError("needs dask.distributed: pip install 'distributed'", field="--scheduler") from None
    try:
        client = Client(address, timeout="20s")
    except (OSError, TimeoutError, ValueError) as exc:
        raise ConfigError(f"cannot reach the Dask scheduler: {exc}", field=f"--scheduler {address}") from None
    try:
        # One job per worker process at a time (run_job holds a process lock): a renderer's state
        # is per process, and two jobs in threads of one process would share it.
        procs = len(client.nthreads())
        yield Workers(client.get_executor(pure=False), max(procs, 1), f"dask at {address} ({procs} workers)")
    finally:
        client.close()


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
