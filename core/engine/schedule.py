"""The schedule of one remap, as declared steps: fit each planned stage (at the coarse level, then
polished at full resolution), render the result, refine jointly while a joint step predicts a
gain, try the held inputs the source needs where the fit leaves more than the noise, polish at
more samples when the fit ends at the render noise, and take the verdict once
at the final parameters. The optimiser only ever calls ``render(params, lobe) -> image``."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from ..data.account import purpose
from ..data.errors import OptimisationError
from ..data.scene import Lighting
from ..data.findings import ChoiceTried, InputsTried, JointRefined, NoisePolished, PredictionNotRealised, StartKept
from ..data.metrics import delta_e_itp, l2, relative_rmse
from ..data.schemas import ModelSpec, Value
from ..data.settings import Scheme, Settings
from ..data.settings import Validation as ValidationPolicy
from .underdetermined import underdetermined
from .assess import Assessment, assess
from .levels import Level, ProgressFn, Renders
from .plan import Plan, PlannedStage, plan_stages
from .residuals import Tally
from .results import EngineResult, StageResult, Validation
from .settled import Settled, settled
from .space import ParamSpace
from .stage import Stage, StageConfig
from .tuning import Tuning
from .verdict import Evidence, judge


@dataclass
class _Run:
    """One remap's fixed context: the levels, the thresholds the noise sets, and what it did."""

    target: ModelSpec
    free: list[str]
    renders: Renders
    settings: Settings
    tuning: Tuning
    progress: ProgressFn | None
    scene: Level
    coarse: Level | None
    fine: Level
    """Where stages are polished and the result assessed: the scene, or tuning.polish_resolution."""
    fine_suffix: str
    source_noise: float
    threshold: float
    good_enough: float
    tally: Tally = field(default_factory=Tally)
    stages: list[StageResult] = field(default_factory=list)
    notes: list = field(default_factory=list)

    def stage(self, config: StageConfig, space: ParamSpace, level: Level, image: str | None) -> Stage:
        return Stage(config, space, level.render, level.image(image), level.norm, self.tuning, self.tally,
                     self.progress)

    def fresh(self, name: str, lobe: str | None, **changes) -> StageConfig:
        s, t = self.settings, self.tuning
        base = dict(budget=t.max_renders_per_stage, starts=s.starts, ftol=t.ftol, xtol=t.xtol, method=s.method,
                    good_enough=self.good_enough, jacobian_updates=s.jacobian_updates, start_margin=t.start_margin,
                    rescale_starts=t.linear_starts)
        return StageConfig(name, lobe, **{**base, **changes})

    def polish(self, name: str, lobe: str | None, budget: int, origin: str = "the coarse optimum") -> StageConfig:
        return self.fresh(name, lobe, budget=budget, starts=1, start_margin=0.0, rescale_starts=False,
                          extend_while_gaining=True, budget_converges=True, origin=origin)

    def polish_budget(self, space: ParamSpace) -> int:
        """A polish's renders: its start, one Jacobian, and a few steps."""
        return 1 + space.jacobian_renders(self.tuning.separable_rgb) + self.tuning.fine_steps

    def assess(self, state: "_State", level: Level | None = None) -> Assessment:
        """The Jacobian checks at ``level`` (default: the fine level, where stages are polished)."""
        return assess(self.target, state.params, self.free, level or self.fine, self.tuning, self.tally,
                      jacobian_updates=self.settings.jacobian_updates, seed=state.last, held=state.held,
                      good_enough=self.good_enough)

    def noise_floor(self, target_noise: float) -> float:
        """The error two renders of a perfect match would show: the verdict's noise floor."""
        return float(np.hypot(self.source_noise, target_noise) / np.sqrt(2))

    def render_final(self, params: dict[str, Value], label: str = "final") -> tuple[np.ndarray, float]:
        image = np.asarray(self.scene.render(params, None), dtype=np.float32)
        self.tally.requests += 1
        err = relative_rmse(self.scene.source, image)
        if self.progress:
            self.progress(label, self.tally.requests, err)
        return image, err


@dataclass
class _State:
    params: dict[str, Value]
    image: np.ndarray
    err: float
    last: Stage | None = None
    """The last stage fitted at the fine level: the assessment may reuse its renders and Jacobian."""
    held: dict[str, Settled] = field(default_factory=dict)


