"""How many threads a renderer may use in this process.

`--jobs N` runs N worker processes on one machine; each renderer would otherwise start a thread
per core, and N of them on the same cores compete (two Blenders on 2 cores: a warm remap 0.56x as
fast as one, `bench/workers.py`). A local pool gives each worker process its share of the cores
(`RENDER_THREADS_ENV`, set by `core.executors`); adapters read it here and tell their renderer.
Unset (this process, a Dask worker): the renderer's own default, every core."""

from __future__ import annotations

import os

RENDER_THREADS_ENV = "BRDFREMAP_RENDER_THREADS"


def share(jobs: int) -> int:
    """Each of ``jobs`` local worker processes' threads: the cores divided among them, at least one."""
    return max(1, (os.cpu_count() or 1) // max(1, jobs))


def render_threads() -> int | None:
    """The threads a renderer in this process may use, or None for its default."""
    raw = os.environ.get(RENDER_THREADS_ENV, "").strip()
    try:
        n = int(raw)
    except ValueError:
        return None
    return n if n >= 1 else None
