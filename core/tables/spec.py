"""The table spec (`remap schema table-spec`): a grid over a source model's continuous parameters,
remapped point by point to a target model, from which a smooth map is learnt (Sztrajman et al.,
JCGT 2019).

An axis is a source parameter. A scalar one is sampled at `steps` values over its range (evenly,
or evenly in its logarithm) or at the `values` listed; an RGB one either as a grey level
(`mode: scale`: the map is then applied channel by channel, the paper's separable form, which holds
where each image channel depends on its own component alone) or over the colour cube
(`mode: channels`: three axes, a full regression, n³ points)."""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from pathlib import Path
from enum import StrEnum
from typing import Any, Literal

import numpy as np
from pydantic import Field, model_validator

from ..data.configio import load_yaml_model
from ..data.model import Strict
from ..data.schemas import ParamKind, Scale
from ..data.settings import Settings
from ..experiments.spec import SceneSpec, SourceSide
from ..job.job import Target

MAX_POINTS = 20_000
CHANNELS = "rgb"


class AxisMode(StrEnum):
    """How an RGB axis is sampled: as grey levels (the separable form), or each channel an axis."""

    SCALE = "scale"
    CHANNELS = "channels"


class Axis(Strict):
    range: tuple[float, float] = Field(description="Lowest and highest value sampled (within the parameter's "
                                                   "bounds); held-out and coloured materials are drawn inside it.")
    steps: int | None = Field(None, ge=2, le=64, description="Values sampled, both ends included, evenly spaced "
                                                             "(give steps or values).")
    values: list[float] | None = Field(None, min_length=2, max_length=64,
                                       description="The values sampled, increasing, from the range's lower end to "
                                                   "its upper (instead of steps): closer together where the map bends "
                                                   "(a dark colour, where a target's fits turn from one optimum to "
                                                   "another). Between two of them the map interpolates evenly in the "
                                                   "value, or in its logarithm with scale: log.")
    scale: Scale = Field(Scale.LINEAR, description="Spacing of the values: even, or even in the "
                                                                   "logarithm (roughness: most change is near 0).")
    mode: AxisMode = Field(
        AxisMode.SCALE, description="RGB parameters only. scale: sampled as grey levels, the map applied to each channel "
                             "alone (the separable form; needs a separable parameter); channels: each channel an "
                             "axis of its own (a full regression over the colour cube, n³ points).")

    @model_validator(mode="after")
    def _check(self) -> "Axis":
        lo, hi = self.range
        if not (math.isfinite(lo) and math.isfinite(hi)) or not lo < hi:
            raise ValueError("range must be two finite numbers, the lower first")
        if self.scale == Scale.LOG and lo <= 0:
            raise ValueError("a log axis needs a range above 0")
        if self.steps is None and self.values is None:
            raise ValueError("give steps (values evenly spaced over the range) or values (listed)")
        if self.steps is not None and self.values is not None:
            raise ValueError("give steps or values, not both")
        v = self.values
        if v is not None:
            if v[0] != lo or v[-1] != hi:
                raise ValueError(f"values: {v[0]:g} to {v[-1]:g}; they must begin and end at the range's ends "
                                 f"({lo:g}, {hi:g})")
            bad = next((k for k in range(1, len(v)) if not v[k] > v[k - 1]), None)
            if bad is not None:
                raise ValueError(f"values: {v[bad]:g} (number {bad + 1}) is not above {v[bad - 1]:g}; they must "
                                 "increase")
        return self

    @property
    def count(self) -> int:
        """The number of values sampled."""
        return len(self.values) if self.values is not None else int(self.steps or 0)

    def samples(self) -> list[float]:
        """The values sampled, increasing."""
        if self.values is not None:
            return [float(v) for v in self.values]
        lo, hi = self.range
        if self.scale == Scale.LOG:
            return [float(v) for v in np.geomspace(lo, hi, self.count)]
        return [float(v) for v in np.linspace(lo, hi, self.count)]

    def to_unit(self, v, dtype=np.float64):
        """Values (any array shape) on the range's scale: 0 at its lower end, 1 at its upper, evenly
        in the value or in its logarithm (outside the range: beyond). The maps' coordinate."""
        lo, hi = self.range
        v = np.asarray(v, dtype=dtype)
        if self.scale == Scale.LOG:
            tiny = np.finfo(dtype).tiny
            return (np.log(np.maximum(v, dtype(tiny))) - dtype(math.log(lo))) * dtype(1.0 / (math.log(hi) -
                                                                                             math.log(lo)))
        return (v - dtype(lo)) * dtype(1.0 / (hi - lo))

    def knots(self) -> np.ndarray:
        """The sampled values' coordinates (`to_unit`): evenly spaced from 0 to 1 unless listed."""
        return self.to_unit(np.asarray(self.samples(), np.float64))

    def sample(self, t):
        """The value at ``t`` in [0, 1] of the range, evenly spaced as `scale` says (random draws)."""
        lo, hi = self.range
        t = np.asarray(t, dtype=np.float64)
        if self.scale == Scale.LOG:
            return np.exp(math.log(lo) + t * (math.log(hi) - math.log(lo)))
        return lo + t * (hi - lo)


