"""One least-squares fit against one source image: starts, TRF, a confirming Jacobian, bounds."""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Literal

import numpy as np
from scipy.optimize import least_squares

from ..data.metrics import l2
from .jacobian import Jacobian
from .levels import ProgressFn, RenderFn
from .residuals import BudgetExhausted, GoodEnough, Residuals, Tally
from .results import StageResult
from .space import ParamSpace
from .tuning import Tuning
from ..data.schemas import ParamKind


@dataclass(frozen=True)
class StageConfig:
    """How one stage runs. A fresh fit tries several starts (moved off bounds, each with its best
    reflectance scale); a polish goes on from the point it is given, within a few renders."""

    name: str
    lobe: str | None
    budget: int
    starts: int = 1
    ftol: float = 1e-4
    xtol: float = 1e-4
    method: str = "trf"
    good_enough: float = 0.0
    jacobian_updates: int = 8
    start_margin: float = 0.0
    """A start on a bound is moved this far inside it (0: left there)."""
    rescale_starts: bool = False
    """Give each start its best scale of a parameter the image is proportional to (no render)."""
    extend_while_gaining: bool = False
    """Up to two renders over the budget while the latest improvement gained 1 %."""
    budget_converges: bool = False
    """Using up the budget is the plan (a polish), not a fit cut short."""
    origin: str = "the coarse optimum"
    """Where a polish starts from, in words."""


