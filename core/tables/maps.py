"""Candidate maps from a table's grid of fits to the target parameters: smooth regressions of each
target parameter on the source's, in the unit cube of the axes.

Three kinds are compared (`METHODS`): a multilinear interpolation of the grid, a low-order
polynomial (the JCGT paper's parametric form, its degree chosen by cross-validation) and a
thin-plate-spline RBF (its smoothing chosen the same way). Each is rebuilt from the grid and its
hyperparameters whenever a table is read, so a table stores data, never code."""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np

FOLDS = 5
RIDGE = 1e-9
POLY_DEGREES = (1, 2, 3)
RBF_SMOOTHING = (0.0, 1e-5, 1e-4, 1e-3, 1e-2)


class Regressor(Protocol):
    def predict(self, x: np.ndarray) -> np.ndarray:
        """N x dims unit coordinates -> N values (unit scale of the target parameter)."""


@dataclass(frozen=True)
class Grid:
    """The training data of one output: the points' unit coordinates, their index on the grid, the
    value, and which points the map may use (the others' fits are in question)."""

    x: np.ndarray
    idx: np.ndarray
    y: np.ndarray
    used: np.ndarray
    shape: tuple[int, ...]
    knots: tuple[np.ndarray, ...] | None = None
    """Each dimension's grid values as coordinates (None: evenly spaced from 0 to 1)."""

    def subset(self, keep: np.ndarray) -> "Grid":
        return Grid(self.x, self.idx, self.y, self.used & keep, self.shape, self.knots)


class Multilinear:
    """Interpolation of the grid, multilinear in each cell; a point left out is filled from its
    neighbours along the grid's lines (`fill`), so the grid stays whole."""

    name = "multilinear"

    def __init__(self, grid: Grid, _: float | int | None = None):
        values = np.full(grid.shape, np.nan)
        values[tuple(grid.idx[grid.used].T)] = grid.y[grid.used]
        self.values = fill(values)
        self.knots = grid.knots or tuple(np.linspace(0.0, 1.0, n) for n in grid.shape)

    def predict(self, x: np.ndarray) -> np.ndarray:
        x = np.clip(np.asarray(x, np.float64), 0.0, 1.0)
        out = np.zeros(len(x))
        # The cell of each point and its weights along each axis, then the 2^d corners summed.
        lo, w = [], []
        for d, k in enumerate(self.knots):
            i = np.clip(np.searchsorted(k, x[:, d], side="right") - 1, 0, len(k) - 2)
            lo.append(i)
            w.append((x[:, d] - k[i]) / (k[i + 1] - k[i]))
        for corner in itertools.product((0, 1), repeat=len(lo)):
            weight = np.ones(len(x))
            for d, c in enumerate(corner):
                weight *= w[d] if c else 1.0 - w[d]
            out += weight * self.values[tuple(lo[d] + c for d, c in enumerate(corner))]
        return out


def fill(values: np.ndarray) -> np.ndarray:
    """Grid nodes without a value (NaN) filled from the nodes along each grid line through them: the
    mean of the linear interpolations between the nearest known nodes on either side, or where a line
    has known nodes on one side only, the linear extrapolation of the two nearest (a linear function
    is filled exactly). Repeated until every node is filled (a node no line reaches takes the mean of
    the nodes that have a value)."""
    out = values.copy()
    if not np.isnan(out).any():
        return out
    if np.isnan(out).all():
        raise ValueError("no point of the grid can be used")
    for _ in range(sum(values.shape)):
        holes = np.argwhere(np.isnan(out))
        if len(holes) == 0:
            return out
        found = {tuple(h): _along_lines(out, tuple(h)) for h in holes}
        filled = {h: v for h, v in found.items() if v is not None}
        if not filled:
            break
        for h, v in filled.items():
            out[h] = v
    out[np.isnan(out)] = float(np.nanmean(out))
    return out


def _along_lines(values: np.ndarray, at: tuple[int, ...]) -> float | None:
    estimates = []
    for d, n in enumerate(values.shape):
        line = [values[at[:d] + (i,) + at[d + 1:]] for i in range(n)]
        known = [i for i, v in enumerate(line) if not np.isnan(v)]
        below = [i for i in known if i < at[d]]
        above = [i for i in known if i > at[d]]
        if below and above:
            a, b = below[-1], above[0]
            estimates.append(line[a] + (line[b] - line[a]) * (at[d] - a) / (b - a))
        elif len(below) >= 2 or len(above) >= 2:
            a, b = (below[-1], below[-2]) if len(below) >= 2 else (above[0], above[1])
            estimates.append(line[a] + (line[a] - line[b]) * (at[d] - a) / (a - b))
    return float(np.mean(estimates)) if estimates else None