class TableSpec(Strict):
    """A remap table to build: `remap table build SPEC.yaml --out TABLE`."""

    kind: Literal["table"]
    name: str = Field("", description="A name for people (default: the file's).")
    description: str = ""
    source: SourceSide = Field(description="The source model; `params` holds what every point shares (a "
                                           "distribution, a fixed IOR).")
    axes: dict[str, Axis] = Field(description="Source parameters the grid spans, in order.", min_length=1)
    target: Target = Field(description="The target model; `fix` holds parameters at values (every discrete choice "
                                       "the fit would otherwise try must be held: the map is continuous).")
    holdout: int = Field(10, ge=0, le=1000, description="Source materials drawn at random inside the grid's range "
                                                        "(colours not grey), fitted directly, on which the "
                                                        "candidate maps are compared by image error; 0: by "
                                                        "cross-validation of the grid's parameters alone.")
    colours: int = Field(0, ge=0, le=MAX_POINTS, description="Source materials of every colour drawn at random "
                                                             "inside the ranges (as the held-out ones, another draw) "
                                                             "and fitted, to correct the map where the target couples "
                                                             "a colour's channels, which a grey grid cannot show (a "
                                                             "dielectric's diffuse pinned at 1 in its bright channel "
                                                             "lowers its IOR for all three). Each map is then tried "
                                                             "with the correction and without. Needs one RGB axis "
                                                             "sampled as grey levels.")
    seed: int = Field(0, ge=0, le=2**31 - 1, description="Seed of the held-out draw.")
    continuation: bool = Field(False, description="Refit each grid point once more, from one start: what a smooth "
                                                  "map of the other points' fits gives there; the refit replaces the "
                                                  "first where it is as good (fits that landed in different optima "
                                                  "become one family a map can follow). Twice the fits; off by "
                                                  "default: on the shipped tables it did not bring lookups closer "
                                                  "to direct fits (docs/measurements/tables.md).")
    follow: list[str] = Field(default_factory=list, description="Axes along which each grid point is fitted again "
                                                                "from its neighbour's fit, one start, up the axis and "
                                                                "then back down; the refit replaces the fit where it "
                                                                "ends lower (path following: where a fit from the "
                                                                "exporters' conversion falls into a worse optimum, as "
                                                                "a rough plastic's at high roughness, its "
                                                                "neighbours lead it into theirs, and the fits become "
                                                                "one family a map can follow). Up to two refits a "
                                                                "point per axis; coloured points are then fitted again "
                                                                "from the grid's map, one refit each.")
    scene: SceneSpec = SceneSpec()
    options: Settings = Field(default_factory=Settings, description="How every fit runs (as `remap`'s flags).")

    @model_validator(mode="after")
    def _check(self) -> "TableSpec":
        if len(set(self.follow)) < len(self.follow):
            raise ValueError(f"follow: {', '.join(self.follow)}: an axis named twice (each is followed once)")
        for name in self.follow:
            if name not in self.axes or self.axes[name].mode == AxisMode.CHANNELS:
                raise ValueError(f"follow: {name!r} is not a scalar or grey axis of the grid (axes: "
                                 f"{', '.join(a for a, ax in self.axes.items() if ax.mode != AxisMode.CHANNELS)})")
        shared = sorted(set(self.axes) & set(self.source.params))
        if shared:
            raise ValueError(f"axes.{shared[0]}: also given in source.params: an axis's values come from the grid")
        n = math.prod(a.count ** 3 if a.mode == AxisMode.CHANNELS else a.count for a in self.axes.values())
        if n > MAX_POINTS:
            raise ValueError(f"axes: {n} points, at most {MAX_POINTS} in one table")
        return self


def load_table_spec(path: str | Path) -> TableSpec:
    return load_yaml_model(path, TableSpec, "a table spec")


@dataclass(frozen=True)
class Dim:
    """One coordinate of the map's input: an axis, or one channel of a `channels` axis."""

    axis: str
    channel: int | None
    """None: a scalar axis, or a `scale` axis (its grey level: the channel the map is applied to)."""

    @property
    def label(self) -> str:
        return self.axis if self.channel is None else f"{self.axis}.{CHANNELS[self.channel]}"


