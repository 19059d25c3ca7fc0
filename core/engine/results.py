"""What the engine hands back: each stage's account, and the remap's."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from pydantic import Field

from ..data.findings import Verdict
from ..data.model import Strict
from ..data.scene import Lighting
from ..data.schemas import Value
from ..data.settings import Scheme

StageStatus = Literal["converged", "below_noise", "polished", "budget", "stopped"]
CONVERGED: frozenset[str] = frozenset({"converged", "below_noise", "polished"})


class StageResult(Strict):
    """One least-squares fit of the schedule."""

    name: str = Field(description="Stage and level, e.g. 'specular@32px', 'all', 'precise@64spp'.")
    lobe: str | None = Field(description="The source lobe matched, or None for the full image.")
    fitted: list[str] = Field(description="Parameters this stage varied.")
    renders: int = Field(description="Target renders this stage requested.")
    start_error: float = Field(description="Relative RMSE of its best start.")
    error: float = Field(description="Relative RMSE where it ended (at its own level).")
    status: StageStatus = Field(description="converged; below_noise (stopped at the render noise); polished (a "
                                            "polish that used its few renders, as planned); budget (a fit stopped "
                                            "by its render budget); stopped (least squares gave up).")
    detail: str = Field(description="The status in words.")
    seconds: float
    resolution: int = Field(description="Image width of the level, pixels.")
    jacobians: int = Field(0, description="Finite-difference Jacobians rendered.")
    jacobian_updates: int = Field(0, description="Jacobians updated from a step instead (no render).")
    held: dict[str, str] = Field(default_factory=dict, description="Parameters of the stage this pass left where "
                                                                   "the coarse fit put them, and why.")
    kept: bool = Field(True, description="False: the schedule discarded what this stage found (it did not lower "
                                         "the error); its renders were spent all the same.")

    @property
    def converged(self) -> bool:
        return self.status in CONVERGED


class Check(Strict):
    """The source and the fitted target rendered under one held-out condition, at samples and
    seeds the fit never saw (each side twice, half the samples each: their difference is the noise)."""

    condition: Lighting = Field(description="grazing, rim, headlight, environment.")
    label: str = Field(description="The condition in a few words (grazing light, studio environment).")
    description: str
    spp: int = Field(description="Samples per pixel of each side's image (two renders of half as many).")
    resolution: int = Field(description="Image width, pixels.")
    error: float = Field(description="Relative RMSE of the target against the source.")
    perceptual: float = Field(description="Mean ΔE_ITP over the lit pixels.")
    noise_floor: float = Field(description="The error two renders of one material would show here.")
    beyond_noise: float = Field(description="The error the noise does not explain: sqrt(error² - floor²).")
    given: bool = Field(False, description="The job's own scene at its own samples (the fit ran on another), not "
                                           "a held-out light.")


WHITE = "white Lambertian"
"""The reference material a renderer pair's floor is measured on, but for a metal."""


class Disagreement(Strict):
    """Two renderers drawing one kind of material otherwise under one condition: their reference
    materials (clear glasses) differ there beyond the noise, by more than the threshold."""

    condition: Lighting = Field(description="'scene' (the fit's) or a held-out condition.")
    label: str
    kind: str = Field(description="The reference compared (smooth glass, rough glass, white Lambertian).")
    error: float
    noise_floor: float
    beyond_noise: float
    own: str = Field("", description="An adapter whose white Lambertian there is itself off its box-filtered "
                                     "analytic image (`remap check`'s sampling row): the difference is its fault, "
                                     "not a floor; empty where both draw it right or it was not measured.")
    own_error: float = Field(0.0, description="That adapter's white Lambertian's error beyond its noise there.")


@dataclass
class Agreement:
    """Whether the job's two renderers agree on its kind of material (`core.job.agreement`)."""

    checked: bool = False
    """Their references were compared (a transmissive material between two adapters)."""
    disagree: list[Disagreement] = field(default_factory=list)
    unchecked: str = ""
    """Why they could not be compared, where they should have been."""
    floors: dict[str, Disagreement] = field(default_factory=dict)
    """By held-out condition: how far the two renderers' white Lambertians (`Adapter.calibration`)
    differ there beyond their noise, where they do: a floor no material's error can be asked to go
    below (`core.job.agreement.calibration_floors`)."""


@dataclass
class Validation:
    """What the held-out conditions showed, and those that could not be rendered (condition: why)."""

    checks: list[Check] = field(default_factory=list)
    skipped: dict[str, str] = field(default_factory=dict)
    scenes: dict[str, tuple] = field(default_factory=dict)
    """Each checked condition's two scenes as rendered (its lights, samples, seeds): what the renderers'
    own agreement is measured on there."""


@dataclass
class EngineResult:
    """A remap as the engine saw it. ``params`` is the complete target parameter set."""

    params: dict[str, Value]
    fitted: list[str]
    scheme: Scheme
    scheme_used: Scheme
    relative_rmse: float
    perceptual: float
    threshold: float
    """The error threshold the verdict used, on the error beyond the render noise."""
    source_noise: float
    target_noise: float
    renders: int
    seconds: float
    verdict: Verdict
    target_image: np.ndarray
    stages: list[StageResult] = field(default_factory=list)
    jacobian_condition: float | None = None
    validation: Validation = field(default_factory=Validation)
    start_error: float | None = None
    """The informed start's error at the scene (the result is never worse)."""

    @property
    def noise_floor(self) -> float:
        """The error two renders of one material show, source and target noise combined: each
        noise is the difference of two seeds (√2 σ), so the floor is sqrt((n_s² + n_t²) / 2)."""
        return float(np.sqrt((self.source_noise**2 + self.target_noise**2) / 2))
