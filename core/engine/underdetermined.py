"""Whether what was fitted determines the material where it was not judged.

A fit matches the source under the fit scene; parameters along the direction that scene pins least
(`assess.Weakest`), as far as the fit's error grows by the render noise, match it as well within it. Where the source was not judged under
a held-out condition (a source given as images without it), the target is rendered there at the fit's
parameters and at the two others, with one seed (the noise of one image is common to both): parting by
more than the threshold, the images given do not determine the material, and the result says so
(`Underdetermined`). Where every condition was judged, the checks decide and nothing is rendered."""

from __future__ import annotations

import numpy as np

from ..data.findings import Underdetermined, Unrendered
from ..data.metrics import relative_rmse
from ..data.schemas import Value
from .assess import Weakest
from .levels import Level, Renders
from .results import Validation

SLACK = 1.5
"""Another parameter set counts as within the noise while its fit-scene error is at most the fit's plus this
times the floor (the step is a first-order model's, aimed at the fit's plus one floor)."""
HALVINGS = 4
"""A step that overshoots the noise (the error is not linear that far) is halved at most this many times."""
MOVED = 1e-3
"""A parameter whose value moved less than this (relative) is left out of the finding's words."""


def _moved(fitted: dict[str, Value], other: dict[str, Value]) -> dict[str, Value]:
    def far(a: Value, b: Value) -> bool:
        if isinstance(a, str) or isinstance(b, str):
            return a != b
        a_, b_ = np.atleast_1d(np.asarray(a, float)), np.atleast_1d(np.asarray(b, float))
        return bool(np.any(np.abs(a_ - b_) > MOVED * np.maximum(1.0, np.abs(a_))))

    return {k: v for k, v in other.items() if far(fitted[k], v)}


def _within(fit: Level, params: dict[str, Value], error: float, weakest: Weakest, floor: float):
    """Each side's furthest parameters along `Weakest` found within the fit's noise (error up to the fit's plus
    `SLACK` floors): the first-order step, halved up to `HALVINGS` times where the error grew faster; with
    their error on the fit scene."""
    first = weakest.step(float(np.sqrt((error + floor) ** 2 - error ** 2)))
    for sign in (1.0, -1.0):
        for k in range(HALVINGS + 1):
            other = weakest.at(sign * first / 2 ** k)
            moved = _moved(params, other)
            if not moved:
                break
            err = relative_rmse(fit.source, np.asarray(fit.render(other, None)))
            if err <= error + SLACK * floor:
                yield other, moved, err
                break


def underdetermined(renders: Renders, fit: Level, params: dict[str, Value], error: float, weakest: Weakest | None,
                    validation: Validation, floor: float, threshold: float) -> Underdetermined | None:
    """The held-out condition not given (`Unrendered`: a source of images without it) where parameters within
    the fit's noise part most, if by more than ``threshold``; else None, and nothing rendered (a condition the
    source was judged under is decided by its check)."""
    unjudged = {name for name, why in validation.skipped.items() if isinstance(why, Unrendered)}
    if weakest is None or floor <= 0 or not unjudged:
        return None
    conditions = [c for c in renders.held_out() if c[0] in unjudged]
    found: Underdetermined | None = None
    for other, moved, err in _within(fit, params, error, weakest, floor):
        for name, label, scene in conditions:
            diff = relative_rmse(renders.target_at(params, scene), renders.target_at(other, scene))
            if diff > threshold and (found is None or diff > found.difference):
                found = Underdetermined(condition=name, label=label, difference=diff, other=moved,
                                        fitted={k: params[k] for k in moved}, error=err)
    return found
