"""The verdict: findings from the final parameters, the final renders, their assessment and the
held-out validation. Errors are judged by the part the render noise does not explain, against a
fixed threshold; a noise floor over the resolve limit is its own finding (nothing is judged there)."""

from __future__ import annotations

from dataclasses import dataclass, field

from ..data.scene import Lighting
from ..data.findings import (
    CannotResolve,
    NotGiven,
    Unrendered,
    DeadParameters,
    ErrorAboveThreshold,
    HeldOutAbove,
    HeldOutError,
    IllConditioned,
    ImagePrecision,
    ModelMismatch,
    NoEffect,
    TableMismatch,
    NotAtMinimum,
    NothingFitted,
    PinnedOnBound,
    TableLookup,
    Approximated,
    RendererAlters,
    RenderersDisagree,
    RenderersFloor,
    AdapterOff,
    TransportUnchecked,
    ValidationSkipped,
    Verdict,
)
from ..data.metrics import beyond_noise, clipped_at, eight_bit
from .assess import Assessment
from .results import WHITE, Agreement, StageResult, Validation

GAIN_BEYOND_NOISE = 0.5
"""A joint step's predicted gain beyond the noise, as a fraction of the threshold, that says a result
is not at a minimum (less could not change how the result is judged)."""
LOOKUP_SLACK = 1.2
"""A table's lookup within this factor of what the table's direct fits reach there is the model's mismatch."""
SCENE_ADVICE = ("render more samples (--spp), or fit under an environment (a scene whose lights include "
                "{type: environment}), which resolves sharp highlights a point light leaves sub-pixel")
HELD_OUT_ADVICE = "raise the scene's samples (the validation renders take 4x them, at least 64)"


@dataclass(frozen=True)
class Evidence:
    """Everything the verdict is taken on, all of it at the final parameters."""

    error: float
    noise_floor: float
    threshold: float
    resolve_limit: float
    assessment: Assessment
    stages: list[StageResult]
    cond_limit: float
    renderer_notes: list[str]
    approximated: list[tuple[str, str]] = field(default_factory=list)
    """(side, what) a side's renderer draws only approximately (`Renders.approximations`)."""
    fitted: bool = True
    """False when every parameter was held: a comparison, with no fit to judge."""
    trust_prediction: bool = True
    """False when joint rounds already failed to realise what a joint step predicts."""
    validation: Validation = field(default_factory=Validation)
    agreement: Agreement = field(default_factory=Agreement)
    """Whether the two renderers agree on this kind of material, condition by condition."""
    images: tuple = ()
    """(source, target) at the final parameters: checked for clipping and 8-bit levels."""

    @property
    def beyond_noise(self) -> float:
        return beyond_noise(self.error, self.noise_floor)


def _errors(ev: Evidence) -> list:
    """The fit scene's error and each held-out condition's, judged beyond the noise. Where the noise
    floor is over the limit nothing is judged: a finding that says so, a note while another
    condition resolves the material (the verdict rests on those), else unreliable. Where the
    renderers draw this kind of material otherwise, a condition's error is theirs: said so instead. A
    held-out error is judged beyond the renderers' own difference on a white Lambertian there too
    (`Agreement.floors`), as beyond the noise: within it, a note says the difference is theirs."""
    checked = (["the fit scene"] if ev.noise_floor <= ev.resolve_limit else []) + \
        [f"the {c.label}" for c in ev.validation.checks if c.noise_floor <= ev.resolve_limit]
    resolved = len(checked)
    theirs = {d.condition: d for d in ev.agreement.disagree}
    out: list = []
    if ev.noise_floor > ev.resolve_limit:
        out.append(CannotResolve(condition=Lighting.SCENE, label="the scene", noise_floor=ev.noise_floor,
                                 limit=ev.resolve_limit, advice=SCENE_ADVICE, elsewhere=resolved > 0, checked=checked))
    elif ev.beyond_noise > ev.threshold and Lighting.SCENE not in theirs:
        out.append(ErrorAboveThreshold(error=ev.error, threshold=ev.threshold, beyond_noise=ev.beyond_noise))
    if Lighting.SCENE in theirs:
        out.append(_disagree(theirs[Lighting.SCENE], ev.error if ev.beyond_noise > ev.threshold else None))
    above = []
    for c in ev.validation.checks:
        if c.noise_floor > ev.resolve_limit:
            out.append(CannotResolve(condition=c.condition, label=f"the {c.label}", noise_floor=c.noise_floor,
                                     limit=ev.resolve_limit, advice=HELD_OUT_ADVICE, elsewhere=resolved > 0,
                                     checked=checked, spp=c.spp))
        elif c.condition in theirs:
            out.append(_disagree(theirs[c.condition], c.error if c.beyond_noise > ev.threshold else None))
        elif c.beyond_noise > ev.threshold:
            floor = ev.agreement.floors.get(c.condition)
            if floor is not None and floor.own:  # an adapter's own fault there: said, and no floor
                out.append(AdapterOff(condition=c.condition, label=c.label, adapter=floor.own, error=floor.own_error,
                                      renderers=floor.beyond_noise))
                floor = None
            pair = floor.beyond_noise if floor is not None else 0.0
            far = beyond_noise(c.beyond_noise, pair)
            if far > ev.threshold or floor is None:
                above.append(HeldOutError(condition=c.condition, label=c.label, error=c.error, beyond_noise=far,
                                          renderers=pair, reference=floor.kind if floor is not None else WHITE))
            else:
                out.append(RenderersFloor(condition=c.condition, label=c.label, error=floor.error,
                                          beyond_noise=pair, result_error=c.error, reference=floor.kind))
    if above:
        out.append(HeldOutAbove(conditions=above, threshold=ev.threshold))
    return out


