"""The Jacobian of a stage's residuals: forward differences, or Broyden updates between them.

A finite-difference Jacobian costs a render per parameter, except that a separable RGB
parameter moves its three components in one render (residual rows of channel c belong to
component c alone) and a parameter the model declares inert where the fit is gets a zero
column. Between rendered Jacobians it is updated from the steps taken (Broyden's rank-one
update, keeping the separable structure: Schubert's sparse update)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .residuals import Residuals, point_key


@dataclass(frozen=True)
class JacobianState:
    u: np.ndarray
    r: np.ndarray
    J: np.ndarray
    nonzero: np.ndarray


class Jacobian:
    """``jac`` for scipy's least_squares over one `Residuals`."""

    def __init__(self, residuals: Residuals, *, fd_step: float, updates: int, refresh_on_retry: bool,
                 separable: bool):
        self.res, self.fd_step, self.max_updates = residuals, fd_step, updates
        self.refresh_on_retry, self.separable = refresh_on_retry, separable
        self.state: JacobianState | None = None
        self.inert: frozenset[int] = frozenset()
        self.in_a_row = 0
        """Updates since the last rendered Jacobian."""
        self.rendered = self.updated = 0

    def force_rendered(self) -> None:
        """The next call renders a fresh Jacobian."""
        self.in_a_row = self.max_updates

    def __call__(self, u: np.ndarray) -> np.ndarray:
        r0 = self.res(u)
        trials, tried = self.res.take_trials()
        inert = self._inert_columns(u)
        if (self.state is not None and self.in_a_row < self.max_updates
                and (trials <= 1 or not self.refresh_on_retry) and inert >= self.inert):
            # The last step was taken at its first try (or retries update it too): update the
            # Jacobian along each secant from the last Jacobian's point, the accepted one last.
            return self._update(u, r0, tried, inert)
        return self._finite_differences(u, r0, inert)

    def _update(self, u: np.ndarray, r0: np.ndarray, tried: list, inert: frozenset[int]) -> np.ndarray:
        st = self.state
        J, nonzero = st.J, st.nonzero
        if float(np.linalg.norm(u - st.u)) < 0.1 * self.fd_step:
            return J  # (nearly) the same point: a secant over so short a step is only noise
        if inert != self.inert:  # a parameter became inert along the step: its column goes to zero
            nonzero = nonzero.copy()
            nonzero[:, sorted(inert)] = False
            self.inert = inert
        secants = [(v, rv) for v, rv in tried if not np.array_equal(v, u)] + [(u, r0)]
        for v, rv in secants:
            dx = v - st.u
            if float(np.linalg.norm(dx)) < 0.1 * self.fd_step:
                continue
            J = J + np.outer(rv - st.r - J @ dx, dx) / float(dx @ dx)
            J[~nonzero] = 0.0
        self.state = JacobianState(u.copy(), r0, J, nonzero)
        self.in_a_row += 1
        self.updated += 1
        return J

    def _finite_differences(self, u: np.ndarray, r0: np.ndarray, inert: frozenset[int]) -> np.ndarray:
        self.in_a_row = 0
        self.rendered += 1
        h = self.fd_step
        J = np.zeros((r0.size, u.size))
        nonzero = np.ones(J.shape, dtype=bool)
        steps = np.where(u + h <= 1.0, h, -h)
        grouped = self.res.space.separable_groups() if self.separable else []
        # Parameters (nearly) without effect here: a zero column, no render, kept zero by the updates
        # (one that regains its effect gets a rendered Jacobian).
        nonzero[:, sorted(inert)] = False
        done = set(inert)
        grouped = [sl for sl in grouped if sl.start not in done]
        self._prefetch(u, steps, grouped, done)
        for sl in grouped:
            v = u.copy()
            v[sl] += steps[sl]
            d = self.res(v) - r0
            for c, j in enumerate(range(sl.start, sl.stop)):
                J[c::3, j] = d[c::3] / steps[j]
                nonzero[:, j] = False
                nonzero[c::3, j] = True
                done.add(j)
        for j in range(u.size):
            if j in done:
                continue
            v = u.copy()
            v[j] += steps[j]
            J[:, j] = (self.res(v) - r0) / steps[j]
        self.res.take_trials()
        self.state, self.inert = JacobianState(u.copy(), r0, J, nonzero), inert
        return J

    def _inert_columns(self, u: np.ndarray) -> frozenset[int]:
        """Columns of the parameters that cannot change the image here, or barely: their
        ``inert_when`` values are met within 1 % of those parameters' ranges (Specular IOR Level
        as Metallic nears 1, where steps along it would only chase noise)."""
        space = self.res.space
        spec, params, out = space.spec, None, set()
        for name, sl in space.slices.items():
            cond = spec.param(name).inert_when
            if not cond:
                continue
            params = params or space.decode(u)
            if all(abs(float(params[k]) - v) <= 0.01 * (spec.param(k).upper - spec.param(k).lower)
                   for k, v in cond.items()):
                out.update(range(sl.start, sl.stop))
        return frozenset(out)

    def _prefetch(self, u: np.ndarray, steps: np.ndarray, grouped: list[slice], skip: set[int]) -> None:
        """Hand the renderer every point of this Jacobian at once when it can render in parallel
        (``render.many``); the residuals then read them from its cache, counted as before."""
        many = getattr(self.res.render, "many", None)
        if many is None:
            return
        points, in_group = [], set(skip)
        for sl in grouped:
            v = u.copy()
            v[sl] += steps[sl]
            points.append(v)
            in_group.update(range(sl.start, sl.stop))
        for j in range(u.size):
            if j not in in_group:
                v = u.copy()
                v[j] += steps[j]
                points.append(v)
        todo = [v for v in points if point_key(v) not in self.res.memo]
        room = self.res.budget - self.res.renders
        if len(todo) >= 2 and room >= 2:
            many([(self.res.space.decode(v), self.res.lobe) for v in todo[:room]])