class Stage:
    """A fit over ``space`` of ``render`` against ``source``; `run` returns the best point."""

    def __init__(self, config: StageConfig, space: ParamSpace, render: RenderFn, source: np.ndarray, norm: float,
                 tuning: Tuning, tally: Tally, progress: ProgressFn | None = None):
        self.config, self.space = config, space
        self.resolution = int(np.asarray(source).shape[1])  # the width: views stack vertically
        self.residuals = Residuals(config.name, config.lobe, space, render, source, norm, budget=config.budget,
                                   extend_while_gaining=config.extend_while_gaining,
                                   good_enough=config.good_enough, tally=tally, progress=progress)
        self.jacobian = Jacobian(self.residuals, fd_step=tuning.fd_step, updates=config.jacobian_updates,
                                 refresh_on_retry=tuning.refresh_on_retry, separable=tuning.separable_rgb)
        self.result: StageResult | None = None

    @property
    def render(self) -> RenderFn:
        return self.residuals.render

    def run(self, u_base: np.ndarray) -> np.ndarray:
        t0 = time.perf_counter()
        if self.space.dim == 0:
            return u_base
        start_err: float | None = None
        try:
            start_err, u0 = self._best_start(u_base)
            status, detail = self._least_squares(u0)
            self._snap_to_bounds()
        except GoodEnough:
            status, detail = "below_noise", "converged (below the noise floor)"
        except BudgetExhausted:
            status, detail = self._out_of_budget()
        res, jac = self.residuals, self.jacobian
        self.result = StageResult(
            name=self.config.name, lobe=self.config.lobe, fitted=list(self.space.free), renders=res.renders,
            start_error=res.best_err if start_err is None else start_err, error=res.best_err, status=status,
            detail=detail, seconds=time.perf_counter() - t0, resolution=self.resolution, jacobians=jac.rendered,
            jacobian_updates=jac.updated)
        return res.best_u

    def _out_of_budget(self) -> tuple[str, str]:
        if self.config.budget_converges:
            return "polished", f"converged (polished from {self.config.origin} in {self.residuals.renders} renders)"
        return "budget", f"stopped at the render budget ({self.config.budget})"

    def _best_start(self, u_base: np.ndarray) -> tuple[float, np.ndarray]:
        lin = self._linear_slice() if self.config.rescale_starts else None
        errs = []
        for i, u in enumerate(self.starts(u_base)):
            r = self.residuals(u)
            errs.append((l2(r), i, u))
            if lin is not None:
                e, v = self._rescaled(u, r, lin)
                errs.append((e, i, v))
        start_err, _, u0 = min(errs, key=lambda t: (t[0], t[1]))
        return start_err, u0

    def _least_squares(self, u0: np.ndarray) -> tuple[Literal["converged", "stopped"], str]:
        c = self.config
        for _ in range(2):
            res = least_squares(self.residuals, u0, jac=self.jacobian, bounds=(0.0, 1.0), method=c.method,
                                ftol=c.ftol, xtol=c.xtol, gtol=1e-10, x_scale=1.0)
            if self.jacobian.in_a_row == 0:
                break
            # It stopped on an updated Jacobian, which can call a poor step convergence:
            # confirm from the best point with a rendered one.
            self.jacobian.force_rendered()
            u0 = self.residuals.best_u.copy()
        return ("converged", "converged") if res.status > 0 else ("stopped", f"stopped: {res.message}")

    def _snap_to_bounds(self) -> None:
        """TRF approaches an optimum on a bound from the inside and stops short (metallic
        0.005 for a dielectric); try the parameters that are nearly there exactly on it."""
        u = self.residuals.best_u.copy()
        near_lo, near_hi = (u > 0) & (u < 0.02), (u < 1) & (u > 0.98)
        if not (near_lo.any() or near_hi.any()):
            return
        u[near_lo], u[near_hi] = 0.0, 1.0
        try:
            self.residuals(u)  # kept as the best point if it is better
        except (BudgetExhausted, GoodEnough):
            pass

    def starts(self, u_base: np.ndarray) -> list[np.ndarray]:
        """The given point (moved off a bound it lies on) and a low-discrepancy spread over the
        scalar parameters."""
        u0 = u_base.copy()
        if self.config.start_margin > 0:
            u0[u0 <= 1e-9] = self.config.start_margin
            u0[u0 >= 1.0 - 1e-9] = 1.0 - self.config.start_margin
        out = [u0]
        idx = self.space.scalar_indices()
        if not idx:
            return out
        primes = [2, 3, 5, 7, 11, 13, 17, 19]
        for i in range(1, self.config.starts):
            u = out[0].copy()
            for d, j in enumerate(idx):
                lo, hi = self.space.typical_unit(j)
                u[j] = lo + (hi - lo) * (0.1 + 0.8 * _van_der_corput(i, primes[d % len(primes)]))
            out.append(u)
        return out

    def _linear_slice(self) -> tuple[str, slice] | None:
        """The one free parameter this stage's image is proportional to, if there is exactly one."""
        key = self.config.lobe or "full"
        hits = [(n, sl) for n, sl in self.space.slices.items() if key in self.space.spec.param(n).linear_in]
        return hits[0] if len(hits) == 1 else None

    def _rescaled(self, u: np.ndarray, r: np.ndarray, lin: tuple[str, slice]) -> tuple[float, np.ndarray]:
        """The start with its linear parameter scaled to fit best (per channel for RGB), and the
        error it will have there, predicted from the image already rendered (no render)."""
        name, sl = lin
        spec = self.space.spec.param(name)
        res = self.residuals
        img = r * res.norm + res.source
        chans = [slice(c, None, 3) for c in range(3)] if sl.stop - sl.start == 3 else [slice(None)]
        old = self.space.decode(u)[name]
        old_vals = old if isinstance(old, tuple) else (old,)
        new_vals, pred = list(old_vals), r.copy()
        for j, ch in enumerate(chans):
            a, b = img[ch], res.source[ch]
            denom = float(a @ a)
            if denom <= 0 or old_vals[j] <= 0:
                continue
            v = min(max(old_vals[j] * float(a @ b) / denom, spec.lower), spec.upper)
            new_vals[j] = v
            pred[ch] = (a * (v / old_vals[j]) - b) / res.norm
        params = dict(self.space.decode(u))
        params[name] = tuple(new_vals) if spec.kind == ParamKind.RGB else new_vals[0]
        return l2(pred), self.space.encode(params)


def _van_der_corput(n: int, base: int) -> float:
    q, denom = 0.0, 1.0
    while n:
        n, rem = divmod(n, base)
        denom *= base
        q += rem / denom
    return q
