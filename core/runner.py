"""The runner: many jobs, each stored as it finishes; the ones the store already has are skipped.

Killed at any moment (Ctrl-C, `kill -9`), a rerun finds every finished job in the store and
runs only the rest: nothing is lost and nothing is done twice."""

from __future__ import annotations

import concurrent.futures as cf
import sys
import time
from dataclasses import dataclass
from typing import Callable

from . import interrupt
from .engine import ProgressFn
from .errors import RemapError, RenderError
from .execute import run_job
from .executors import Workers, worker_deaths
from .job import Job
from .report import Report
from .store import Store


@dataclass(frozen=True)
class Task:
    slot: str
    """The job's folder in the store."""
    job: Job
    """Canonical (resolved) already: its errors were reported before any render."""
    title: str = ""


@dataclass(frozen=True)
class Done:
    task: Task
    report: Report | None
    resumed: bool
    error: str = ""
    """Why the job failed (a renderer error), when it did."""
    redone: str = ""
    """Why a stored result was not reused, when there was one."""


LineFn = Callable[[Done, int, int], str]
"""A progress line for a finished job: (done, its position among the finished, total)."""


class Runner:
    def __init__(self, store: Store, workers: Workers, *, renderer_files: tuple[str, ...] = (),
                 line: LineFn | None = None, quiet: bool = False, render_progress: ProgressFn | None = None,
                 stop_on_error: bool = True, reuse: bool = True):
        """``render_progress``: per-render progress of a job run in this process. ``stop_on_error``:
        a job that fails stops the run (else it is reported in its `Done`). ``reuse``: take a stored
        result of the same job instead of running it."""
        self.store, self.workers, self.renderer_files = store, workers, tuple(renderer_files)
        self.line, self.quiet, self.render_progress = line, quiet, render_progress
        self.stop_on_error, self.reuse = stop_on_error, reuse

    def run(self, tasks: list[Task]) -> list[Done]:
        found: dict[int, Done] = {}
        todo: list[tuple[int, Task, str]] = []
        for i, t in enumerate(tasks):
            report, why = self.store.inspect(t.slot)
            if self.reuse and report is not None and report.key == t.job.key():
                found[i] = Done(t, report, resumed=True)
            else:
                todo.append((i, t, why or ("its inputs or the engine changed" if report is not None else "")))
        bar = _Bar(len(tasks), len(found), self.quiet, self.workers.where)
        for i in sorted(found):
            bar.finished(self._line(found[i], bar))
        try:
            self._run_todo(todo, found, bar)
        finally:
            bar.close()
        return [found[i] for i in range(len(tasks))]

    def _run_todo(self, todo: list[tuple[int, Task, str]], found: dict[int, Done], bar: "_Bar") -> None:
        queue = list(todo)
        flight: dict[cf.Future, tuple[int, Task, str]] = {}
        try:
            while queue or flight:
                while queue and len(flight) < self.workers.capacity:
                    i, t, why = queue.pop(0)
                    bar.current(t.title or t.slot)
                    flight[self._submit(t)] = (i, t, why)
                ready, _ = cf.wait(list(flight), timeout=0.5, return_when=cf.FIRST_COMPLETED)
                interrupt.check()  # a Ctrl-C a renderer swallowed still stops the run here
                for fut in ready:
                    i, t, why = flight.pop(fut)
                    found[i] = self._finish(fut, t, why)
                    bar.finished(self._line(found[i], bar))
        except BaseException:
            for fut in flight:
                fut.cancel()
            raise

    def _submit(self, t: Task) -> cf.Future:
        if self.workers.in_process:
            return self.workers.executor.submit(run_job, t.job, self.renderer_files, self.render_progress)
        return self.workers.executor.submit(run_job, t.job, self.renderer_files)

    def _finish(self, fut: cf.Future, t: Task, why: str) -> Done:
        try:
            outcome = fut.result()
        except RemapError as exc:
            if self.stop_on_error:
                raise
            return Done(t, None, resumed=False, error=str(exc), redone=why)
        except worker_deaths() as exc:
            err = RenderError(f"{t.title or t.slot}: the worker running it died ({exc})")
            if self.stop_on_error:
                raise err from None
            return Done(t, None, resumed=False, error=str(err), redone=why)
        self.store.save(t.slot, outcome)
        return Done(t, outcome.report, resumed=False, redone=why)

    def _line(self, done: Done, bar: "_Bar") -> str:
        return self.line(done, bar.done + 1, bar.total) if self.line else ""


class _Bar:
    """Jobs done, the current one and the time left: a tqdm bar on a terminal, else plain lines."""

    def __init__(self, total: int, resumed: int, quiet: bool, where: str):
        self.total, self.done, self.quiet = total, 0, quiet
        self.t0 = time.perf_counter()
        self.tqdm = None
        if not quiet and sys.stderr.isatty() and total > 1:
            from tqdm import tqdm

            self.tqdm = tqdm(total=total, unit="job", file=sys.stderr, dynamic_ncols=True, desc=where)
        elif not quiet and total > 1:
            print(f"{total} jobs ({resumed} already done), running in {where}", file=sys.stderr, flush=True)

    def current(self, title: str) -> None:
        if self.tqdm is not None:
            self.tqdm.set_postfix_str(title[:40])

    def finished(self, line: str) -> None:
        self.done += 1
        if self.tqdm is not None:
            if line:
                self.tqdm.write(line, file=sys.stderr)
            self.tqdm.update(1)
        elif line and not self.quiet:
            print(line, file=sys.stderr, flush=True)

    def close(self) -> None:
        if self.tqdm is not None:
            self.tqdm.close()
