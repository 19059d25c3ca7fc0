"""The engine's private knobs and its version. Users choose `Settings`; these stay with the engine
(benchmarks set them to measure what each one buys: see docs/measurements/engine.md)."""

from __future__ import annotations

from pydantic import Field

from ..data.model import Strict

ENGINE_VERSION = 15
"""Bump whenever a change in core/ would change a result: the engine, but also the informed start
(execute.py, appearance.py), the renders' cache and rounding (renders.py) or the metrics. A stored
result is reused (a resumed sweep, a library rerun) only when its job key, which includes this
number, matches. (An adapter's own `version` covers its renders.)"""


class Tuning(Strict):
    """How the engine fits, below the level of `Settings`. Defaults are the measured best."""

    fd_step: float = Field(0.01, gt=0, lt=0.5, description="Forward-difference step in normalised parameter units.")
    polish_resolution: int | None = Field(
        None, ge=8, description="Resolution where each stage is polished and the verdict taken, when the scene's is "
                                "at least twice it and there is a coarse level (None: the scene's own).")
    min_highlight_px: float = Field(2.0, ge=0, description="The coarse level is made finer (or left out) until the "
                                                            "brightest half of the source's highlight covers this "
                                                            "many of its pixels.")
    coarse_tol: float = Field(1e-2, gt=0, description="ftol and xtol of the coarse level.")
    start_margin: float = Field(0.05, ge=0, lt=0.5, description="A fresh fit's start that lies on a bound is moved "
                                                                 "this far inside it (normalised units).")
    linear_starts: bool = Field(True, description="Scale each start's reflectance that its image is proportional to "
                                                  "(ParamSpec.linear_in) to fit best, predicted without a render.")
    separable_rgb: bool = Field(True, description="One render for the three Jacobian columns of a separable RGB "
                                                  "parameter.")
    refresh_on_retry: bool = Field(True, description="A step that had to be retried gets a rendered Jacobian (False: "
                                                     "the rejected trials update it as secants).")
    fine_steps: int = Field(2, ge=0, description="Renders a polish may take beyond its start and one Jacobian (two "
                                                 "more while its latest improvement gained 1 %).")
    hold_settled: bool = Field(True, description="The polish leaves out what the coarse fit settled: a parameter "
                                                 "pinned on a bound its gradient pushes against, or inert there.")
    precise_below: float = Field(3.0, gt=0, description="A fit ending within this many times the source's render "
                                                        "noise gets the polish at `Settings.precise_spp` samples.")
    precise_max_spp: int = Field(256, ge=1, description="The polish at more samples is left out where it would "
                                                         "render more samples than this on a fit scene chosen for "
                                                         "the source (`core.job.fitscene`: it reached its noise goal "
                                                         "there) whose noise floor is within `precise_noisy`.")
    precise_noisy: float = Field(0.05, ge=0, description="A fit whose noise floor is above this gets the polish at "
                                                         "more samples at any cost (a rough glass under the studio: "
                                                         "16-20 % at 256 spp, its fit mostly noise there).")
    choice_budget: int = Field(30, ge=1, le=100_000, description="Renders of the brief fit each value of an open "
                                                                 "discrete choice gets (the best is kept).")
    max_renders_per_stage: int = Field(80, ge=1, le=100_000, description="Render budget of one fresh stage.")
    ftol: float = Field(1e-4, gt=0, description="Least-squares ftol (relative cost change that stops a fit).")
    xtol: float = Field(1e-4, gt=0, description="Least-squares xtol (relative step that stops a fit).")
    cond_limit: float = Field(1e4, gt=1, description="Jacobian condition number above which the result is flagged.")
    joint_rounds: int = Field(2, ge=0, description="Joint refinements of a merged two-stage result while a "
                                                   "Gauss-Newton step predicts a gain.")
    joint_min_gain: float = Field(0.002, ge=0, description="... a gain of at least 15 % of the error and this much "
                                                           "relative RMSE.")
    noise_stop_fraction: float = Field(1 / 3, ge=0, description="A fit stops once its error falls to this "
                                                                "fraction of the source's render noise.")
