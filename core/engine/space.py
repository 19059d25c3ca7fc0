"""The free parameters of a model as a vector in [0, 1]^n: the optimiser's coordinates."""

from __future__ import annotations

import math

import numpy as np

from ..data.schemas import ModelSpec, ParamKind, Scale, Value


class ParamSpace:
    """Maps the free parameters of a model to a vector in [0, 1]^n and back."""

    def __init__(self, spec: ModelSpec, base: dict[str, Value], free: list[str]):
        self.spec, self.base, self.free = spec, dict(base), list(free)
        self.slices: dict[str, slice] = {}
        i = 0
        for name in self.free:
            n = spec.param(name).size
            self.slices[name] = slice(i, i + n)
            i += n
        self.dim = i

    def _to_unit(self, name: str, x: float) -> float:
        p = self.spec.param(name)
        if p.scale == Scale.LOG:
            return math.log(x / p.lower) / math.log(p.upper / p.lower) if x > 0 else 0.0
        return (x - p.lower) / (p.upper - p.lower)

    def _from_unit(self, name: str, u: float) -> float:
        p = self.spec.param(name)
        u = min(max(float(u), 0.0), 1.0)
        if p.scale == Scale.LOG:
            return p.lower * (p.upper / p.lower) ** u
        return p.lower + u * (p.upper - p.lower)

    def encode(self, params: dict[str, Value]) -> np.ndarray:
        u = np.empty(self.dim)
        for name, sl in self.slices.items():
            v = params[name]
            vals = v if isinstance(v, tuple) else (v,)
            u[sl] = [min(max(self._to_unit(name, float(x)), 0.0), 1.0) for x in vals]
        return u

    def decode(self, u: np.ndarray) -> dict[str, Value]:
        out = dict(self.base)
        for name, sl in self.slices.items():
            vals = tuple(self._from_unit(name, x) for x in u[sl])
            out[name] = vals if self.spec.param(name).kind == ParamKind.RGB else vals[0]
        return out

    def labels(self) -> list[str]:
        out = []
        for name, sl in self.slices.items():
            n = sl.stop - sl.start
            out += [name] if n == 1 else [f"{name}[{c}]" for c in "rgb"[:n]]
        return out

    def separable_groups(self) -> list[slice]:
        return [sl for name, sl in self.slices.items()
                if self.spec.param(name).kind == ParamKind.RGB and self.spec.param(name).separable]

    def jacobian_renders(self, separable: bool = True) -> int:
        """Renders one forward-difference Jacobian costs (one per separable RGB parameter)."""
        return self.dim - 2 * len(self.separable_groups()) if separable else self.dim

    def typical_unit(self, index: int) -> tuple[float, float]:
        """The normalised range of the typical values (`ParamSpec.typical`) of the scalar at ``index``."""
        name = next(n for n, sl in self.slices.items() if sl.start == index)
        typical = self.spec.param(name).typical
        return (0.0, 1.0) if typical is None else (self._to_unit(name, typical[0]), self._to_unit(name, typical[1]))

    def scalar_indices(self) -> list[int]:
        return [sl.start for name, sl in self.slices.items() if self.spec.param(name).kind == ParamKind.SCALAR]
