"""The remap table file (`table.json`, `remap schema table`): the grid and its fits, their findings,
the candidate maps and how each did on held-out materials, and the map chosen. Versioned like the
report, with a digest of its content; `TableMap` rebuilds the chosen map from it and answers
lookups, vectorised (one material or every texel of a texture)."""

from __future__ import annotations

import hashlib
import json
from enum import StrEnum
from pathlib import Path
from typing import Any

import numpy as np
from pydantic import Field, computed_field

from ..data.errors import ConfigError
from ..data.findings import FindingKind
from ..data.model import Strict, WithDerived
from ..data.scene import ProbeScene
from ..data.versioned import JsonFormat, check_version, parse, read_json
from .colours import Polynomial, Rows, correction_columns, corrected, gaps
from .maps import Grid, Regressor, build
from .outputs import ERROR, Output, assemble, target_value
from .spec import Layout, TableSpec
from ..data.schemas import ParamKind

TABLE_SCHEMA_VERSION = 7
"""2: an output the channels share is looked up at each channel's grey level and weighted (was: at the
mean grey level); a table of 1 is built again into its folder, which reuses its fits. 3: coloured
points and maps corrected by them (`colours`); a table of 2 has neither and is read as it is. 4: path
following along axes of the grid (`spec.follow`); tables of 2 and 3 have none and are read as they are.
5: an axis's values may be listed (`values`, closer together where the map bends); earlier tables have
evenly spaced ones and are read as they are. 6: the build record counts its cliffs
(`BuildRecord.cliffs`); a table of 5 has none and is read as it is. 7: a point left out says why as a
type (`PointRecord.left_out_as`) beside its sentence; earlier tables have the sentence alone."""
READS = (2, 3, 4, 5, 6, 7)


class PointVerdict(StrEnum):
    """A grid point's verdict: its fit's (`Verdict.status`), or failed (no fit). Written as its value."""

    OK = "ok"
    MISMATCH = "mismatch"
    UNCHECKED = "unchecked"
    UNRELIABLE = "unreliable"
    FAILED = "failed"

    @property
    def flagged(self) -> bool:
        """Its fit is not to be relied on: unreliable, or no fit at all."""
        return self in (PointVerdict.UNRELIABLE, PointVerdict.FAILED)


class Channels(StrEnum):
    """How a map reads a colour for an output the channels share: each channel's grey level,
    weighted; or the mean grey level."""

    WEIGHTED = "weighted"
    MEAN = "mean"


class LeftOut(StrEnum):
    """Why a point is left out of the regression: its fit failed, a finding questions the fit
    itself (`plan.QUESTIONED`), or it is a cliff (`refits.leave_out_cliffs`)."""

    FAILED = "failed"
    QUESTIONED = "questioned"
    CLIFF = "cliff"


class PointRecord(Strict):
    """One fit of the table: a grid point or a held-out material."""

    id: str
    index: list[int] = Field(default_factory=list, description="Its index along each input dimension (grid points).")
    values: dict[str, Any] = Field(description="The source's axis values (RGB as triples).")
    params: dict[str, Any] | None = Field(description="The fitted target parameters (None: the fit failed).")
    error: float | None = Field(description="Relative RMSE of the fit.")
    noise_floor: float | None = None
    verdict: PointVerdict = Field(description="ok, mismatch, unchecked, unreliable, or failed.")
    reason: str = Field("", description="The verdict's findings in words (or the failure).")
    findings: list[FindingKind] = Field(default_factory=list, description="The kinds of the findings of severity "
                                                                         "unreliable (the findings themselves are "
                                                                         "in the fit's result.json).")
    used: bool = Field(description="Whether the map was fitted to it.")
    left_out: str = Field("", description="Why it was left out of the regression, in words.")
    left_out_as: LeftOut | None = Field(None, description="Why it was left out, as a type (None: used; or a table "
                                                          "of format 6 or earlier, which says it in words alone).")
    renders: int = 0
    seconds: float = 0.0
    key: str = ""
    continued: bool = Field(False, description="A refit from its neighbours (their map, or its neighbour's fit along "
                                               "an axis of `follow`) replaced the first fit.")
    remedy: str = Field("", description="The settings of the refit its first fit's finding named as the remedy, "
                                        "where that refit replaced the first fit ('': none did).")
    first_error: float | None = Field(None, description="The first fit's relative RMSE, where a refit replaced it.")


