"""Where a job's time goes: every render, by purpose and side, with its pixels x samples and seconds.

A job's renders are made through `Metered` adapters (one for the source side, one for the
target's), which time each render into the job's `Ledger` under the purpose current when it ran
(`purpose`, a context variable the engine and the job set around each of their steps). The
engine names its steps and knows no renderer; the adapters know no purpose."""

from __future__ import annotations

import time
from contextlib import contextmanager
from contextvars import ContextVar
from typing import Any, Iterator, Literal

from pydantic import BaseModel, ConfigDict, Field

Purpose = Literal["fit scene", "source", "tries", "fit", "checks", "joint", "inputs", "precise", "noise", "validation",
                  "agreement", "textured", "other"]
PURPOSES: tuple[str, ...] = Purpose.__args__  # type: ignore[attr-defined]
"""In the order a job runs them: choosing the fit scene (source renders that say whether the job's
lights resolve it), the source's images, tries of discrete choices, the fit's stages, the Jacobian
checks at the optimum, joint refinement, the held inputs the source needs, the polish at more samples, the target's noise,
validation under held-out lights, the renderers' agreement on glasses, the textured check."""

Side = Literal["source", "target"]

_CURRENT: ContextVar[str] = ContextVar("brdfremap_purpose", default="other")


@contextmanager
def purpose(name: Purpose) -> Iterator[None]:
    """Renders made inside the block are counted under ``name``."""
    token = _CURRENT.set(name)
    try:
        yield
    finally:
        _CURRENT.reset(token)


class Spent(BaseModel):
    """The renders of one purpose on one side."""

    model_config = ConfigDict(extra="forbid")
    purpose: Purpose
    side: Side
    renders: int = 0
    pixel_samples: int = Field(0, description="Pixels x samples per pixel, summed over the renders.")
    seconds: float = 0.0


class Account(BaseModel):
    """Where one job's seconds went."""

    model_config = ConfigDict(extra="forbid")
    renders: list[Spent] = Field(default_factory=list, description="Renders by purpose and side, in the order the "
                                                                   "job runs them.")
    render_seconds: float = Field(0.0, description="Seconds inside renderers (the sum of `renders`).")
    other_seconds: float = Field(0.0, description="The job's seconds outside renderers: the optimiser, images, "
                                                  "files.")

    def by_purpose(self) -> dict[str, Spent]:
        """The two sides of each purpose added together (side "target" stands for both)."""
        out: dict[str, Spent] = {}
        for s in self.renders:
            row = out.setdefault(s.purpose, Spent(purpose=s.purpose, side="target"))
            row.renders += s.renders
            row.pixel_samples += s.pixel_samples
            row.seconds += s.seconds
        return out


class Ledger:
    """One job's renders as they are made."""

    def __init__(self) -> None:
        self._rows: dict[tuple[str, str], Spent] = {}

    def add(self, side: Side, pixel_samples: int, seconds: float, renders: int = 1) -> None:
        key = (_CURRENT.get(), side)
        row = self._rows.setdefault(key, Spent(purpose=key[0], side=side))  # type: ignore[arg-type]
        row.renders += renders
        row.pixel_samples += pixel_samples
        row.seconds += seconds

    def account(self, total_seconds: float) -> Account:
        order = {p: i for i, p in enumerate(PURPOSES)}
        rows = sorted(self._rows.values(), key=lambda s: (order[s.purpose], s.side))
        inside = sum(s.seconds for s in rows)
        return Account(renders=[s.model_copy() for s in rows], render_seconds=inside,
                       other_seconds=max(0.0, total_seconds - inside))


def _pixel_samples(scene: Any) -> int:
    views = 1 + len(getattr(scene, "views", ()) or ())
    return int(scene.resolution) ** 2 * int(scene.spp) * views


class Metered:
    """An adapter whose renders are timed into ``ledger`` as ``side``'s; everything else is the
    adapter's own. Two Metered of one adapter (a job within one renderer) share the renderer.
    Each call counts as a render: one the adapter serves from its own cache (Cycles' lobe passes,
    kept from a render of the same parameters) counts too, in next to no time, as the report's
    render counts do. The reference glasses of `core.job.agreement` are counted here and not in the
    report's counts of the fit's renders."""

    def __init__(self, adapter: Any, side: Side, ledger: Ledger):
        self._adapter, self._side, self._ledger = adapter, side, ledger

    def __getattr__(self, name: str) -> Any:
        if name == "_adapter":  # not yet set (a copy, an unpickling): no adapter to ask
            raise AttributeError(name)
        return getattr(self._adapter, name)

    @property
    def unmetered(self) -> Any:
        return self._adapter

    def render(self, model: Any, params: dict, scene: Any, lobe: str | None = None) -> Any:
        t0 = time.perf_counter()
        try:
            return self._adapter.render(model, params, scene, lobe)
        finally:
            self._ledger.add(self._side, _pixel_samples(scene), time.perf_counter() - t0)

    def render_batch(self, requests: list[tuple]) -> list:
        t0 = time.perf_counter()
        try:
            return self._adapter.render_batch(requests)
        finally:
            if requests:
                self._ledger.add(self._side, sum(_pixel_samples(r[2]) for r in requests), time.perf_counter() - t0,
                                 renders=len(requests))

    def render_native(self, native: Any, scene: Any, lobe: str | None = None, transmissive: bool = False) -> Any:
        t0 = time.perf_counter()
        try:
            return self._adapter.render_native(native, scene, lobe, transmissive)
        finally:
            self._ledger.add(self._side, _pixel_samples(scene), time.perf_counter() - t0)

    def render_textured(self, model: Any, params: dict, maps: Any, scene: Any) -> Any:
        t0 = time.perf_counter()
        try:
            return self._adapter.render_textured(model, params, maps, scene)
        finally:
            self._ledger.add(self._side, _pixel_samples(scene), time.perf_counter() - t0)
