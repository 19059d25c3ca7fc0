"""The experiment file format (a pydantic model: `remap schema experiment`) and its grid of points."""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum
from pathlib import Path
from typing import Any

import numpy as np
from pydantic import Field, model_validator
from pydantic_core import core_schema

from ..data.configio import load_yaml_model
from ..data.model import Strict as _Strict
from ..data.scene import MAX_SEED, ProbeScene, load_scene
from ..data.settings import Settings
from ..job.job import Target

MAX_POINTS = 100_000


class Range(_Strict):
    start: float
    stop: float
    steps: int = Field(ge=2, le=MAX_POINTS, description="Number of values, ends included.")

    def values(self) -> list[float]:
        return [float(v) for v in np.linspace(self.start, self.stop, self.steps)]


class Sweep(_Strict):
    param: str = Field(description="Source parameter that varies.")
    values: list[Any] | None = Field(None, description="Explicit values (numbers, RGB lists or choices).")
    range: Range | None = Field(None, description="Evenly spaced numbers instead of values.")

    @model_validator(mode="after")
    def _one(self) -> "Sweep":
        if (self.values is None) == (self.range is None):
            raise ValueError("give exactly one of values or range")
        if self.values is not None and not self.values:
            raise ValueError("values is empty")
        return self

    def all_values(self) -> list[Any]:
        return self.range.values() if self.range is not None else list(self.values or [])


class Groups(_Strict):
    param: str = Field(description="Source parameter held at one value per curve.")
    values: list[Any] = Field(min_length=1)


class SourceSide(_Strict):
    adapter: str = Field(description="Adapter of the source model (a name: see `remap adapters`).")
    model: str
    params: dict[str, Any] = Field(default_factory=dict, description="Fixed source parameters.")


class SceneSpec(_Strict):
    file: str | None = Field(None, description="Probe scene YAML, relative to this file (default: the built-in "
                                               "probe).")
    resolution: int | None = Field(None, ge=8, le=4096)
    spp: int | None = Field(None, ge=1, le=65536)
    seed: int | None = Field(None, ge=0, le=MAX_SEED)

    def scene(self, base_dir: Path) -> ProbeScene:
        scene = ProbeScene()
        if self.file:
            path = Path(self.file)
            scene = load_scene(path if path.is_absolute() or path.exists() else base_dir / path)
        return scene.overridden(resolution=self.resolution, spp=self.spp, seed=self.seed)


class PlotChannels(StrEnum):
    MEAN = "mean"
    EACH = "each"


class Side(StrEnum):
    """Whose quantity an experiment reads: the source's, the forward result's or the way back's."""

    SOURCE = "source"
    TARGET = "target"
    BACK = "back"


@dataclass(frozen=True)
class SideParam:
    """A quantity of one side, written "side.name" ("source.alpha", "target.roughness", "back.x"):
    parsed here alone; a model holding one reads and writes that string."""

    side: Side
    name: str

    @classmethod
    def parse(cls, text: str, field: str = "") -> SideParam:
        """``text`` as a SideParam; ``field`` (e.g. "plot.x") names it in the error."""
        side, dot, name = text.partition(".")
        if not dot or not name or side not in {s.value for s in Side}:
            raise ValueError(f"{field + ': ' if field else ''}must look like source.<name>, target.<name> or "
                             f"back.<name>, not {text!r}")
        return cls(Side(side), name)

    def __str__(self) -> str:
        return f"{self.side}.{self.name}"

    @classmethod
    def __get_pydantic_core_schema__(cls, source: Any, handler: Any) -> core_schema.CoreSchema:
        text = core_schema.no_info_after_validator_function(cls.parse, core_schema.str_schema())
        return core_schema.json_or_python_schema(  # one given as such is read from its string
            json_schema=text, python_schema=core_schema.no_info_before_validator_function(
                lambda v: str(v) if isinstance(v, cls) else v, text),
            serialization=core_schema.to_string_ser_schema(when_used="always"))  # a dump to Python too