class Candidate(Strict):
    """One kind of map, fitted to the used grid points, and how it did."""

    method: str
    channels: Channels = Field(
        Channels.WEIGHTED, description="How an output the channels share (a scalar target parameter under a grey `scale` "
                                "axis) reads the source's colour: looked up at each channel's grey level and weighted "
                                "by the channel's value squared, or looked up at the mean grey level.")
    problem: str = Field("", description="Why this map cannot be fitted to the grid's used points ('': it can).")
    hyper: dict[str, float | int | None] = Field(description="Per output: the hyperparameter cross-validation chose "
                                                             "(polynomial degree, RBF smoothing).")
    cv_rms: dict[str, float | None] = Field(description="Per output: cross-validated RMS error on the grid, as a "
                                                        "fraction of the parameter's range (its log range for a log "
                                                        "parameter); None where it could not be measured.")
    holdout_errors: list[float | None] = Field(default_factory=list, description="Relative RMSE of its lookup of "
                                                                                 "each held-out material.")
    ratios: list[float | None] = Field(default_factory=list, description="Each held-out material's lookup error "
                                                                         "over its direct fit's.")
    median_ratio: float | None = None
    p95_ratio: float | None = None
    correction: dict[str, int] | None = Field(
        None, description="Per output: the degree of the polynomial that corrects the map where a colour's channels "
                          "couple, fitted to what it misses at the coloured points (`colours`); None: uncorrected.")
    correction_cv: dict[str, list[float]] = Field(
        default_factory=dict, description="Per corrected output: the cross-validated mean absolute miss of the map at "
                                          "the channels a shared parameter moves off their own lookup, uncorrected "
                                          "and corrected (a fraction of the range).")


class BuildRecord(Strict):
    points: int
    used: int
    flagged: int = Field(description="Grid points whose verdict is unreliable, or whose fit failed.")
    left_out: int = Field(description="Grid points left out of the regression (their fit itself is in question).")
    cliffs: int | None = Field(None, description="Of those, the points left out as cliffs (their fit found another "
                                                 "optimum than their neighbours'); None: built before they were "
                                                 "counted.")
    holdout: int
    renders: int = Field(description="Target renders of every fit and check, all runs.")
    seconds: float = Field(description="Sum of the jobs' own times, all runs.")
    wall_seconds: float = Field(description="This build's wall time (resumed jobs cost nothing).")
    ran_in: str


class Table(WithDerived):
    """`table.json`: a remap table over a model pair."""

    derived_fields = ("digest",)

    schema_version: int
    tool: str
    name: str
    spec: TableSpec
    scene: ProbeScene = Field(description="The probe scene the fits ran under (the spec's, resolved): lookups "
                                          "render under it.")
    source_kinds: dict[str, str] = Field(description="Each axis's kind in the source model (scalar, rgb).")
    source_params: dict[str, Any] = Field(description="The source parameters every point shares (completed with "
                                                      "the model's defaults); a lookup checks a material against "
                                                      "them.")
    target_params: dict[str, Any] = Field(description="The target's complete parameters; the mapped ones are "
                                                      "replaced by the map's values.")
    versions: dict[str, str] = Field(description="Adapter versions the fits were made with.")
    outputs: list[Output]
    points: list[PointRecord]
    holdout: list[PointRecord]
    colours: list[PointRecord] = Field(default_factory=list, description="The coloured points' fits (`spec.colours`), "
                                                                          "from which maps are corrected.")
    candidates: dict[str, Candidate]
    chosen: str = Field(description="The candidate map lookups use (a key of candidates).")
    chosen_why: str
    build: BuildRecord

    @computed_field  # type: ignore[prop-decorator]
    @property
    def digest(self) -> str:
        """SHA-256 of what determines the map (all but the build's account of time and place): the
        same table rebuilt gives the same digest, and lookups stored with it stay valid."""
        timing = {"seconds", "renders", "left_out_as"}  # left_out_as restates `used` and `left_out`
        doc = self.model_dump(mode="json", exclude={"digest": True, "build": True, "tool": True,
                                                    "points": {"__all__": timing}, "holdout": {"__all__": timing},
                                                    "colours": {"__all__": timing}})
        if not doc["colours"]:  # format 2 had none: its tables keep their digests
            del doc["colours"], doc["spec"]["colours"]
        if not doc["spec"]["follow"]:  # nor had 3 path following
            del doc["spec"]["follow"]
        for ax in doc["spec"]["axes"].values():  # nor 4 listed values
            if ax["values"] is None:
                del ax["values"]
        doc["spec"]["options"].pop("inputs", None)  # its fits never vary them (`Settings.for_study`)
        for c in doc["candidates"].values():
            if c["correction"] is None:
                del c["correction"], c["correction_cv"]
        return hashlib.sha256(json.dumps(doc, sort_keys=True, ensure_ascii=False).encode()).hexdigest()

    @property
    def layout(self) -> Layout:
        return Layout(self.spec.axes, self.source_kinds)

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(self.spec.axes[d.axis].count for d in self.layout.dims)


