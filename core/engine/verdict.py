"""The verdict: findings from the final parameters, the final renders and their assessment."""

from __future__ import annotations

from dataclasses import dataclass

from ..findings import (
    DeadParameters,
    ErrorAboveThreshold,
    IllConditioned,
    ModelMismatch,
    NoEffect,
    NotAtMinimum,
    PinnedOnBound,
    RendererAlters,
    Verdict,
)
from .assess import Assessment
from .results import StageResult


@dataclass(frozen=True)
class Evidence:
    """Everything the verdict is taken on, all of it at the final parameters."""

    error: float
    threshold: float
    assessment: Assessment
    stages: list[StageResult]
    cond_limit: float
    renderer_notes: list[str]
    trust_prediction: bool = True
    """False when joint rounds already failed to realise what a joint step predicts."""


def judge(ev: Evidence, notes: list) -> Verdict:
    """The findings in order of weight, then ``notes`` (what the schedule did) and the dead parameters."""
    a = ev.assessment
    problems: list = []
    if ev.error > ev.threshold:
        problems.append(ErrorAboveThreshold(error=ev.error, threshold=ev.threshold))
    if a.no_effect:
        problems.append(NoEffect())
    if a.condition is not None and a.condition > ev.cond_limit:
        problems.append(IllConditioned(condition=a.condition))
    if a.predicted is not None and ev.trust_prediction:
        problems.append(NotAtMinimum(predicted=a.predicted))
    problems += [PinnedOnBound(parameter=p.parameter, side=p.side, error_without=p.error_without) for p in a.pins]
    if (len(problems) == 1 and isinstance(problems[0], ErrorAboveThreshold)
            and all(s.converged for s in ev.stages)):
        problems = [ModelMismatch(error=ev.error, threshold=ev.threshold)]
    problems += [RendererAlters(detail=n) for n in ev.renderer_notes]
    extra = [DeadParameters(parameters=list(a.dead))] if a.dead and not a.no_effect else []
    return Verdict.of(problems + list(notes) + extra)