class PlotSpec(_Strict):
    x: SideParam = Field(description="source.<name>: a source parameter or derived quantity.")
    y: SideParam = Field(description="target.<name> (or back.<name> in a round trip).")
    channels: PlotChannels = Field(PlotChannels.MEAN, description="RGB values: their mean, or one point per channel.")
    xlabel: str | None = None
    ylabel: str | None = None
    title: str | None = None


class CliffSpec(_Strict):
    k: float = Field(4.0, gt=1, description="A step larger than k times the median of its neighbours is a cliff.")
    window: int = Field(3, ge=1, description="Neighbouring steps on each side.")
    params: list[str] | None = Field(None, description="Target parameters checked (default: all fitted).")
    min_step: float = Field(0.002, ge=0, description="Steps below this fraction of a parameter's range (of the "
                                                    "error for the error series) never count.")
    error: bool = Field(True, description="Also look for jumps in the relative RMSE.")
    error_min_step: float = Field(0.005, ge=0, description="Error jumps below this (0.005: half a point of "
                                                          "relative RMSE) never count.")


class ExperimentKind(StrEnum):
    """A sweep remaps each point once; a roundtrip remaps it there and back."""

    SWEEP = "sweep"
    ROUNDTRIP = "roundtrip"


class Experiment(_Strict):
    """A sweep (remap every point of a one-parameter family of source materials) or a round trip
    (remap each result back to the source model)."""

    kind: ExperimentKind
    name: str
    description: str = ""
    figure: str = Field("", description="The paper's figure this reproduces.")
    source: SourceSide
    sweep: Sweep
    groups: Groups | None = None
    target: Target
    back: Target | None = Field(None, description="Round trip: the model to return to (default: the source's, "
                                                  "fitting the swept parameter).")
    compare: str | None = Field(None, description="Round trip: quantity compared, source vs back (default: the "
                                                 "plot's x without its prefix).")
    scene: SceneSpec = SceneSpec()
    options: Settings = Field(default_factory=Settings, description="How every remap runs (as `remap`'s flags).")
    plot: PlotSpec
    cliff: CliffSpec = CliffSpec()

    @model_validator(mode="after")
    def _check(self) -> "Experiment":
        if self.kind is ExperimentKind.SWEEP and (self.back is not None or self.compare is not None):
            raise ValueError("back and compare belong to kind: roundtrip")
        n = len(self.sweep.all_values()) * (len(self.groups.values) if self.groups else 1)
        if n > MAX_POINTS:
            raise ValueError(f"{n} points: at most {MAX_POINTS} in one experiment")
        return self

    def compared(self) -> str:
        """Round trip: the quantity compared, source against back (the plot's x's name by default)."""
        return self.compare or self.plot.x.name

    def back_side(self) -> Target:
        if self.back is not None:
            return self.back
        return Target(adapter=self.source.adapter, model=self.source.model,
                      fix={k: v for k, v in self.source.params.items() if k != self.sweep.param})


def load_experiment(path: str | Path) -> Experiment:
    return load_yaml_model(path, Experiment, "an experiment")


@dataclass(frozen=True)
class Point:
    id: str
    group: Any
    value: Any
    params: dict[str, Any]


def label(v: Any) -> str:
    if isinstance(v, (list, tuple)):
        return "[" + ",".join(f"{x:g}" for x in v) + "]"
    if isinstance(v, float):
        return f"{v:g}"
    return str(v)


def points_of(exp: Experiment) -> list[Point]:
    groups = exp.groups.values if exp.groups else [None]
    out = []
    for gi, g in enumerate(groups):
        for si, v in enumerate(exp.sweep.all_values()):
            params = dict(exp.source.params)
            if exp.groups:
                params[exp.groups.param] = g
            params[exp.sweep.param] = v
            out.append(Point(f"{gi:02d}-{si:03d}", g, v, params))
    return out