def grid_of(table: Table, output: Output) -> Grid:
    """The training data of one output, from the table's points."""
    layout, pts = table.layout, table.points
    vals = {name: np.array([p.values[name] for p in pts], np.float64) for name in table.spec.axes}
    x = layout.features(vals, None)
    y = np.array([target_value(p.params, p.error, output) for p in pts])
    used = np.array([p.used for p in pts]) & np.isfinite(y)
    return Grid(x, np.array([p.index for p in pts], int), np.nan_to_num(y), used, table.shape, layout.knots())


class TableMap:
    """A table's map, ready for lookups: target parameters for source axis values."""

    def __init__(self, table: Table, method: str | None = None):
        """``method``: a key of the table's candidates (its chosen map by default)."""
        self.table, self.method = table, method or table.chosen
        c = table.candidates[self.method]
        self.weighted = c.channels == Channels.WEIGHTED
        self.regressors: dict[str, Regressor] = {o.label: build(c.method, grid_of(table, o), c.hyper.get(o.label))
                                                 for o in table.outputs}
        self.corrections: dict[str, Polynomial] = {}
        if c.correction:
            self.corrections = {o.label: Polynomial(correction_rows(table, self, o), c.correction[o.label])
                                for o in table.outputs if o.label in c.correction}

    def corrector(self, values: dict[str, np.ndarray], dtype=np.float64):
        """The correction of assembled values at these source values (None: this map has none)."""
        if not self.corrections:
            return None
        return lambda assembled, spread: corrected(self.table.outputs, self.corrections, self.table.layout, values,
                                                   assembled, spread, dtype)

    def predict(self, values: dict[str, Any], *, finished: bool = True) -> dict[str, np.ndarray]:
        """Target values (N, or N x 3 for RGB) for source axis values (N, or N x 3; or a single
        material's scalars and triples, giving N = 1), clamped to the grid's range; as the map's
        outputs (a conductor's reflectivity and edge tint) when not ``finished``."""
        arr = self._arrays(values)
        return self._assemble(arr, self.corrector(arr), finished)

    def uncorrected(self, values: dict[str, Any]) -> tuple[dict[str, np.ndarray], dict]:
        """The map's outputs without the coloured points' correction, and each shared output's
        lookups at each channel's grey level (what the correction is given)."""
        kept: dict = {}

        def keep(assembled: dict, spread: dict) -> dict:
            kept.update(spread)
            return assembled

        return self._assemble(self._arrays(values), keep, False), kept

    def _arrays(self, values: dict[str, Any]) -> dict[str, np.ndarray]:
        layout = self.table.layout
        arr = {k: np.asarray(values[k], np.float64) for k in self.table.spec.axes}
        return {k: (v.reshape(-1, 3) if layout.kinds[k] == ParamKind.RGB else v.reshape(-1)) for k, v in arr.items()}

    def _assemble(self, arr: dict[str, np.ndarray], correct, finished: bool) -> dict[str, np.ndarray]:
        layout = self.table.layout
        features: dict[int | None, np.ndarray] = {}

        def at(channel: int | None) -> np.ndarray:  # each channel's coordinates, computed once
            if channel not in features:
                features[channel] = layout.features(arr, channel)
            return features[channel]

        def each_channel(o: Output) -> np.ndarray:  # 3 x N: the three channels' coordinates in one call
            return o.from_unit(self.regressors[o.label].predict(np.concatenate([at(c) for c in range(3)]))
                               ).reshape(3, -1)

        return assemble(self.table.outputs, each_channel,
                        lambda o: o.from_unit(self.regressors[o.label].predict(at(None))),
                        layout.channel_weights(arr) if self.weighted else None, correct, finished)

    def params(self, values: dict[str, Any]) -> tuple[dict[str, Any], float]:
        """One material's complete target parameters and the error a direct fit reaches there."""
        pred = self.predict(values)
        params = dict(self.table.target_params)
        for k, v in pred.items():
            if k != ERROR:
                params[k] = [float(x) for x in v[0]] if v.ndim == 2 else float(v[0])
        return params, float(pred[ERROR][0])


