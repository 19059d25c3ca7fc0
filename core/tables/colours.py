"""A correction of a separable map where a colour's channels couple (`TableSpec.colours`).

Under a grey `scale` axis a table maps each channel as if it alone made its image (the JCGT paper's
separable form), and reads a scalar the channels share at each channel's grey level
(`Layout.channel_weights`). Where the target couples its channels, a grey grid cannot tell how: a
Mitsuba rough plastic whose bright channel's diffuse reflectance is pinned at 1 lowers its IOR for
all three channels, and the dim channels' diffuse then makes up for it. A table with coloured
points (source materials of every colour, drawn at random and fitted like the grid's) learns that
from them, for each target colour mapped channel by channel: what the map misses at a channel is
taken as the sum over the shared parameters of the channel's *gap* (how far the shared parameter the
map gives is from the channel's own lookup of it, `gaps`) times a polynomial in the other axes and
the colour's channels (its own, then the others, the brighter first). A gap of zero asks for no
correction: on grey, and wherever the channels agree, the map is left as it is. Its degree is
chosen by cross-validation over the points; the fit is robust (Huber's weights), so a point whose
fit found another optimum pulls it little. The shared parameters themselves are not corrected."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .maps import folds, monomials
from .outputs import Output, OutputKind
from .spec import Layout

DEGREES = (0, 1, 2)
RIDGE = 1e-6
"""Added to the normal equations' diagonal, as a fraction of its mean (the gaps scale the columns)."""
GAIN = 0.97
"""A correction is kept where its cross-validated miss at the moved rows is at most this much of the
map's alone (the least of three degrees' scores is biased low)."""
HUBER, ROUNDS = 1.345, 20
"""The fit is robust (Huber's weights, this many robust standard deviations; iteratively reweighted,
this many rounds): a point whose fit found another optimum pulls it little."""


def shared_outputs(outputs: list[Output]) -> list[Output]:
    """The target parameters the channels share (a roughness, an IOR)."""
    return [o for o in outputs if o.kind != OutputKind.ERROR and not o.per_channel and o.channel is None]


def gaps(outputs: list[Output], values: dict[str, np.ndarray], spread: dict) -> np.ndarray:
    """N x 3 x k: how far each shared output's value is from its lookup at each channel's grey level
    (unit scale): what a channel must make up for, where the bright channels set a shared parameter."""
    cols = [o.to_unit(values[o.param])[:, None] - np.stack([o.to_unit(v) for v in spread[o.param]], axis=-1)
            for o in shared_outputs(outputs)]
    return np.stack(cols, axis=-1) if cols else np.zeros((len(next(iter(values.values()))), 3, 0))


def correction_columns(layout: Layout, values: dict[str, np.ndarray], channel: int, dtype=np.float64
                       ) -> np.ndarray:
    """N x dims: what the correction of ``channel`` depends on besides the gaps: the other axes as
    the map reads them, the channel's own value and the others' (the brighter first)."""
    grey = layout.grey_axes[0]
    cols = [col for d, col in zip(layout.dims, layout.columns(values, 0, dtype)) if d.axis != grey]
    u = layout.axes[grey].to_unit(np.asarray(values[grey]), dtype)
    a, b = (u[..., c] for c in range(3) if c != channel)
    cols += [u[..., channel], np.maximum(a, b), np.minimum(a, b)]  # not a reduction over an axis of 2: slow
    return np.clip(np.stack(cols, axis=-1), dtype(0.0), dtype(1.0))


@dataclass
class Rows:
    """Training data of one output's correction: inputs (`correction_columns`), gaps (`gaps` at the
    row's channel), what the separable map misses (unit scale), and the point each row comes from."""

    x: np.ndarray
    gap: np.ndarray
    y: np.ndarray
    point: np.ndarray

    def take(self, keep: np.ndarray) -> "Rows":
        return Rows(self.x[keep], self.gap[keep], self.y[keep], self.point[keep])

    @property
    def moved(self) -> np.ndarray:
        """The rows whose channel is given a shared parameter off its own (the rows a correction can reach)."""
        return np.abs(self.gap).max(axis=1, initial=0.0) > 1e-6


