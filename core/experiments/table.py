"""An experiment's table (`results.csv`) and its summary (`summary.json`)."""

from __future__ import annotations

import csv
import io
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from pydantic import Field

from ..data.atomic import write_text_atomic
from ..data.model import Strict
from ..data.schemas import Value
from .analysis import Leg, Row
from .spec import Experiment, label


@dataclass
class ExperimentResult:
    exp: Experiment
    rows: list[Row]
    cliffs: list[dict[str, Any]]
    fit: dict[str, float] | None
    files: list[Path]
    seconds: float
    resumed: int
    where: str = "this process"

    @property
    def legs(self) -> list[Leg]:
        return [leg for r in self.rows for leg in r.legs]


def _cells(prefix: str, d: dict[str, Value]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for k, v in d.items():
        if isinstance(v, (tuple, list)):
            out[f"{prefix}{k}"] = f"{float(np.mean(v)):.6g}"
            for c, x in zip("rgb", v):
                out[f"{prefix}{k}_{c}"] = f"{float(x):.6g}"
        elif isinstance(v, float):
            out[f"{prefix}{k}"] = f"{v:.6g}"
        else:
            out[f"{prefix}{k}"] = v
    return out


def _leg_cells(prefix: str, leg: Leg) -> dict[str, Any]:
    rep = leg.report
    d = _cells(prefix, {k: v for k, v in leg.params.items() if k in rep.fitted})
    d.update(_cells(prefix, leg.derived))
    m = rep.metrics
    d.update({f"{prefix}relative_rmse": f"{m.relative_rmse:.5f}", f"{prefix}perceptual": f"{m.perceptual:.3f}",
              f"{prefix}noise_floor": f"{m.noise_floor:.5f}", f"{prefix}renders": rep.renders,
              f"{prefix}seconds": f"{rep.seconds:.3f}", f"{prefix}reliable": rep.reliable,
              f"{prefix}verdict": rep.verdict, f"{prefix}reason": "" if rep.reliable else rep.reason})
    return d


def write_csv(path: Path, exp: Experiment, rows: list[Row]) -> Path:
    records = []
    for r in rows:
        rec: dict[str, Any] = {"point": r.point.id}
        if exp.groups:
            rec["group"] = label(r.point.group)
        rec[f"source.{exp.sweep.param}"] = label(r.point.value)
        rec.update(_cells("source.", {k: v for k, v in r.source.items()
                                      if k not in (exp.sweep.param,) and not isinstance(v, str)}))
        rec.update(_leg_cells("target.", r.forward))
        if r.back is not None:
            rec.update(_leg_cells("back.", r.back))
        rec.update({"cliff": bool(r.cliff), "flagged": r.flagged, "mismatch": r.mismatch, "why": r.why()})
        records.append(rec)
    columns: list[str] = []
    for rec in records:
        columns += [c for c in rec if c not in columns]
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=columns)
    w.writeheader()
    for rec in records:
        w.writerow(rec)
    return write_text_atomic(path, buf.getvalue())


SUMMARY_SCHEMA_VERSION = 1


class Cliff(Strict):
    before: str = Field(description="The point before the jump.")
    after: str = Field(description="The point after it.")
    why: list[str] = Field(description="What jumped there, one line for each parameter or error.")
    short: str


class RoundtripFit(Strict):
    """A roundtrip's line of recovered against original values (NaN where fewer than two points, or no
    spread, leave none to fit: written as NaN, as before)."""

    points: int
    slope: float
    intercept: float
    r2: float
    rms_from_unit_line: float


class ExperimentSummary(Strict):
    """`summary.json`: an experiment's points and what they showed (`remap schema experiment-summary`)."""

    schema_version: int = SUMMARY_SCHEMA_VERSION
    name: str
    figure: str
    points: int
    flagged: int = Field(description="Points whose verdict is not ok.")
    unstable: int
    after_a_cliff: int
    model_mismatch_only: int
    cliffs: list[Cliff]
    roundtrip_fit_unflagged: RoundtripFit | None = Field(description="A roundtrip's fit of recovered against original "
                                                                     "(None: a sweep).")
    median_relative_rmse: float | None
    renders: int = Field(description="Target renders of this run (resumed points not counted).")
    renders_all_points: int
    remap_seconds_all_points: float
    remaps_resumed: int
    ran_in: str
    seconds: float
    files: list[str]


def summary(result: ExperimentResult) -> ExperimentSummary:
    rows, legs = result.rows, result.legs
    return ExperimentSummary(
        name=result.exp.name,
        figure=result.exp.figure,
        points=len(rows),
        flagged=sum(r.flagged for r in rows),
        unstable=sum(any(leg.unstable for leg in r.legs) for r in rows),
        after_a_cliff=sum(bool(r.cliff) for r in rows),
        model_mismatch_only=sum(r.mismatch for r in rows),
        cliffs=[Cliff(before=rows[c["before"]].point.id, after=rows[c["after"]].point.id, why=c["why"],
                      short=c["short"]) for c in result.cliffs],
        roundtrip_fit_unflagged=result.fit,
        median_relative_rmse=float(np.median([r.forward.relative_rmse for r in rows])) if rows else None,
        renders=int(sum(leg.report.renders for leg in legs if not leg.resumed)),
        renders_all_points=int(sum(leg.report.renders for leg in legs)),
        remap_seconds_all_points=float(sum(leg.report.seconds for leg in legs)),
        remaps_resumed=result.resumed,
        ran_in=result.where,
        seconds=result.seconds,
        files=[p.name for p in result.files],
    )
