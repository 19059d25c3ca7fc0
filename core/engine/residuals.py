"""The residual function of one fit: what least squares minimises, counted and memoised."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..data.errors import OptimisationError
from ..data.metrics import l2
from .levels import ProgressFn, RenderFn
from .space import ParamSpace


class BudgetExhausted(Exception):
    """The stage has used its renders."""


class GoodEnough(Exception):
    """The error fell below what the render noise allows telling apart."""


@dataclass
class Tally:
    """Target render requests of the whole remap, across stages (for progress lines)."""

    requests: int = 0


def point_key(u: np.ndarray) -> bytes:
    return np.round(u, 12).tobytes()


class Residuals:
    """(target render - source) / norm over one stage's free parameters.

    Each point is rendered once (memoised); renders count against ``budget``. A polish may
    go up to two renders over it while its latest improvement still gained 1 %: a sharp
    highlight's roughness is found only at full resolution, a broad one's is not moved.
    The best point seen is kept, and the points rendered since the last Jacobian (its
    secants) are handed over with `take_trials`."""

    def __init__(self, name: str, lobe: str | None, space: ParamSpace, render: RenderFn, source: np.ndarray,
                 norm: float, *, budget: int, extend_while_gaining: bool, good_enough: float, tally: Tally,
                 progress: ProgressFn | None):
        self.name, self.lobe, self.space, self.render = name, lobe, space, render
        self.source = np.asarray(source, dtype=np.float64).ravel()
        self.norm, self.budget, self.good_enough = norm, budget, good_enough
        self.extend_while_gaining, self.tally, self.progress = extend_while_gaining, tally, progress
        self.renders = 0
        self.best_u: np.ndarray | None = None
        self.best_err = math.inf
        self.memo: dict[bytes, np.ndarray] = {}
        self._extra, self._last_gain = 0, 0.0
        self._since_jacobian = 0
        self._trials: list[tuple[np.ndarray, np.ndarray]] = []

    def __call__(self, u: np.ndarray) -> np.ndarray:
        key = point_key(u)
        if key in self.memo:
            return self.memo[key]
        self._charge()
        img = self.render(self.space.decode(u), self.lobe)
        self.renders += 1
        self._since_jacobian += 1
        self.tally.requests += 1
        r = (np.asarray(img, dtype=np.float64).ravel() - self.source) / self.norm
        if not np.isfinite(r).all():
            raise OptimisationError(f"stage {self.name}: residuals are not finite at {self.space.decode(u)}")
        self.memo[key] = r
        self._trials.append((u.copy(), r))
        self._keep_best(u, l2(r))
        if self.progress:
            self.progress(self.name, self.tally.requests, self.best_err)
        if self.good_enough > 0 and l2(r) <= self.good_enough:
            raise GoodEnough
        return r

    def _charge(self) -> None:
        if self.renders < self.budget:
            return
        if not (self.extend_while_gaining and self._extra < 2 and self._last_gain >= 0.01):
            raise BudgetExhausted
        self._extra += 1

    def _keep_best(self, u: np.ndarray, err: float) -> None:
        if err < self.best_err < math.inf:
            self._last_gain = (self.best_err - err) / self.best_err  # of the latest improvement
        if err < self.best_err:
            self.best_err, self.best_u = err, u.copy()

    def at_best(self) -> np.ndarray | None:
        return None if self.best_u is None else self.memo.get(point_key(self.best_u))

    def take_trials(self) -> tuple[int, list[tuple[np.ndarray, np.ndarray]]]:
        """(renders since the last Jacobian, the points they were at) and start counting anew."""
        out = (self._since_jacobian, self._trials)
        self._since_jacobian, self._trials = 0, []
        return out
