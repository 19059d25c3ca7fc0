"""What a coarse fit settled, so the polish at full resolution can leave it out."""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum

import numpy as np

from .stage import Stage
from ..data.schemas import ParamKind


class Held(StrEnum):
    """Why the coarse fit settled a parameter: pinned on a bound, or without effect there."""

    PINNED = "pinned"
    INERT = "inert"


@dataclass(frozen=True)
class Settled:
    """A parameter the coarse fit settled: why, and (pinned) the coarse gradient and column norm
    at its optimum, relative residual units, for the verdict's pinned-bound check."""

    why: Held
    g: float = 0.0
    col: float = 0.0
    rr: float = 0.0


def settled(stage: Stage) -> dict[str, Settled]:
    """The scalar parameters a (coarse) fit left on a bound whose gradient pushes firmly against
    it (its own Newton step would go 2 % of the range beyond), and those without effect there."""
    space, u = stage.space, stage.residuals.best_u
    r = stage.residuals.at_best()
    if u is None or stage.jacobian.state is None or r is None:
        return {}
    J = stage.jacobian.state.J
    g, col, rr = J.T @ r, np.linalg.norm(J, axis=0), float(r @ r)
    out: dict[str, Settled] = {}
    for name, sl in space.slices.items():
        j = sl.start
        if space.spec.param(name).kind != ParamKind.SCALAR or col[j] == 0:
            continue
        newton = -g[j] / col[j] ** 2
        if (u[j] >= 1.0 and newton > 0.02) or (u[j] <= 0.0 and newton < -0.02):
            out[name] = Settled(Held.PINNED, float(g[j]), float(col[j]), rr)
    params = space.decode(u)
    for name in space.free:
        deps = space.spec.param(name).inert_when
        if name not in out and space.spec.is_inert(name, params) and all(k in out or k not in space.free for k in deps):
            out[name] = Settled(Held.INERT)
    return out
