"""A Jacobian of the full image at a result, and what it says: conditioning, parameters without
effect, bounds the fit is pinned against, and what a joint Gauss-Newton step could still gain.

The schedule asks it whether a merged two-stage result is a minimum; the verdict reads the
assessment at the final parameters. The last stage's renders and Jacobian are reused when
it fitted the same parameters to the full image at this resolution."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import lsq_linear

from ..data.metrics import l2
from ..data.schemas import ModelSpec, Value
from .levels import Level
from .residuals import Tally
from .settled import Held, Settled
from .space import ParamSpace
from .stage import Stage, StageConfig
from .tuning import Tuning


@dataclass(frozen=True)
class Pin:
    parameter: str
    side: str
    error_without: float


@dataclass(frozen=True)
class Weakest:
    """The direction in parameter space the fit's image pins least (the Jacobian's smallest singular value):
    along it the parameters move furthest for a given rise of the error."""

    space: ParamSpace
    u: np.ndarray
    v: np.ndarray
    gain: float
    """How fast the error rises along it: |J v| (relative RMSE per unit step in [0, 1]^n)."""

    def step(self, rise: float) -> float:
        """The step along it that raises the error by ``rise`` in quadrature, to first order (at a minimum the
        residual is orthogonal to J's columns)."""
        return rise / max(self.gain, 1e-12)

    def at(self, t: float) -> dict[str, Value]:
        """The parameters ``t`` along it from the fit's (either side by its sign), held within the bounds."""
        return self.space.decode(np.clip(self.u + t * self.v, 0.0, 1.0))


@dataclass(frozen=True)
class Assessment:
    condition: float | None
    no_effect: bool
    dead: list[str] = field(default_factory=list)
    predicted: float | None = None
    """What a joint step predicts, when that is a gain worth a joint round; else None."""
    pins: list[Pin] = field(default_factory=list)
    weakest: Weakest | None = None


@dataclass(frozen=True)
class _Check:
    space: ParamSpace
    u: np.ndarray
    r: np.ndarray
    J: np.ndarray
    held: dict[str, Settled]


def assess(target: ModelSpec, params: dict[str, Value], free: list[str], level: Level, tuning: Tuning,
           tally: Tally, *, jacobian_updates: int, seed: Stage | None = None,
           held: dict[str, Settled] | None = None, good_enough: float = 0.0) -> Assessment:
    """``jacobian_updates``: the fit's setting (the reused Jacobian is updated along the last step
    when it allows). ``seed``: the last stage fitted; ``held``: parameters it left as settled by the coarse fit
    (their checks use the coarse gradient instead of new renders)."""
    if not free:
        return Assessment(condition=None, no_effect=False)
    chk = _jacobian_at(target, params, free, level, tuning, tally, jacobian_updates, seed, dict(held or {}))
    labels = chk.space.labels()
    col = np.linalg.norm(chk.J, axis=0)
    live = col > 1e-6 * max(col.max(), 1e-30)
    dead = [labels[j] for j in range(len(col)) if not live[j]] + [n for n, h in chk.held.items() if h.why == Held.INERT]
    cond = None
    if live.sum() > 1:
        s = np.linalg.svd(chk.J[:, live] / col[live], compute_uv=False)
        cond = float(s[0] / s[-1]) if s[-1] > 0 else math.inf
    return Assessment(condition=cond, no_effect=not live.any(), dead=dead,
                      predicted=_joint_gain(chk, tuning, good_enough),
                      pins=_pins(target, params, chk, labels, col), weakest=_weakest(chk, live))


def _weakest(chk: _Check, live: np.ndarray) -> Weakest | None:
    if not live.any():
        return None
    _, s, vt = np.linalg.svd(chk.J[:, live], full_matrices=False)
    v = np.zeros(chk.J.shape[1])
    v[live] = vt[-1]
    return Weakest(chk.space, chk.u, v, float(s[-1]))


def _jacobian_at(target, params, free, level: Level, tuning: Tuning, tally: Tally, updates: int,
                 seed: Stage | None, held: dict[str, Settled]) -> _Check:
    reuse = (seed is not None and seed.config.lobe is None and seed.jacobian.state is not None
             and seed.resolution == level.resolution
             and set(seed.space.free) | set(held) == set(free) and not set(seed.space.free) & set(held))
    if not reuse:
        held = {}
    checked = [p for p in free if p not in held]
    space = ParamSpace(target, params, checked)
    config = StageConfig("check", None, budget=10**6, jacobian_updates=min(updates, 1))
    check = Stage(config, space, level.render, level.source, level.norm, tuning, tally)
    u = space.encode(params)
    same = reuse and seed.space.free == checked
    if same and seed.render is level.render:
        check.residuals.memo = dict(seed.residuals.memo)
        check.jacobian.state, check.jacobian.inert = seed.jacobian.state, seed.jacobian.inert
    r = check.residuals(u)
    if same and seed.render is not level.render:
        # The seed fitted these parameters at more samples: its Jacobian is the better estimate,
        # but a secant between two samplings would be noise. Used as it is.
        return _Check(space, u, r, seed.jacobian.state.J, held)
    return _Check(space, u, r, check.jacobian(u), held)


def _joint_gain(chk: _Check, tuning: Tuning, good_enough: float) -> float | None:
    """Is the result a minimum of the full problem? A bounded Gauss-Newton step from here
    predicts what a joint fit could still gain (the lobe split can miss a coupling)."""
    rr = float(chk.r @ chk.r)
    step = lsq_linear(chk.J, -chk.r, bounds=(-chk.u, 1.0 - chk.u))
    predicted = max(l2(chk.J @ step.x + chk.r), good_enough)
    gain = math.sqrt(rr) - predicted
    return predicted if gain > max(0.15 * math.sqrt(rr), tuning.joint_min_gain) else None


def _pins(target: ModelSpec, params: dict[str, Value], chk: _Check, labels: list[str], col: np.ndarray) -> list[Pin]:
    g = chk.J.T @ chk.r
    rr = float(chk.r @ chk.r)
    found = []
    for j, lab in enumerate(labels):
        at_lo, at_hi = chk.u[j] <= 1e-3, chk.u[j] >= 1 - 1e-3
        wants_out = (at_lo and g[j] > 0) or (at_hi and g[j] < 0)
        if wants_out and col[j] > 0:
            found.append((lab, "lower" if at_lo else "upper", float(g[j]), float(col[j]), rr))
    # Held as pinned by the coarse fit: judged on its gradient there (same relative units).
    ph = ParamSpace(target, params, list(chk.held))
    uh = ph.encode(params)
    found += [(n, "lower" if uh[ph.slices[n].start] <= 0.5 else "upper", h.g, h.col, h.rr)
              for n, h in chk.held.items() if h.why == Held.PINNED]
    pins = []
    for lab, side, gj, cj, rrj in found:
        better = math.sqrt(max(rrj - gj ** 2 / cj ** 2, 0.0))
        if math.sqrt(rrj) - better > max(0.1 * math.sqrt(rrj), 0.002):
            pins.append(Pin(lab, side, better))
    return pins