def remap(target: ModelSpec, base: dict[str, Value], free: list[str], renders: Renders,
          settings: Settings = Settings(), tuning: Tuning = Tuning(),
          progress: ProgressFn | None = None, alternatives: list[dict[str, Value]] = (),
          notes: list = (), needed: dict[str, str] | None = None) -> EngineResult:
    """Fit ``free`` parameters of ``target`` (the others as in ``base``) so that the target's render
    matches the source's, both as ``renders`` gives them at its scene. ``alternatives``: values of
    discrete choices to try first (each fitted briefly, the best kept). ``notes``: findings the
    caller adds to the verdict (where the parameters came from). ``needed``: held parameters to try
    as well where the fit leaves more than the noise, each with what of the source's needs it."""
    t0 = time.perf_counter()
    with purpose("source"):
        run = _setup(target, free, renders, settings, tuning, progress)
    run.notes += list(notes)
    with purpose("tries"):
        base = _choose(run, dict(base), list(alternatives))
    plan = plan_stages(settings.scheme, target, free, run.scene.source_lobes)
    if free:  # with nothing to fit, no scheme runs
        run.notes += plan.findings
    with purpose("fit"):
        start = _State(dict(base), *run.render_final(dict(base), "start"))
        state = _never_worse(run, start, _fit_stages(run, plan, dict(base)))
    with purpose("checks"):
        assessment = run.assess(state)
    with purpose("joint"):
        state, assessment, joint = _refine_jointly(run, plan, state, assessment)
    with purpose("inputs"):
        state, assessment = _fit_needed(run, state, assessment, needed or {})
    with purpose("precise"):
        state, assessment = _polish_noise_limited(run, state, assessment, start.err)
    return _conclude(run, plan, state, assessment, joint, t0, start.err)


def _setup(target: ModelSpec, free: list[str], renders: Renders, settings: Settings, tuning: Tuning,
           progress: ProgressFn | None) -> _Run:
    unknown = [p for p in free if p not in target.names]
    if unknown:
        raise OptimisationError(f"`free` names unknown parameters {unknown} of model {target.name!r}")
    scene = renders.scene
    full = renders.level(scene)
    _check_source(full.source)
    noise = renders.source_noise()
    coarse = polish = None
    size = coarse_size(full, settings.coarse, tuning.min_highlight_px)
    if size and 2 * size <= scene.resolution:
        coarse = renders.level(scene.with_(resolution=size))
        p = tuning.polish_resolution
        if p and 2 * p <= scene.resolution:
            polish = renders.level(scene.with_(resolution=p))
    return _Run(target, list(free), renders, settings, tuning, progress, full, coarse, polish or full,
                "" if polish is None else f"@{polish.resolution}px", noise,
                threshold=settings.threshold,
                good_enough=max(0.0, noise * tuning.noise_stop_fraction))


def highlight_pixels(image: np.ndarray) -> float:
    """How many pixels the brightest half of an image's light covers: a few for a sharp highlight
    under a point light, thousands for a diffuse sphere."""
    lum = np.sort((np.asarray(image, np.float64) @ np.array([0.2126, 0.7152, 0.0722])).ravel())[::-1]
    total = lum.sum()
    if total <= 0:
        return float(lum.size)
    return float(np.searchsorted(np.cumsum(lum), 0.5 * total) + 1)


def coarse_size(full: Level, wanted: int, min_px: float) -> int:
    """The coarse level's width: the setting, raised until the source's highlight (its specular
    lobe where it has one) covers ``min_px`` pixels there; 0 for none."""
    if not wanted:
        return 0
    spec = full.source_lobes.get("specular")
    image = spec if spec is not None and float(np.max(spec)) > 0 else full.source
    px = highlight_pixels(image) * (wanted / full.resolution) ** 2
    if px >= min_px:
        return wanted
    return int(8 * math.ceil(wanted * math.sqrt(min_px / max(px, 1e-9)) / 8))


def _check_source(source: np.ndarray) -> None:
    if source.ndim != 3 or source.shape[2] != 3:
        raise OptimisationError(f"`source` must be an H x W x 3 image, got shape {source.shape}")
    if not np.isfinite(source).all():
        raise OptimisationError("`source` has NaN or Inf pixels")
    if l2(source) == 0.0:
        raise OptimisationError("`source` image is black: nothing to match (check the light and the material)")