@dataclass(frozen=True)
class Layout:
    """The axes as the map sees them: their kinds (from the source model) and the input dimensions."""

    axes: dict[str, Axis]
    kinds: dict[str, str]
    """Axis name -> "scalar" or "rgb"."""

    @property
    def dims(self) -> list[Dim]:
        out = []
        for name, ax in self.axes.items():
            if self.kinds[name] == ParamKind.RGB and ax.mode == AxisMode.CHANNELS:
                out += [Dim(name, c) for c in range(3)]
            else:
                out.append(Dim(name, None))
        return out

    @property
    def separable(self) -> bool:
        """Every RGB axis is a grey `scale`: an RGB target parameter is mapped channel by channel."""
        return not any(self.kinds[n] == ParamKind.RGB and a.mode == AxisMode.CHANNELS for n, a in self.axes.items())

    def grid(self) -> list[tuple[tuple[int, ...], dict[str, Any]]]:
        """Every grid point: its index along each dimension, and its axis values (RGB as triples)."""
        dims = self.dims
        samples = [self.axes[d.axis].samples() for d in dims]
        out = []
        for idx in itertools.product(*(range(len(s)) for s in samples)):
            values: dict[str, Any] = {}
            for d, s, i in zip(dims, samples, idx):
                v = s[i]
                if d.channel is not None:
                    values.setdefault(d.axis, [0.0, 0.0, 0.0])[d.channel] = v
                else:
                    values[d.axis] = [v, v, v] if self.kinds[d.axis] == ParamKind.RGB else v
            out.append((idx, values))
        return out

    def draw(self, n: int, seed: int) -> list[dict[str, Any]]:
        """``n`` source values at random inside the ranges (a scrambled Sobol' sequence over the
        unit cube of every channel: colours are not grey)."""
        from scipy.stats import qmc

        cols: list[tuple[str, int | None]] = []
        for name in self.axes:
            cols += [(name, c) for c in range(3)] if self.kinds[name] == ParamKind.RGB else [(name, None)]
        if n == 0:
            return []
        unit = qmc.Sobol(len(cols), scramble=True, seed=seed).random(1 << max(0, (n - 1).bit_length()))[:n]
        out = []
        for row in unit:
            values: dict[str, Any] = {}
            for (name, c), t in zip(cols, row):
                v = float(self.axes[name].sample(t))
                if c is None:
                    values[name] = v
                else:
                    values.setdefault(name, [0.0, 0.0, 0.0])[c] = v
            out.append(values)
        return out

    @property
    def grey_axes(self) -> list[str]:
        """The RGB axes sampled as grey levels (`mode: scale`)."""
        return [n for n, a in self.axes.items() if self.kinds[n] == ParamKind.RGB and a.mode == AxisMode.SCALE]

    def channel_weights(self, values: dict[str, np.ndarray], dtype=np.float64) -> np.ndarray | None:
        """N x 3: how much each channel counts in an output the channels share (a scalar target
        parameter), which is looked up at each channel's grey level and averaged with these weights.
        A channel's weight is its share of the squared values of the `scale` RGB axes (summed over
        them): a fit minimises the squared pixel error, to which a channel's image counts as its
        brightness squared (so the bright channels decide, as they do in a direct fit). None without
        such an axis; equal weights for black."""
        names = self.grey_axes
        if not names:
            return None
        w = sum(np.square(np.clip(np.asarray(values[n], np.float64), 0.0, None)) for n in names)
        total = w.sum(axis=-1, keepdims=True)
        return np.where(total > 0, w / np.where(total > 0, total, 1.0), 1.0 / 3.0).astype(dtype)

    def features(self, values: dict[str, np.ndarray], channel: int | None) -> np.ndarray:
        """The map's input for source values (each an array: N for a scalar axis, N x 3 for an RGB
        one), as N x dims coordinates in the unit cube. ``channel`` picks the channel of `scale`
        axes (None: their mean), for a target parameter mapped channel by channel."""
        return np.stack(self.columns(values, channel), axis=-1)

    def knots(self) -> tuple[np.ndarray, ...]:
        """Each dimension's grid values as coordinates (`Axis.knots`)."""
        return tuple(self.axes[d.axis].knots() for d in self.dims)

    def columns(self, values: dict[str, np.ndarray], channel: int | None, dtype=np.float64) -> list[np.ndarray]:
        """`features`, a column (a contiguous array) per dimension."""
        cols = []
        for d in self.dims:
            v = np.asarray(values[d.axis])
            if self.kinds[d.axis] == ParamKind.RGB:
                v = v[..., d.channel] if d.channel is not None else (
                    v.mean(axis=-1) if channel is None else v[..., channel])
            cols.append(np.ascontiguousarray(self.axes[d.axis].to_unit(v, dtype)))
        return cols