def correction_rows(table: Table, tmap: TableMap, output: Output) -> Rows:
    """What the uncorrected map misses of a per-channel output at the used grid and coloured points
    (unit scale), a row per channel, with the correction's inputs and gaps there."""
    pts = [p for p in table.points + table.colours if p.used]
    vals = {name: np.array([p.values[name] for p in pts], np.float64) for name in table.spec.axes}
    pred, spread = tmap.uncorrected(vals)
    gap = gaps(table.outputs, pred, spread)
    xs, gs, ys, ids = [], [], [], []
    for c in range(3):
        y = np.array([target_value(p.params, p.error, output, channel=c) for p in pts])
        miss = y - output.to_unit(pred[output.param][:, c])
        ok = np.isfinite(miss)
        xs.append(correction_columns(table.layout, vals, c)[ok])
        gs.append(gap[ok, c])
        ys.append(miss[ok])
        ids.append(np.flatnonzero(ok))
    return Rows(np.concatenate(xs), np.concatenate(gs), np.concatenate(ys), np.concatenate(ids))


def outside(table: Table, values: dict[str, Any]) -> list[str]:
    """The axes whose values lie outside the grid's range, in words (clamped by the map)."""
    out = []
    for name, ax in table.spec.axes.items():
        v = np.asarray(values[name])
        v = v if v.dtype in (np.float32, np.float64) else v.astype(np.float64)
        lo, hi = ax.range
        tol = 1e-4 * (hi - lo)  # an image's quantisation (a 16-bit PNG's 1.0, 0.4) is not outside
        if lo - tol <= float(v.min()) and float(v.max()) <= hi + tol:
            continue
        below, above = v < lo - tol, v > hi + tol
        if below.any() or above.any():
            shown = (f"{float(v.min()):.4g}" if below.any() else f"{float(v.max()):.4g}")
            what = "below" if below.any() else "above"
            count = "" if v.size <= 3 else f" ({int((below | above).sum())} of {v.size} values)"
            out.append(f"{name} {shown} {what} the table's range [{lo:g}, {hi:g}]{count}")
    return out


def write_table(path: Path, table: Table) -> Path:
    from ..data.atomic import write_text_atomic

    return write_text_atomic(path, json.dumps(table.model_dump(mode="json"), indent=1, ensure_ascii=False) + "\n")


def table_file(path: str | Path) -> Path:
    """A table given as its folder or as its file: the file."""
    p = Path(path)
    return p / "table.json" if p.is_dir() else p


TABLE_FORMAT = JsonFormat(kind="table format", reads=READS,
                          older="build it again with `remap table build` into its folder (its stored fits are reused)",
                          missing="not found: give a table built by `remap table build` (its folder or its table.json)",
                          edited="was edited after it was built (its digest does not match its content): build it "
                                 "again")


def read_table(path: str | Path) -> Table:
    """A table file, checked: its format version and its digest (an edited table is refused)."""
    p = table_file(path)
    doc = read_json(p, TABLE_FORMAT)
    if not isinstance(doc, dict) or "chosen" not in doc or not isinstance(doc.get("schema_version"), int):
        raise ConfigError("not a remap table (build one with `remap table build SPEC.yaml --out DIR`)", file=str(p))
    check_version(doc, TABLE_FORMAT, str(p))
    return parse(doc, Table, TABLE_FORMAT, str(p), digest="digest")