def _fit_stages(run: _Run, plan: Plan, params: dict[str, Value]) -> _State:
    """Each planned stage at the coarse level, then polished at the fine level from its optimum
    over what the coarse fit did not settle (or fitted at the fine level alone without one)."""
    last: Stage | None = None
    held: dict[str, Settled] = {}
    for planned in plan.stages:
        if not planned.free:
            continue
        space = ParamSpace(run.target, params, planned.free)
        settle: dict[str, Settled] = {}
        config = run.fresh(planned.name + run.fine_suffix, planned.lobe)
        if run.coarse is not None:
            params, coarse = _coarse_fit(run, planned, space, params)
            if coarse.result.start_error - coarse.result.error <= 0.01 * coarse.result.start_error:
                continue  # nothing to do at this stage: no full-resolution pass either
            settle = settled(coarse) if run.tuning.hold_settled else {}
            polish_free = [p for p in planned.free if p not in settle]
            if not polish_free:
                last, held = None, {}
                continue
            space = ParamSpace(run.target, params, polish_free)
            config = run.polish(planned.name + run.fine_suffix, planned.lobe, run.polish_budget(space))
        stage = run.stage(config, space, run.fine, planned.source)
        params = space.decode(stage.run(space.encode(params)))
        run.stages.append(stage.result.model_copy(update={"held": {k: v.why for k, v in settle.items()}}))
        last, held = stage, settle
    image, err = run.render_final(params)
    return _State(params, image, err, last, held)


def _choose(run: _Run, base: dict[str, Value], alternatives: list[dict[str, Value]]) -> dict[str, Value]:
    """Each alternative's choices with every free parameter fitted briefly, at the coarse level (the
    scene's without one): the base with the best of them."""
    if len(alternatives) < 2 or not run.free:
        return base
    level, t = run.coarse or run.fine, run.tuning
    errors: dict[str, float] = {}
    for alt in alternatives:
        label = " ".join(f"{k}={v}" for k, v in alt.items())
        params = {**base, **alt}
        space = ParamSpace(run.target, params, run.free)
        config = run.fresh(f"try {label}@{level.resolution}px", None, ftol=t.coarse_tol, xtol=t.coarse_tol, starts=1,
                           budget=t.choice_budget)
        stage = run.stage(config, space, level, None)
        stage.run(space.encode(params))
        errors[label] = stage.result.error
        run.stages.append(stage.result.model_copy(update={"kept": False}))
    best = min(range(len(alternatives)), key=lambda i: list(errors.values())[i])
    run.notes.append(ChoiceTried(errors=errors, chosen=list(errors)[best], resolution=level.resolution))
    return {**base, **alternatives[best]}


def _never_worse(run: _Run, start: _State, fitted: _State) -> _State:
    """The fit's result, unless the start it began from is better at the scene's resolution and
    samples (a coarse level that cannot see a sharp highlight "converges" away from it)."""
    if not run.free or fitted.err <= start.err:
        return fitted
    run.notes.append(StartKept(start_error=start.err, fitted_error=fitted.err))
    return start


def _coarse_fit(run: _Run, planned: PlannedStage, space: ParamSpace,
                params: dict[str, Value]) -> tuple[dict[str, Value], Stage]:
    t = run.tuning
    config = run.fresh(f"{planned.name}@{run.coarse.resolution}px", planned.lobe, ftol=t.coarse_tol, xtol=t.coarse_tol)
    stage = run.stage(config, space, run.coarse, planned.source)
    params = space.decode(stage.run(space.encode(params)))
    run.stages.append(stage.result)
    return params, stage


@dataclass(frozen=True)
class _Joint:
    """What the joint rounds did: how many, the error before and after them, the first prediction."""

    rounds: int = 0
    before: float = 0.0
    after: float = 0.0
    predicted: float = 0.0

    def realised(self, predicted_now: float | None) -> bool:
        """Whether a joint step's prediction can be trusted here: rounds that realised under a
        quarter of the gain first predicted show that its linear model does not hold (render
        noise or curvature)."""
        return not (self.rounds and predicted_now is not None
                    and self.before - self.after < 0.25 * (self.before - self.predicted))