def _disagree(d, result_error: float | None) -> RenderersDisagree:
    return RenderersDisagree(condition=d.condition, label=d.label, reference=d.kind, error=d.error,
                             beyond_noise=d.beyond_noise, result_error=result_error)


def _fit_problems(ev: Evidence) -> list:
    a = ev.assessment
    out: list = []
    if a.no_effect:
        out.append(NoEffect())
    if a.condition is not None and a.condition > ev.cond_limit:
        out.append(IllConditioned(condition=a.condition))
    # Judged beyond the noise, as errors are: a step "predicting" less than the render noise is fitting
    # the noise (a mirror at a 2.0 % floor, 2.2 % "could be 0.6 %": 0.9 % beyond it, nothing to gain).
    if a.predicted is not None and ev.trust_prediction and ev.beyond_noise - beyond_noise(
            max(a.predicted, ev.noise_floor), ev.noise_floor) > GAIN_BEYOND_NOISE * ev.threshold:
        out.append(NotAtMinimum(predicted=a.predicted))
    out += [PinnedOnBound(parameter=p.parameter, side=p.side, error_without=p.error_without) for p in a.pins]
    return out


def _image_problems(ev: Evidence) -> list:
    """Images that cannot carry a fit (a ceiling at 1, 256 levels): then no error is the model's."""
    out = []
    for side, img in zip(("source", "target"), ev.images):
        clip, levels = clipped_at(img), eight_bit(img)
        words = ([f"clips at {clip[0]:.4g} ({clip[1]} pixels at exactly that value)"] if clip else []) + (
            [f"has 256 {levels} levels (an 8-bit image)"] if levels else [])
        if words:
            out.append(ImagePrecision(side=side, problem=" and ".join(words)))
    return out


def judge(ev: Evidence, notes: list) -> Verdict:
    """The findings in order of weight, then ``notes`` (what the schedule did) and the dead parameters.
    With nothing fitted there is no fit to question: only the errors, and a mismatch only where a
    table's lookup is about as close as the table's direct fits get there."""
    errors = _errors(ev)
    fit = (_fit_problems(ev) if ev.fitted else []) + _image_problems(ev)
    scene = [p for p in errors if isinstance(p, ErrorAboveThreshold)]
    if ev.fitted and scene and not fit and all(s.converged for s in ev.stages) and not ev.agreement.unchecked:
        errors = [ModelMismatch(error=ev.error, threshold=ev.threshold, beyond_noise=ev.beyond_noise)
                  if p is scene[0] else p for p in errors]
    lookup = next((n for n in notes if isinstance(n, TableLookup)), None)
    if not ev.fitted and scene and lookup is not None and lookup.expected_error is not None and \
            ev.error <= max(LOOKUP_SLACK * lookup.expected_error, lookup.expected_error + ev.noise_floor):
        errors = [TableMismatch(error=ev.error, expected=lookup.expected_error, threshold=ev.threshold)
                  if p is scene[0] else p for p in errors]
    problems = errors + fit + [RendererAlters(detail=n) for n in ev.renderer_notes]
    extra: list = [NotGiven(condition=k, why=v) if isinstance(v, Unrendered) else ValidationSkipped(condition=k, why=v)
                   for k, v in ev.validation.skipped.items()]
    extra += [Approximated(side=side, detail=what) for side, what in ev.approximated]
    if ev.agreement.unchecked:
        extra.append(TransportUnchecked(why=ev.agreement.unchecked))
    if not ev.fitted and not any(isinstance(n, TableLookup) for n in notes):
        extra.append(NothingFitted())
    elif ev.assessment.dead and not ev.assessment.no_effect:
        extra.append(DeadParameters(parameters=list(ev.assessment.dead)))
    return Verdict.of(problems + list(notes) + extra)
