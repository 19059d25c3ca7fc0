"""What a table regresses: a target parameter, or one channel of it, on a unit scale; a conductor's
complex IOR through its reflectivity and edge tint; and the direct fit's error.

A conductor's eta and k trade off against each other in an image (the fit's Jacobian is
ill-conditioned along them), so fits at neighbouring grid points land anywhere along that
trade-off, and interpolating eta and k separately leaves it. Its reflectivity and edge tint
(Gulbrandsen 2014, an exact reparameterisation, `core.data.appearance`) are what the image fixes: a
table maps those and turns them back into eta and k."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from enum import StrEnum
from typing import Any

import numpy as np
from pydantic import Field

from ..data.appearance import eta_k_from_reflectivity, reflectivity_edge_tint
from ..data.model import Strict
from ..data.schemas import ModelSpec, ParamKind, ParamSpec, Scale
from .spec import CHANNELS

ERROR = "error"
"""The output that maps a direct fit's relative RMSE (its logarithm): what a fit reaches there."""
PARTS = ("reflectivity", "edge_tint")


class OutputKind(StrEnum):
    """What an output maps: a scalar parameter, an RGB one (or a channel of it), or the fit's error."""

    SCALAR = "scalar"
    RGB = "rgb"
    ERROR = "error"


class Output(Strict):
    """One regressed quantity: a target parameter (or one channel of it), on its unit scale."""

    param: str
    kind: OutputKind
    channel: int | None = Field(None, description="The channel of an RGB parameter mapped by a regression of its "
                                                  "own (a full regression); None otherwise.")
    per_channel: bool = Field(False, description="An RGB parameter whose one regression is applied to each channel "
                                                 "with that channel of the source's colours (the separable form).")
    lower: float
    upper: float
    scale: Scale
    via: list[str] = Field(default_factory=list, description="For a conductor's reflectivity or edge tint (`param`): "
                                                             "the target's eta and k it stands for.")
    via_upper: list[float] = Field(default_factory=list, description="Their upper bounds (both have 0 below).")

    @property
    def label(self) -> str:
        return self.param if self.channel is None else f"{self.param}.{CHANNELS[self.channel]}"

    def to_unit(self, v) -> np.ndarray:
        v = np.asarray(v, np.float64)
        if self.scale == Scale.LOG:
            return (np.log(np.maximum(v, self.lower)) - math.log(self.lower)) / (math.log(self.upper) -
                                                                                  math.log(self.lower))
        return (v - self.lower) / (self.upper - self.lower)

    def from_unit(self, t, dtype=np.float64) -> np.ndarray:
        t = np.clip(np.asarray(t, dtype), dtype(0.0), dtype(1.0))
        if self.scale == Scale.LOG:
            lo, hi = math.log(self.lower), math.log(self.upper)
            return np.exp(dtype(lo) + t * dtype(hi - lo))
        return dtype(self.lower) + t * dtype(self.upper - self.lower)


def outputs_for(spec: ModelSpec, names: list[str], separable: bool) -> list[Output]:
    """The regressions that map these target parameters (a conductor's eta and k as its reflectivity
    and edge tint); then the direct fit's error."""
    out = []
    pair = spec.complex_ior if spec.complex_ior and all(n in names for n in spec.complex_ior) else None
    for name in names:
        if pair and name in pair:
            continue
        p: ParamSpec = spec.param(name)
        out += _channels(p, separable, param=name, lower=p.lower, upper=p.upper, scale=p.scale)
    if pair:
        eta, k = (spec.param(n) for n in pair)
        for part, upper in zip(PARTS, (0.999, 1.0)):
            out += _channels(eta, separable and k.separable, param=part, lower=0.0, upper=upper, scale="linear",
                             via=list(pair), via_upper=[eta.upper, k.upper])
    out.append(Output(param=ERROR, kind="error", lower=1e-4, upper=10.0, scale="log"))
    return out


def _channels(p: ParamSpec, separable: bool, **common) -> list[Output]:
    if p.kind == ParamKind.RGB and separable and p.separable:
        return [Output(kind="rgb", per_channel=True, **common)]
    if p.kind == ParamKind.RGB:
        return [Output(kind="rgb", channel=c, **common) for c in range(3)]
    return [Output(kind="scalar", **common)]


def target_value(params: dict[str, Any] | None, error: float | None, output: Output,
                 channel: int | None = None) -> float:
    """A fit's value of one output, on the output's unit scale (NaN where the fit has none); an RGB
    output's own channel, else ``channel``, else the mean of the three."""
    if params is None:
        return math.nan
    if output.kind == OutputKind.ERROR:
        return float(output.to_unit(error)) if error else math.nan
    if output.via:
        if any(n not in params for n in output.via):
            return math.nan
        v = reflectivity_edge_tint(*(params[n] for n in output.via))[PARTS.index(output.param)]
    else:
        v = params.get(output.param)
        if v is None:
            return math.nan
    if output.kind == OutputKind.RGB:
        c = output.channel if output.channel is not None else channel
        v = float(np.mean(v)) if c is None else float(np.asarray(v)[c])
    return float(output.to_unit(v))