def _refine_jointly(run: _Run, plan: Plan, state: _State, assessment: Assessment) -> tuple[_State, Assessment, _Joint]:
    """The merged lobes are provably not a minimum of the full image (a coupling the split cannot
    see, e.g. a little Metallic standing in for Specular): refine jointly from here, again while
    a round ends with a joint step still predicting a gain."""
    if plan.scheme == Scheme.ONE or len(plan.stages) < 2:
        return state, assessment, _Joint()
    rounds, err0, predicted0 = 0, state.err, assessment.predicted
    while assessment.predicted is not None and rounds < run.tuning.joint_rounds:
        rounds += 1
        space = ParamSpace(run.target, state.params, run.free)
        name = "joint-refine" + run.fine_suffix + ("" if rounds == 1 else f" #{rounds}")
        joint = run.stage(run.polish(name, None, 2 * (space.dim + 1) + 1, origin="the merged result"), space,
                          run.fine, None)
        refined = space.decode(joint.run(space.encode(state.params)))
        if not joint.result.error < joint.result.start_error:
            run.stages.append(joint.result.model_copy(update={"kept": False}))
            break
        image, err = run.render_final(refined)
        run.stages.append(joint.result.model_copy(update={"kept": err < state.err}))
        if not err < state.err:
            break
        state = _State(refined, image, err, joint)
        assessment = run.assess(state)
    if rounds and state.err < err0:
        run.notes.append(JointRefined(before=err0, after=state.err, rounds=rounds))
    return state, assessment, _Joint(rounds, err0, state.err, predicted0 or 0.0)


INPUT_GAIN = 0.1
"""A held input tried for what the source needs is kept where it lowers the fit's error by this
fraction: less is within what another start or the noise would change."""
INPUT_MIN = 0.01
"""Nor tried where the fit ends within this error (noiseless renders have no noise to measure by)."""


def _fit_needed(run: _Run, state: _State, assessment: Assessment, needed: dict[str, str]
                ) -> tuple[_State, Assessment]:
    """The held inputs the source needs (`ParamSpec.fit_for`: Principled's Specular Tint for a
    complex IOR's edge), tried where the fit without them ended beyond `Tuning.precise_below` times
    the source's noise and `INPUT_MIN`: every free parameter and these, polished from the fit at the fine level with
    twice a polish's renders, kept where the scene-level error falls by `INPUT_GAIN`. Tried after the
    fit, not in it: a fit given every input the reading proposes spends renders on columns that
    change nothing where the models already agree (a material at its noise floor never gets here)."""
    tried = {k: v for k, v in needed.items() if k not in run.free}
    if not tried or not run.free or state.err <= max(run.tuning.precise_below * run.source_noise, INPUT_MIN):
        return state, assessment
    free = run.free + list(tried)
    space = ParamSpace(run.target, state.params, free)
    config = run.polish(f"inputs {', '.join(tried)}{run.fine_suffix}", None, 2 * run.polish_budget(space),
                        origin="the fit")
    stage = run.stage(config, space, run.fine, None)
    params = space.decode(stage.run(space.encode(state.params)))
    image, err = run.render_final(params) if stage.result.error < stage.result.start_error else (None, state.err)
    kept = image is not None and err <= (1.0 - INPUT_GAIN) * state.err
    run.stages.append(stage.result.model_copy(update={"kept": kept}))
    run.notes.append(InputsTried(inputs=tried, before=state.err, after=err, kept=kept))
    if not kept:
        return state, assessment
    run.free = free
    state = _State(params, image, err, stage)
    return state, run.assess(state)


PRECISE_SLACK = 0.05
"""How much a noise polish may raise the scene-level error (relative) and be kept."""


