"""A table's map baked on a fine regular grid over its unit cube, for textures: millions of texels
are looked up by multilinear interpolation of the baked values, the cell and weights of each texel
computed once and shared by every output that reads the same coordinates (bench/tables.py
measures the time and what baking costs in accuracy)."""

from __future__ import annotations

import itertools

import numpy as np

from .outputs import assemble, ERROR, OutputKind
from .spec import Axis
from .table import TableMap

NODES = {1: 257, 2: 129, 3: 49, 4: 21}
"""Nodes per dimension of the baked grid, by the map's dimensions (about two million values at most)."""

BLOCK = 1 << 16
"""Points looked up at once (measured on a 2048² texture set of three inputs: bench/tables.py speed)."""


class _Cells:
    """Each point's cell in a grid of ``n`` nodes per dimension and the weights of its corners."""

    def __init__(self, columns: list[np.ndarray], shape: tuple[int, ...]):
        d = len(columns)
        strides = [int(np.prod(shape[k + 1:])) for k in range(d)]
        self.base = np.zeros(len(columns[0]), np.int32)
        fracs = []
        for col, stride, n in zip(columns, strides, shape):
            pos = np.clip(col, np.float32(0.0), np.float32(1.0)) * np.float32(n - 1)
            lo = np.minimum(pos.astype(np.int32), np.int32(n - 2))
            fracs.append(pos - lo.astype(np.float32))  # float32 throughout: float32 - int32 would be float64
            self.base += lo * np.int32(stride)
        self.corners = []
        for corner in itertools.product((0, 1), repeat=d):
            w = None
            for f, c in zip(fracs, corner):
                part = f if c else np.float32(1.0) - f
                w = part.copy() if w is None else np.multiply(w, part, out=w)
            self.corners.append((sum(c * s for c, s in zip(corner, strides)), w))

    def interpolate(self, lut: np.ndarray) -> np.ndarray:
        flat = lut.ravel()
        out = np.zeros(len(self.base), np.float32)
        for offset, w in self.corners:
            out += w * flat.take(self.base + offset)
        return out


class DenseMap:
    """`TableMap.predict` for many points at once, from the map baked on a fine grid."""

    def __init__(self, tmap: TableMap, nodes: int | None = None):
        self.tmap, self.table = tmap, tmap.table
        want = nodes or NODES.get(len(self.table.shape), 11)
        layout = self.table.layout
        axes = [_nodes(layout.axes[d.axis], want) for d in layout.dims]
        self.shape = tuple(len(a) for a in axes)
        grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, len(axes))
        self.luts = {o.label: tmap.regressors[o.label].predict(grid).astype(np.float32).reshape(self.shape)
                     for o in self.table.outputs}

    def predict(self, values: dict[str, np.ndarray], errors: bool = False) -> dict[str, np.ndarray]:
        """Target values for N points (each axis N, or N x 3), as `TableMap.predict` (float32);
        the error output only when ``errors``. Looked up BLOCK points at a time: a block's cells and
        weights stay in the cache (a 2048² texture set at once spends more time on memory)."""
        n = len(next(iter(values.values())))
        if n <= BLOCK:
            return self._predict(values, errors)
        out: dict[str, np.ndarray] = {}
        for start in range(0, n, BLOCK):
            part = self._predict({k: v[start:start + BLOCK] for k, v in values.items()}, errors)
            for k, v in part.items():
                if k not in out:
                    out[k] = np.empty((n, *v.shape[1:]), v.dtype)
                out[k][start:start + len(v)] = v
        return out

    def _predict(self, values: dict[str, np.ndarray], errors: bool) -> dict[str, np.ndarray]:
        layout = self.table.layout
        cells: dict[int | None, _Cells] = {}

        def at(channel: int | None) -> _Cells:
            if channel not in cells:
                cells[channel] = _Cells(layout.columns(values, channel, np.float32), self.shape)
            return cells[channel]

        outputs = [o for o in self.table.outputs if errors or o.kind != OutputKind.ERROR]
        return assemble(outputs,
                        lambda o: [_decode(o, at(c).interpolate(self.luts[o.label])) for c in range(3)],
                        lambda o: _decode(o, at(None).interpolate(self.luts[o.label])),
                        layout.channel_weights(values, np.float32) if self.tmap.weighted else None,
                        self.tmap.corrector(values, np.float32))


def _nodes(axis: Axis, want: int) -> np.ndarray:
    """The baked grid's nodes along an axis (coordinates, evenly spaced), with each of the axis's
    own values on a node, so that a multilinear map is baked exactly: the first division of the
    range from ``want`` nodes (or the axis's own count) up to twice as many steps that puts each on
    a node, which evenly spaced values always find (a multiple of their steps). Listed values that
    fall on none lie between nodes, and the bake rounds the map's bend there off over one node's
    spacing."""
    knots, low = axis.knots(), max(want - 1, axis.count - 1)
    aligned = (m for m in range(low, 2 * low + 1) if np.allclose(knots * m, np.round(knots * m), rtol=0, atol=1e-9))
    return np.linspace(0.0, 1.0, next(aligned, low) + 1)


def _decode(output, t: np.ndarray) -> np.ndarray:
    return output.from_unit(t, np.float32)


__all__ = ["ERROR", "DenseMap"]
