"""The remap engine: fit a target model's parameters so that its render matches a source image.

The optimiser only ever calls ``render(params, lobe) -> image``; it never evaluates a BRDF.
Schemes follow Sztrajman et al. (MAM 2017): one-stage (all parameters at once), two-stage
(specular and diffuse lobes fitted separately, then merged) and three-stage (two-stage, then a
joint refinement from its result). The default, auto, is two-stage where the target's lobes
divide its parameters and one-stage where they share them.

Rooms: `space` (parameters as a unit vector), `residuals` and `jacobian` (one least-squares
problem), `stage` (one fit), `plan` (which stages a scheme runs), `schedule` (the steps of a
remap), `assess` and `verdict` (what the result is worth), `tuning` (the engine's knobs and
version), `levels` (what the engine asks of the renderers)."""

from .levels import Level, ProgressFn, RenderFn, Renders
from .plan import Plan, PlannedStage, plan_stages
from .results import EngineResult, StageResult
from .schedule import remap
from .space import ParamSpace
from .tuning import ENGINE_VERSION, Tuning

__all__ = ["ENGINE_VERSION", "EngineResult", "Level", "ParamSpace", "Plan", "PlannedStage", "ProgressFn", "RenderFn",
           "Renders", "StageResult", "Tuning", "plan_stages", "remap"]
