"""The runner: many jobs, each stored as it finishes; the ones the store already has are skipped.

Killed at any moment (Ctrl-C, `kill -9`), a rerun finds every finished job in the store and
runs only the rest: nothing is lost and nothing is done twice. A job that fails stops the
submission of new ones; those already running are still collected and stored, then the error
is raised."""

from __future__ import annotations

import concurrent.futures as cf
import sys
import time
from dataclasses import dataclass, replace
from typing import Callable

from ..data.errors import ConfigError, RemapError, RenderError
from ..engine import ProgressFn
from ..job.execute import AdapterPool, run_in_worker, run_job
from ..job.job import Job, Resolved
from ..job.report import Report, for_job
from . import interrupt
from .executors import Workers, worker_deaths
from .store import Store


@dataclass(frozen=True)
class Task:
    slot: str
    """The job's folder in the store."""
    resolved: Resolved
    """The job, resolved once (`core.job.job.resolve`): its errors were reported before any render,
    and the models it names are in it."""
    title: str = ""

    @property
    def job(self) -> Job:
        return self.resolved.job


@dataclass(frozen=True)
class Done:
    task: Task
    report: Report | None
    """None when the job failed (``error`` says why)."""
    resumed: bool
    redone: str = ""
    """Why a result the slot held was not reused, when it held one."""
    error: str = ""


LineFn = Callable[[Done, int, int], str]
"""A progress line for a finished job: (done, its position among the finished, total)."""

_Todo = tuple[int, Task, str]


class Runner:
    def __init__(self, store: Store, workers: Workers, adapters: AdapterPool, *,
                 line: LineFn | None = None, quiet: bool = False, render_progress: ProgressFn | None = None,
                 reuse: bool = True, stop_on_error: bool = True):
        """``adapters``: this process's, for jobs run here (a worker process opens its own, from the
        same renderer definitions). ``render_progress``: per-render progress of a job run in this
        process. ``reuse``: take a stored result of the same job instead of running it.
        ``stop_on_error``: a job that fails (a renderer error) stops the run; else its `Done` says
        why and the others go on."""
        self.store, self.workers, self.adapters = store, workers, adapters
        self.renderer_files = tuple(adapters.registry.loaded_files())
        self.line, self.quiet, self.render_progress, self.reuse = line, quiet, render_progress, reuse
        self.stop_on_error = stop_on_error

    def run(self, tasks: list[Task]) -> list[Done]:
        found: dict[int, Done] = {}
        todo: list[_Todo] = []
        for i, t in enumerate(tasks):
            stored = self.store.inspect(t.slot)
            if stored.newer:
                raise ConfigError(f"{stored.problem}; nothing was overwritten (or remove that result to redo it)")
            if self.reuse and stored.report is not None and stored.report.key == t.job.key():
                found[i] = Done(t, stored.report, resumed=True)
                self.store.tidy(t.slot)  # a staging folder a kill left after the result was in place
            else:
                why = stored.problem or ("its inputs, the engine or a renderer changed" if stored.report else "")
                todo.append((i, t, why if self.reuse else ""))
        first: dict[str, _Todo] = {}
        twins: dict[int, list[_Todo]] = {}  # the same job in other slots (a library's shared material): run once
        for item in todo:
            key = item[1].job.key()
            if key in first:
                twins.setdefault(first[key][0], []).append(item)
            else:
                first[key] = item
        bar = _Bar(len(tasks), len(found), self.quiet, self.workers.where)
        try:
            for i in sorted(found):
                bar.finished(self._line(found[i], bar))
            self._run_todo(list(first.values()), found, bar, twins)
        finally:
            bar.close()
        return [found[i] for i in range(len(tasks))]

    def _run_todo(self, todo: list[_Todo], found: dict[int, Done], bar: "_Bar",
                  twins: dict[int, list[_Todo]] | None = None) -> None:
        twins = twins or {}
        queue, flight = list(todo), {}
        failure: BaseException | None = None
        try:
            while queue or flight:
                while failure is None and queue and len(flight) < self.workers.capacity:
                    i, t, why = queue.pop(0)
                    bar.current(t.title or t.slot)
                    try:
                        flight[self._submit(t)] = (i, t, why)
                    except worker_deaths() as exc:
                        failure = RenderError(f"the worker pool broke ({exc}); rerun to go on where it stopped")
                if not flight:
                    break
                ready, _ = cf.wait(list(flight), timeout=0.5, return_when=cf.FIRST_COMPLETED)
                interrupt.check()  # a Ctrl-C a renderer swallowed still stops the run here
                for fut in ready:
                    i, t, why = flight.pop(fut)
                    for j, done, exc in self._collect(fut, (i, t, why), twins.get(i, [])):
                        if exc is not None and self.stop_on_error:
                            failure = failure or exc
                            continue
                        found[j] = done
                        bar.finished(self._line(done, bar))
        except BaseException:
            for fut in flight:
                fut.cancel()
            raise
        if failure is not None:
            raise failure

    def _submit(self, t: Task) -> cf.Future:
        if self.workers.in_process:
            return self.workers.executor.submit(run_job, t.resolved, self.adapters, self.render_progress)
        return self.workers.executor.submit(run_in_worker, t.resolved, self.renderer_files)

    def _collect(self, fut: cf.Future, todo: _Todo, twins: list[_Todo]) -> list[tuple[int, Done, RemapError | None]]:
        """The finished job's Done, and its twins': each stored in its own slot under its own labels
        (`report.for_job`), with the error that stopped it; the job's failure is its twins' too, and
        a twin that cannot be stored fails alone."""
        i, t, why = todo
        try:
            done, outcome = self._finish(fut, t, why)
        except RemapError as exc:
            return [(j, Done(x, None, resumed=False, redone=w, error=str(exc)), exc) for j, x, w in [todo, *twins]]
        out: list[tuple[int, Done, RemapError | None]] = [(i, done, None)]
        for j, twin, twin_why in twins:
            try:
                mine = replace(outcome, report=for_job(outcome.report, twin.job))
                self.store.save(twin.slot, mine)
                out.append((j, Done(twin, mine.report, resumed=False, redone=twin_why), None))
            except RemapError as exc:
                out.append((j, Done(twin, None, resumed=False, redone=twin_why, error=str(exc)), exc))
        return out

    def _finish(self, fut: cf.Future, t: Task, why: str):
        """(Done, the job's Outcome), its result stored in the task's slot."""
        try:
            outcome = fut.result()
        except worker_deaths() as exc:
            raise RenderError(f"{t.title or t.slot}: the worker running it died ({exc})") from None
        if outcome.report.key != t.job.key():
            theirs = outcome.report.job
            raise RenderError(f"{t.title or t.slot}: the worker ran another version of the job (engine "
                              f"{outcome.report.engine}, adapters {theirs.versions}; here: {t.job.versions}): "
                              "install the same brdf-remap and renderers on every worker")
        self.store.save(t.slot, outcome)
        return Done(t, outcome.report, resumed=False, redone=why), outcome

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
