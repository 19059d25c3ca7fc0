"""What the engine hands back: each stage's account, and the remap's."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from pydantic import Field

from ..findings import Verdict
from ..model import Strict
from ..schemas import Value

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


@dataclass
class EngineResult:
    """A remap as the engine saw it. ``params`` is the complete target parameter set."""

    params: dict[str, Value]
    fitted: list[str]
    scheme: str
    scheme_used: str
    relative_rmse: float
    perceptual: float
    threshold: float
    """The error threshold the verdict used (the setting, or more where the render noise demands)."""
    source_noise: float
    target_noise: float
    renders: int
    seconds: float
    verdict: Verdict
    target_image: np.ndarray
    stages: list[StageResult] = field(default_factory=list)
    jacobian_condition: float | None = None

    @property
    def noise_floor(self) -> float:
        """The error two renders of one material show, source and target noise combined: each
        noise is the difference of two seeds (√2 σ), so the floor is sqrt((n_s² + n_t²) / 2)."""
        return float(np.sqrt((self.source_noise**2 + self.target_noise**2) / 2))