class Polynomial:
    """The correction: each gap times a polynomial of total degree ``degree`` in the inputs (so it
    vanishes where no shared parameter is moved off a channel's own: on grey, and wherever the map
    alone holds), fitted by least squares with a ridge (`RIDGE`), robustly (`HUBER`)."""

    def __init__(self, rows: Rows, degree: int):
        self.terms = np.array(monomials(rows.x.shape[1], degree))
        a = self.design(rows.x, rows.gap)
        moved = rows.moved
        w = np.ones(len(rows.y))
        for _ in range(ROUNDS):
            self.coef = self._solve(a, rows.y, w)
            miss = np.abs(rows.y - a @ self.coef)
            scale = max(1.4826 * float(np.median(miss[moved])) if moved.any() else 0.0, 1e-6)
            w = np.minimum(1.0, HUBER * scale / np.maximum(miss, 1e-12))

    @staticmethod
    def _solve(a: np.ndarray, y: np.ndarray, w: np.ndarray) -> np.ndarray:
        if not a.shape[1]:
            return np.zeros(0)
        aw = a * w[:, None]
        lhs = aw.T @ a
        return np.linalg.solve(lhs + RIDGE * max(float(np.trace(lhs)) / len(lhs), 1e-12) * np.eye(len(lhs)),
                               aw.T @ y)

    def design(self, x: np.ndarray, gap: np.ndarray) -> np.ndarray:
        """N x (terms x gaps): each term's monomial times each gap (the fit's matrix)."""
        x = np.asarray(x)
        cols = [m * gap[:, j].astype(x.dtype) for m in _monomials(x, self.terms) for j in range(gap.shape[1])]
        return np.stack(cols, axis=1) if cols else np.zeros((len(x), 0), x.dtype)

    def predict(self, x: np.ndarray, gap: np.ndarray) -> np.ndarray:
        """The correction at N inputs and gaps, in x's precision: each gap's polynomial summed term by
        term (no N x terms design: a texture's blocks are predicted this way)."""
        x = np.asarray(x)
        dt, k = x.dtype, gap.shape[1]
        if not k:
            return np.zeros(len(x), dt)
        coef = self.coef.reshape(len(self.terms), k).astype(dt)
        accs = [np.zeros(len(x), dt) for _ in range(k)]
        tmp = np.empty(len(x), dt)
        for m, c in zip(_monomials(x, self.terms), coef):
            for acc, cj in zip(accs, c):
                acc += np.multiply(m, cj, out=tmp)
        out = accs[0] * gap[:, 0].astype(dt)
        for j in range(1, k):
            out += accs[j] * gap[:, j].astype(dt)
        return out


def _monomials(x: np.ndarray, terms: np.ndarray):
    """Each term's monomial of x's columns (exponents ``terms``), in one buffer the caller uses before
    the next: a product of columns, never a power or a reduction."""
    cols = [np.ascontiguousarray(x[:, d]) for d in range(x.shape[1])]
    m = np.empty(len(x), x.dtype)
    for e in terms:
        m.fill(1)
        for d, p in enumerate(e):
            for _ in range(int(p)):
                m *= cols[d]
        yield m


def cv_miss(rows: Rows, degree: int | None) -> float:
    """Cross-validated mean absolute miss at the moved rows (`Rows.moved`) of the corrected map, by
    folds over points (None: uncorrected); the mean absolute, since a few fits in another optimum are
    no one's to follow. NaN without moved rows."""
    moved = rows.moved
    if not moved.any():
        return math.nan
    if degree is None:
        return float(np.mean(np.abs(rows.y[moved])))
    points = np.unique(rows.point)
    pred = np.full(len(rows.y), np.nan)
    for test in folds(len(points)):
        held = np.isin(rows.point, points[test])
        pred[held] = Polynomial(rows.take(~held), degree).predict(rows.x[held], rows.gap[held])
    return float(np.mean(np.abs(pred - rows.y)[moved]))


def choose_degree(rows: Rows) -> tuple[int, float, float] | None:
    """The degree with the least cross-validated miss, that miss and the uncorrected map's, where it
    gains (`GAIN`); None where it does not, or nothing is moved."""
    before = cv_miss(rows, None)
    if not math.isfinite(before):
        return None
    err, degree = min((cv_miss(rows, d), d) for d in DEGREES)
    return (degree, err, before) if err <= GAIN * before else None


def corrected(outputs: list[Output], polynomials: dict[str, Polynomial], layout: Layout,
              source: dict[str, np.ndarray], values: dict[str, np.ndarray], spread: dict, dtype=np.float64
              ) -> dict[str, np.ndarray]:
    """Assembled target values (`outputs.assemble`, before `finish`) with each per-channel output's
    correction added on its unit scale (and kept within its bounds), at these ``source`` axis values."""
    out = dict(values)
    gap = gaps(outputs, values, spread)
    for o in outputs:
        poly = polynomials.get(o.label)
        if poly is None:
            continue
        v = np.array(out[o.param], copy=True)
        for c in range(3):
            step = poly.predict(correction_columns(layout, source, c, dtype), gap[:, c])
            v[..., c] = o.from_unit(o.to_unit(v[..., c]) + step, v.dtype.type)
        out[o.param] = v
    return out


__all__ = ["corrected", "Polynomial", "Rows", "choose_degree", "correction_columns", "gaps"]