def _polish_noise_limited(run: _Run, state: _State, assessment: Assessment, ceiling: float
                          ) -> tuple[_State, Assessment]:
    """The fit ended within a few times the render noise: what is left is noise, which more
    samples shrink where more iterations cannot (the target's noise biases a fitted reflectance
    low). One short polish of every free parameter, source and target at `precise_spp` times the
    samples, kept if it lowers the error there and does not raise the error at the scene's samples
    (the error reported) by more than `PRECISE_SLACK` (at the noise those two differ by noise
    alone), nor above ``ceiling`` (the start's error: a result is never worse than its start).
    Not beyond `Tuning.precise_max_spp` samples on a fit scene chosen for the source whose floor is
    within `precise_noisy`: a fit scene of that many (a smooth plastic's studio at 256 spp, 2-3 %
    noise) reaches its noise goal already, and its polish at 1024 spp cost 139 s of a 243 s job for 1.44 % -> 1.35 % there
    (a shiny plastic's 4.89 % -> 4.88 %). A rough glass's fit at 256 spp (16-20 % noise) is mostly
    noise, and its polish there halves its error beyond the noise (21 % -> 10 %): it runs.
    (Leaving it out wherever one render at k times the samples showed the fit within the noise
    there saved 5 of the demo's 45 s, but the same-family Glossy fits fell from 20/20 to 13/20
    within 5 % of the best achievable: its gain is in the parameters, below the image's noise.)"""
    k, scene = run.settings.precise_spp, run.renders.scene
    if k <= 1 or not run.free or not state.err < run.tuning.precise_below * run.source_noise:
        return state, assessment
    if scene.spp * k > run.tuning.precise_max_spp and run.renders.scene_chosen():
        with purpose("noise"):  # the fit's noise floor, as the verdict measures it (its renders are kept)
            floor = run.noise_floor(run.renders.target_noise(state.params))
        if floor <= run.tuning.precise_noisy:
            return state, assessment
    level = run.renders.level(scene.with_(spp=scene.spp * k), lobes=False)
    space = ParamSpace(run.target, state.params, run.free)
    config = run.fresh(f"precise@{scene.spp * k}spp", None, budget=run.polish_budget(space), starts=1,
                       start_margin=0.0, good_enough=0.0, budget_converges=True, origin="the fit")
    stage = run.stage(config, space, level, None)
    params = space.decode(stage.run(space.encode(state.params)))
    image, err = run.render_final(params) if stage.result.error < stage.result.start_error else (None, state.err)
    kept = image is not None and err <= min(state.err * (1 + PRECISE_SLACK), ceiling)
    run.stages.append(stage.result.model_copy(update={"kept": kept}))
    if not kept:
        return state, assessment
    run.notes.append(NoisePolished(error=state.err, source_noise=run.source_noise, factor=run.tuning.precise_below,
                                   spp=scene.spp * k, before=stage.result.start_error, after=stage.result.error))
    state = _State(params, image, err, stage)
    # Checked where these parameters were chosen: at the scene's samples the render noise the
    # polish removed would make the shift it made look like a step away from a minimum.
    return state, run.assess(state, level)


def _conclude(run: _Run, plan: Plan, state: _State, assessment: Assessment, joint: _Joint, t0: float,
              start_error: float) -> EngineResult:
    trust = joint.realised(assessment.predicted)
    if not trust:
        run.notes.append(PredictionNotRealised(predicted_now=assessment.predicted, rounds=joint.rounds,
                                               before=joint.before, after=joint.after,
                                               predicted_first=joint.predicted))
    with purpose("noise"):
        target_noise = run.renders.target_noise(state.params)
    with purpose("validation"):
        validation = run.renders.validation(state.params) if run.settings.validation == ValidationPolicy.HELD_OUT else Validation()
    floor = run.noise_floor(target_noise)
    limit = run.settings.resolve_limit
    judged = {Lighting.SCENE: floor <= limit, **{c.condition: c.noise_floor <= limit for c in validation.checks}}
    with purpose("agreement"):
        agreement = run.renders.agreement(state.params, validation, run.threshold, lambda c: judged.get(c, False))
    with purpose("validation"):
        under = underdetermined(run.renders, run.scene, state.params, state.err, assessment.weakest, validation, floor,
                                run.threshold)
    if under is not None:
        run.notes.append(under)
    evidence = Evidence(error=state.err, noise_floor=floor, threshold=run.threshold,
                        resolve_limit=run.settings.resolve_limit, assessment=assessment, stages=run.stages,
                        cond_limit=run.tuning.cond_limit, renderer_notes=run.renders.notes(state.params),
                        approximated=run.renders.approximations(state.params),
                        fitted=bool(run.free), trust_prediction=trust, validation=validation, agreement=agreement,
                        images=(run.scene.source, state.image))
    return EngineResult(
        params=state.params, fitted=list(run.free), scheme=run.settings.scheme, scheme_used=plan.scheme,
        relative_rmse=state.err, perceptual=delta_e_itp(run.scene.source, state.image), threshold=run.threshold,
        source_noise=run.source_noise, target_noise=target_noise, renders=run.renders.target_renders(),
        seconds=time.perf_counter() - t0, verdict=judge(evidence, run.notes), target_image=state.image,
        stages=list(run.stages), jacobian_condition=assessment.condition, validation=validation,
        start_error=start_error)