def assemble(outputs: list[Output], each_channel: Callable[[Output], Sequence[np.ndarray]],
             at_mean: Callable[[Output], np.ndarray], weights: np.ndarray | None,
             correct: Callable[[dict, dict], dict] | None = None, finished: bool = True) -> dict[str, np.ndarray]:
    """Target values from an output's lookups at each channel's grey level (``each_channel``: three
    arrays of N, red first)
    and at the mean grey level (``at_mean``: N), whichever it needs: an RGB parameter mapped channel
    by channel takes the first; one channel of a target colour that is not separable the second; a
    scalar the channels share the first averaged with ``weights`` (N x 3, `Layout.channel_weights`),
    or the second where there are none. Then ``correct`` (the coloured points' correction, on the
    outputs' own quantities, given also each shared output's lookups at each channel's grey level),
    and `finish` unless not ``finished``."""
    out: dict[str, np.ndarray] = {}
    chans: dict[str, list] = {}
    spread: dict[str, Sequence[np.ndarray]] = {}
    for o in outputs:
        if o.per_channel:
            out[o.param] = np.stack(each_channel(o), axis=-1)
        elif o.channel is not None:
            chans.setdefault(o.param, [None] * 3)[o.channel] = at_mean(o)
        else:
            if weights is not None or (correct is not None and o.kind != OutputKind.ERROR):
                spread[o.param] = each_channel(o)
            if weights is None:
                out[o.param] = at_mean(o)
            else:  # no N x 3 array in between: a texture's millions of texels
                out[o.param] = sum(weights[:, c] * v for c, v in enumerate(spread[o.param]))
    out.update({k: np.stack(v, axis=-1) for k, v in chans.items()})
    if correct is not None:
        out = correct(out, spread)
    return finish(outputs, out) if finished else out


def finish(outputs: list[Output], values: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Predicted outputs as target parameters: a reflectivity and edge tint turned back into eta and k,
    within their bounds, keeping the reflectivity where a bound cuts in (the edge tint gives way)."""
    via = next((o for o in outputs if o.via), None)
    if via is None:
        return values
    r, g = values.pop(PARTS[0]), values.pop(PARTS[1])
    dtype = r.dtype
    eta, k = within_bounds(np.asarray(r, np.float64), *eta_k_from_reflectivity(r, g), *via.via_upper)
    values[via.via[0]], values[via.via[1]] = eta.astype(dtype), k.astype(dtype)
    return values


def within_bounds(r, eta, k, eta_max: float, k_max: float) -> tuple[np.ndarray, np.ndarray]:
    """eta and k moved into [0, eta_max] x [0, k_max] along the curve of constant reflectivity r
    (near r = 1 the edge tint asks for a k no bound allows): k held at its bound and eta solved for r,
    the root nearest the eta asked for; eta held at its bound and k solved likewise."""
    r = np.clip(r, 0.0, 0.999999)
    over_k = k > k_max
    if over_k.any():
        kk = np.full_like(k, k_max)
        a, b, c = r - 1.0, 2.0 * (r + 1.0), (r - 1.0) * (1.0 + kk * kk)
        disc = np.sqrt(np.maximum(b * b - 4 * a * c, 0.0))
        roots = np.stack([(-b + disc) / (2 * a), (-b - disc) / (2 * a)])
        nearest = np.take_along_axis(roots, np.abs(roots - eta).argmin(axis=0)[None], axis=0)[0]
        eta = np.where(over_k, np.maximum(nearest, 0.0), eta)
        k = np.where(over_k, k_max, k)
    over_eta = eta > eta_max
    if over_eta.any():
        n = np.minimum(eta, eta_max)
        k = np.where(over_eta, np.sqrt(np.maximum((r * (n + 1) ** 2 - (n - 1) ** 2) / (1 - r), 0.0)), k)
        eta = n
    return np.clip(eta, 0.0, eta_max), np.clip(k, 0.0, k_max)


def param_bounds(outputs: list[Output]) -> dict[str, tuple[float, float]]:
    """Each mapped target parameter's bounds (eta and k for a reflectivity and edge tint)."""
    out = {}
    for o in outputs:
        if o.via:
            out.update({o.via[0]: (0.0, o.via_upper[0]), o.via[1]: (0.0, o.via_upper[1])})
        elif o.kind != OutputKind.ERROR:
            out[o.param] = (o.lower, o.upper)
    return out


LOG_GAIN = 0.9
"""A logarithmic scale is taken when it cuts the cross-validated error (in the parameter's own units) to this."""


def choose_scales(outputs: list[Output], grid_of) -> list[Output]:
    """Each output on the scale, linear or logarithmic, that predicts the grid better (a roughness
    that follows √α over a logarithmic α axis is a straight line in the logarithm; an α that follows
    r² over a linear r axis is a parabola in the linear), judged by cross-validation of the
    multilinear and RBF maps in the units of the parameter's own scale (a log parameter's errors are
    relative: 0.004 off an α of 0.01 is a highlight twice as bright); the parameter's own scale
    unless the other cuts that error to `LOG_GAIN` of it. ``grid_of``: an output's training data."""
    out = []
    for o in outputs:
        grid = grid_of(o)
        values = o.from_unit(grid.y)[grid.used]
        if o.kind == OutputKind.ERROR or not values.size or float(values.min()) <= 0:
            out.append(o)
            continue
        other = o.model_copy(update={"scale": Scale.LINEAR} if o.scale == Scale.LOG else
                             {"scale": Scale.LOG, "lower": max(o.lower, float(values.min()) / 2)})
        own, alt = (_cv_error(enc, grid_of(enc), o.to_unit(values), o) for enc in (o, other))
        out.append(other if alt < LOG_GAIN * own else o)
    return out


def _cv_error(enc: Output, grid, truth: np.ndarray, judge: Output) -> float:
    """Cross-validated RMS error of an encoding's maps, in ``judge``'s unit scale."""
    from .maps import cv_predictions

    errors = []
    for method, h in (("multilinear", None), ("rbf", 0.0)):
        try:
            pred = judge.to_unit(enc.from_unit(cv_predictions(method, grid, h))[grid.used])
        except (ValueError, np.linalg.LinAlgError):
            continue
        ok = np.isfinite(pred)
        if ok.any():
            errors.append(float(np.sqrt(np.mean((pred[ok] - truth[ok]) ** 2))))
    return min(errors, default=math.inf)