def monomials(dims: int, degree: int) -> list[tuple[int, ...]]:
    """Exponent tuples of every monomial of total degree up to ``degree``."""
    return [e for e in itertools.product(range(degree + 1), repeat=dims) if sum(e) <= degree]


class Polynomial:
    """Least squares polynomial of total degree ``degree`` in the unit coordinates."""

    name = "polynomial"

    def __init__(self, grid: Grid, degree: float | int | None):
        self.terms = monomials(grid.x.shape[1], int(degree or 1))
        a = self._design(grid.x[grid.used])
        lhs = a.T @ a + RIDGE * np.eye(len(self.terms))
        self.coef = np.linalg.solve(lhs, a.T @ grid.y[grid.used])

    def _design(self, x: np.ndarray) -> np.ndarray:
        return np.stack([np.prod(x ** np.array(e), axis=1) for e in self.terms], axis=1)

    def predict(self, x: np.ndarray) -> np.ndarray:
        return self._design(np.clip(np.asarray(x, np.float64), 0.0, 1.0)) @ self.coef


class Rbf:
    """scipy's thin-plate-spline RBF with a linear term, smoothed by ``smoothing``."""

    name = "rbf"

    def __init__(self, grid: Grid, smoothing: float | int | None):
        from scipy.interpolate import RBFInterpolator

        self.f = RBFInterpolator(grid.x[grid.used], grid.y[grid.used], kernel="thin_plate_spline", degree=1,
                                 smoothing=float(smoothing or 0.0))

    def predict(self, x: np.ndarray) -> np.ndarray:
        return self.f(np.clip(np.asarray(x, np.float64), 0.0, 1.0))


METHODS = {"multilinear": Multilinear, "polynomial": Polynomial, "rbf": Rbf}


def _degrees(grid: Grid) -> list[float | int | None]:
    """The polynomial degrees with at most half as many terms as used points (at least the first)."""
    n = int(grid.used.sum())
    fits = [d for d in POLY_DEGREES if len(monomials(grid.x.shape[1], d)) <= max(2, n // 2)]
    return list(fits or POLY_DEGREES[:1])


HYPERPARAMETERS = {"polynomial": _degrees, "rbf": lambda grid: list(RBF_SMOOTHING), "multilinear": lambda grid: [None]}
"""Per kind of map (`METHODS`): the hyperparameters cross-validation chooses among, for a grid."""


def hyperparameters(method: str, grid: Grid) -> list[float | int | None]:
    """The hyperparameters cross-validation chooses among, for this much data."""
    return HYPERPARAMETERS[method](grid)


def folds(n: int, k: int = FOLDS, seed: int = 0) -> list[np.ndarray]:
    """``k`` disjoint test masks over ``n`` points (a fixed shuffle: the same folds every build)."""
    order = np.random.default_rng(seed).permutation(n)
    return [np.isin(np.arange(n), order[i::k]) for i in range(k)]


def cv_predictions(method: str, grid: Grid, h: float | int | None) -> np.ndarray:
    """Each used point predicted by the map fitted without its fold (NaN: not predicted)."""
    pred = np.full(len(grid.y), np.nan)
    for test in folds(len(grid.y)):
        train = grid.subset(~test)
        test = test & grid.used
        if not test.any() or int(train.used.sum()) < grid.x.shape[1] + 2:
            continue
        pred[test] = METHODS[method](train, h).predict(grid.x[test])
    return pred


def cv_rms(method: str, grid: Grid, h: float | int | None) -> float:
    """Root-mean-square error on the used points of each fold, predicted by a map fitted without it."""
    try:
        pred = cv_predictions(method, grid, h)
    except (ValueError, np.linalg.LinAlgError):
        return math.inf
    ok = np.isfinite(pred) & grid.used
    return float(np.sqrt(np.mean((pred[ok] - grid.y[ok]) ** 2))) if ok.any() else math.inf


def choose_hyperparameter(method: str, grid: Grid) -> tuple[float | int | None, float]:
    """The hyperparameter with the least cross-validated error, and that error."""
    scored = [(cv_rms(method, grid, h), i, h) for i, h in enumerate(hyperparameters(method, grid))]
    err, _, h = min(scored, key=lambda s: (s[0], s[1]))
    return h, err


def build(method: str, grid: Grid, h: float | int | None) -> Regressor:
    return METHODS[method](grid, h)
