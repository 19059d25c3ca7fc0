"""What the verdict found about a result: typed findings, each with its own sentence.

A finding of severity ``unreliable`` makes the result not trustworthy as it stands; a ``note``
explains something about the fit without questioning it. The verdict is derived from the
findings alone (`Verdict.of`), never from their text."""

from __future__ import annotations

from enum import StrEnum
from typing import Annotated, ClassVar, Literal, Union

from pydantic import Field, computed_field

from .model import Strict, WithDerived
from .scene import Lighting
from .schemas import Value, format_value
from .settings import Scheme

class Severity(StrEnum):
    UNRELIABLE = "unreliable"
    UNCHECKED = "unchecked"
    NOTE = "note"


"""unreliable: the result is not to be trusted; unchecked: a condition it is judged under could not be
resolved, so it was not checked there (with nothing unreliable, the verdict is "unchecked", never ok);
note: what was done or seen, which changes no verdict."""


class _Finding(WithDerived):
    derived_fields = ("severity", "message")

    @computed_field  # type: ignore[prop-decorator]
    @property
    def severity(self) -> Severity:
        return Severity.UNRELIABLE

    @computed_field  # type: ignore[prop-decorator]
    @property
    def message(self) -> str:
        return self.sentence()

    def sentence(self) -> str:  # pragma: no cover - every finding defines its own
        raise NotImplementedError


class _Note(_Finding):
    @computed_field  # type: ignore[prop-decorator]
    @property
    def severity(self) -> Severity:
        return Severity.NOTE


def _beyond(error: float, beyond: float | None) -> str:
    return "" if beyond is None or beyond >= 0.995 * error else f", {beyond:.1%} beyond the render noise,"


class ErrorAboveThreshold(_Finding):
    kind: Literal["error_above_threshold"] = "error_above_threshold"
    error: float
    threshold: float
    beyond_noise: float | None = Field(None, description="The part of the error the render noise does not explain "
                                                         "(what the threshold judges).")

    def sentence(self) -> str:
        return f"error {self.error:.1%}{_beyond(self.error, self.beyond_noise)} above the {self.threshold:.0%} threshold"


class HeldOutError(Strict):
    condition: Lighting
    label: str
    error: float
    beyond_noise: float = Field(description="The error beyond the render noise and, where they differ, the "
                                            "renderers' own difference on a white Lambertian (a metal: on their "
                                            "metals) there.")
    renderers: float = Field(0.0, description="That difference of the renderers' (beyond their noise); 0: none.")
    reference: str = Field("white Lambertian", description="What that difference was measured on.")

    def words(self) -> str:
        if self.renderers > 0:
            return f"{self.label} {self.error:.1%} ({self.beyond_noise:.1%} beyond the noise and the renderers' " \
                   f"{self.renderers:.1%} on a {self.reference})"
        return f"{self.label} {self.error:.1%}" + (
            "" if self.beyond_noise >= 0.995 * self.error else f" ({self.beyond_noise:.1%} beyond the noise)")


class _Above(_Finding):
    """Lighting conditions under which the result is off its source beyond the threshold: one finding,
    said of the held-out lights (`HeldOutAbove`) and of a textured result (`TexturedAbove`)."""

    opening: ClassVar[str]

    def sentence(self) -> str:  # each declares conditions (with their words) and threshold, in its own order
        return (f"{self.opening}: {', '.join(c.words() for c in self.conditions)}, "  # type: ignore[attr-defined]
                f"over the {self.threshold:.0%} threshold")  # type: ignore[attr-defined]


class HeldOutAbove(_Above):
    """Matches under the scene's lights but not under held-out ones: it does not look the same there."""

    opening: ClassVar[str] = "does not look the same under held-out lights"
    kind: Literal["held_out_above"] = "held_out_above"
    conditions: list[HeldOutError]
    threshold: float


class RenderersFloor(_Note):
    """Under one held-out condition the two renderers differ even on a white Lambertian, and the
    result's error there is within that difference: the renderers', not the material's."""

    kind: Literal["renderers_floor"] = "renderers_floor"
    condition: Lighting
    label: str
    error: float = Field(description="The two renderers' reference materials' relative RMSE there.")
    beyond_noise: float
    result_error: float = Field(description="The result's own error there.")
    reference: str = Field("white Lambertian", description="The reference: 'white Lambertian', or for a metal "
                                                           "'smooth metal' or 'rough metal' (the adapters' "
                                                           "aluminium, `Adapter.metals`).")

    def sentence(self) -> str:
        return (f"the renderers disagree by {self.error:.1%} under the {self.label} even on a {self.reference} "
                f"({self.beyond_noise:.1%} beyond the noise): the result's {self.result_error:.1%} there is within "
                "their difference, not the material's")


class AdapterOff(_Finding):
    """Under one held-out condition an adapter draws even a white Lambertian away from its box-filtered
    analytic image (aliasing at the silhouette, a light drawn otherwise): the difference between the two
    renderers there is that adapter's fault, which `remap check` names, so it is not subtracted from the
    material's error as the renderers' floor."""

    kind: Literal["adapter_off"] = "adapter_off"
    condition: Lighting
    label: str
    adapter: str
    error: float = Field(description="The adapter's white Lambertian's relative RMSE from the box-filtered "
                                     "analytic image there, beyond its noise.")
    renderers: float = Field(description="The two renderers' white Lambertians' difference there, beyond the noise.")

    def sentence(self) -> str:
        return (f"under the {self.label} adapter {self.adapter!r} draws a white Lambertian {self.error:.1%} from its "
                f"box-filtered analytic image (`remap check {self.adapter}`: sampling): the renderers' "
                f"{self.renderers:.1%} difference there is that adapter's fault, not subtracted from the material's "
                "error; fix the adapter")


class RenderersDisagree(_Finding):
    """The two renderers draw this kind of material otherwise under one condition: its error there is
    theirs, not the model's (`core.job.agreement`)."""

    kind: Literal["renderers_disagree"] = "renderers_disagree"
    condition: Lighting
    label: str
    reference: str = Field(description="What was compared: each adapter's clear glass of IOR 1.5, smooth or rough.")
    error: float = Field(description="The two references' relative RMSE (8 x 8 pixel blocks).")
    beyond_noise: float
    result_error: float | None = Field(None, description="The result's own error there, when over the threshold; "
                                                         "None: the result matched there all the same (a note).")

    @computed_field  # type: ignore[prop-decorator]
    @property
    def severity(self) -> Severity:
        return Severity.NOTE if self.result_error is None else Severity.UNRELIABLE

    def sentence(self) -> str:
        what = f"the renderers disagree on light through a sphere under the {self.label}: their {self.reference}es " \
               f"differ by {self.error:.1%} ({self.beyond_noise:.1%} beyond the noise)"
        if self.result_error is None:
            return what + "; the result matches there all the same"
        return what + f", so the result's {self.result_error:.1%} there is the renderers' difference, not the model's"


class TransportUnchecked(_Note):
    """Light through the sphere could not be compared between the two renderers: no error of this
    material is called the model's."""

    kind: Literal["transport_unchecked"] = "transport_unchecked"
    why: str

    def sentence(self) -> str:
        return f"{self.why}: an error here is not called a model mismatch"


class CannotResolve(_Finding):
    """The renders are too noisy to tell a match from a mismatch: no error here means anything."""

    kind: Literal["cannot_resolve"] = "cannot_resolve"
    condition: Lighting = Field(description="'scene' (the fit's own scene) or a held-out condition.")
    label: str = Field(description="The condition in words.")
    noise_floor: float
    limit: float
    advice: str
    elsewhere: bool = Field(False, description="Other conditions did resolve the material and judge the result: "
                                               "then this one is unchecked (not unreliable).")
    checked: list[str] = Field(default_factory=list, description="The conditions that did judge the result.")
    spp: int = Field(0, description="The samples it was last rendered at (0: not said).")

    @computed_field  # type: ignore[prop-decorator]
    @property
    def severity(self) -> Severity:
        return Severity.UNCHECKED if self.elsewhere else Severity.UNRELIABLE

    def sentence(self) -> str:
        where = self.label
        if self.elsewhere:
            at = f" at {self.spp} spp" if self.spp else ""
            return (f"not checked under {where}: two renders of one material differ by "
                    f"{self.noise_floor:.0%} there{at}, over the {self.limit:.0%} limit")
        return (f"{where} cannot resolve this material: two renders of one material differ by {self.noise_floor:.0%} "
                f"(over the {self.limit:.0%} limit), so its error says nothing; {self.advice}")


class ModelMismatch(_Finding):
    """Only the error is above the threshold, and the fit converged with nothing pinned or
    ill-conditioned: the closest this target model gets."""

    kind: Literal["model_mismatch"] = "model_mismatch"
    error: float
    threshold: float
    beyond_noise: float | None = None

    def sentence(self) -> str:
        return (f"error {self.error:.1%}{_beyond(self.error, self.beyond_noise)} above the {self.threshold:.0%} "
                "threshold although the fit converged with no "
                "parameter pinned and a well-conditioned Jacobian: a model mismatch (the closest this target model "
                "gets), not a failed fit")


class TableMismatch(_Finding):
    """A table's lookup above the threshold, but about as close as the table's direct fits get there:
    the target model's mismatch, not the table's."""

    kind: Literal["table_mismatch"] = "table_mismatch"
    error: float
    expected: float = Field(description="The relative RMSE the table's direct fits reach about these source values.")
    threshold: float

    def sentence(self) -> str:
        return (f"error {self.error:.1%} above the {self.threshold:.0%} threshold, about what the table's direct fits "
                f"reach here ({self.expected:.1%}): a model mismatch (the closest this target model gets), not "
                "the table's")


class NoEffect(_Finding):
    kind: Literal["no_effect"] = "no_effect"

    def sentence(self) -> str:
        return "no fitted parameter changes the image (ill-conditioned Jacobian)"


class IllConditioned(_Finding):
    kind: Literal["ill_conditioned"] = "ill_conditioned"
    condition: float

    def sentence(self) -> str:
        return f"ill-conditioned Jacobian (condition {self.condition:.2g}): parameters trade off against each other"


class NotAtMinimum(_Finding):
    kind: Literal["not_at_minimum"] = "not_at_minimum"
    predicted: float = Field(description="Relative RMSE a bounded Gauss-Newton step from the result predicts.")

    def sentence(self) -> str:
        return f"not at a minimum of the full image: a joint step predicts {self.predicted:.1%} (try --scheme three)"


class PinnedOnBound(_Finding):
    kind: Literal["pinned_on_bound"] = "pinned_on_bound"
    parameter: str
    side: Literal["lower", "upper"]
    error_without: float = Field(description="Relative RMSE predicted if the bound were not there.")

    def sentence(self) -> str:
        return (f"{self.parameter} pinned at its {self.side} bound (without it the error would drop to about "
                f"{self.error_without:.1%})")


class RendererAlters(_Finding):
    """The target renderer changes the fitted values before rendering (a trimmed reflectance):
    the numbers do not mean what they say."""

    kind: Literal["renderer_alters"] = "renderer_alters"
    detail: str

    def sentence(self) -> str:
        return f"the renderer alters the fitted parameters: {self.detail}"


class ImagePrecision(_Finding):
    """A renderer's image cannot carry the fit: clipped highlights or 8-bit levels. The error is
    then the file format's, not the model's."""

    kind: Literal["image_precision"] = "image_precision"
    side: Literal["source", "target"]
    problem: str = Field(description="What the image shows, in words (a plateau at 1, 256 levels).")

    def sentence(self) -> str:
        return (f"the {self.side} renderer's image {self.problem}: the error is the image format's, not the "
                "model's; have the renderer write float EXR, PFM or HDR")


class Approximated(_Finding):
    """One side's renderer draws the material only approximately (a real-time renderer's subsurface or
    transmission): the images compared are that approximation, so the result is not checked against what
    the parameters mean (its verdict is unchecked where nothing else is wrong)."""

    kind: Literal["approximated"] = "approximated"
    side: Literal["source", "target"]
    detail: str

    @computed_field  # type: ignore[prop-decorator]
    @property
    def severity(self) -> Severity:
        return Severity.UNCHECKED

    def sentence(self) -> str:
        return f"the {self.side} is matched as its renderer draws it, which is an approximation: {self.detail}"


class SameMaterial(_Note):
    """The target is the source's own model in the same renderer: the source's parameters are the
    result, with nothing to fit or to judge."""

    kind: Literal["same_material"] = "same_material"

    def sentence(self) -> str:
        return "the target is the source's own model in the same renderer: its parameters are the source's, " \
               "nothing was fitted or rendered to judge them"


class UniformTarget(_Note):
    """The source is rendered as its file holds it, with inputs driven by images or node graphs, and the
    target is one uniform material: fitted to, and judged against, the source's own rendering, its error
    holding the variation a uniform material cannot follow. Said in the verdict's reason whatever it is."""

    kind: Literal["uniform_target"] = "uniform_target"
    driven: list[str] = Field(description="The source's inputs driven by an image or a graph, in words.")

    def sentence(self) -> str:
        return (f"the target is uniform where the source is not ({'; '.join(self.driven)}): fitted to the source "
                "as rendered, its error includes what a uniform material cannot follow")


class ValidationSkipped(_Note):
    kind: Literal["validation_skipped"] = "validation_skipped"
    condition: Lighting
    why: str

    def sentence(self) -> str:
        return f"held-out condition {self.condition} not checked: {self.why}"


class Unrendered(str):
    """Why a held-out condition has no source image: it was not given (a source of images without that
    shot, `core.images.folder`). A condition skipped for it is unchecked (`NotGiven`), not a note."""


class _Unchecked(_Finding):
    @computed_field  # type: ignore[prop-decorator]
    @property
    def severity(self) -> Severity:
        return Severity.UNCHECKED


class NotGiven(_Unchecked):
    kind: Literal["not_given"] = "not_given"
    condition: Lighting
    why: str

    def sentence(self) -> str:
        return f"held-out condition {self.condition} unchecked: the source {self.why}"


class Uncalibrated(_Unchecked):
    kind: Literal["uncalibrated"] = "uncalibrated"
    folder: str

    def sentence(self) -> str:
        return (f"the source's renderer is uncalibrated: no images of the export's white Lambertian beside {self.folder} "
                "(renders/calibration), so its units, orientation and encoding are unchecked and the renderers' "
                "own difference is not measured")


class NoiseUnmeasured(_Note):
    kind: Literal["noise_unmeasured"] = "noise_unmeasured"
    shots: list[str]

    def sentence(self) -> str:
        return (f"the source's render noise is estimated from the image where one seed was given "
                f"({', '.join(self.shots)}), not measured: the noise floors there are a rough estimate's (a quarter to "
                "seven times two seeds' difference on the exported scenes), so a verdict near its threshold may go "
                "either way")


class Underdetermined(_Finding):
    """Parameters within the noise of the fit's that look otherwise under a held-out condition the source was not
    given under (`core.engine.underdetermined`): what was fitted does not determine the material there."""

    kind: Literal["underdetermined"] = "underdetermined"
    condition: Lighting
    label: str
    difference: float = Field(description="Relative RMSE between the target at the fit's parameters and at the "
                                          "other's, under that condition.")
    other: dict[str, Value] = Field(description="The other parameters' values that differ from the fit's.")
    fitted: dict[str, Value] = Field(description="The fit's values of those parameters.")
    error: float = Field(description="The other parameters' error on the fit scene.")

    def sentence(self) -> str:
        moved = ", ".join(f"{k} {format_value(self.fitted[k])} -> {format_value(v)}" for k, v in self.other.items())
        return (f"underdetermined: other parameters within the fit's noise ({moved}; {self.error:.2%} on the fit "
                f"scene) look {self.difference:.1%} different under the {self.label}, which the source was not "
                "given under: what was fitted does not determine the material there (give that condition's images, "
                "or judge the result under it yourself)")


class NothingFitted(_Note):
    kind: Literal["nothing_fitted"] = "nothing_fitted"

    def sentence(self) -> str:
        return "every parameter was held: the two materials are compared as given, nothing was fitted"


class TableLookup(_Note):
    """The parameters came from a remap table: nothing was fitted, the errors judge the lookup."""

    kind: Literal["table_lookup"] = "table_lookup"
    table: str
    method: str
    expected_error: float | None = Field(None, description="The relative RMSE the table's direct fits reach about "
                                                           "these source values.")
    outside: list[str] = Field(default_factory=list, description="Source values the map clamped to its range.")

    def sentence(self) -> str:
        text = f"parameters from the remap table {self.table!r} ({self.method} map), not fitted"
        if self.expected_error is not None:
            text += f"; direct fits about these source values reach about {self.expected_error:.1%}"
        if self.outside:
            text += "; outside the table, clamped: " + ", ".join(self.outside)
        return text


class TexturedCondition(Strict):
    condition: Lighting
    error: float
    beyond_noise: float

    def words(self) -> str:
        where = {Lighting.SCENE: "the scene's lights", Lighting.ENVIRONMENT: "the studio environment"}.get(self.condition,
                                                                                              self.condition)
        return f"{self.error:.1%} under {where}" + ("" if self.beyond_noise >= 0.995 * self.error else
                                                    f" ({self.beyond_noise:.1%} beyond the noise)")


class TexturedAbove(_Above):
    """The textured result, rendered over its maps, does not look like the textured source."""

    opening: ClassVar[str] = "the textured result is off the textured source"
    kind: Literal["textured_above"] = "textured_above"
    conditions: list[TexturedCondition]
    threshold: float


class TexturedNotes(_Note):
    """What the texel-by-texel remap could not carry as it is."""

    kind: Literal["textured_notes"] = "textured_notes"
    held: list[str] = Field(default_factory=list, description="Parameters written as their mean, and why.")
    outside: list[str] = Field(default_factory=list, description="Texel values clamped to the table's range.")

    def sentence(self) -> str:
        parts = self.held + ([f"texels outside the table, clamped: {'; '.join(self.outside)}"] if self.outside else [])
        return "; ".join(parts)


class StartKept(_Note):
    """Every fitted point was worse at the scene's resolution and samples than the informed start."""

    kind: Literal["start_kept"] = "start_kept"
    start_error: float
    fitted_error: float

    def sentence(self) -> str:
        return (f"the fit ended at {self.fitted_error:.2%} at the scene's resolution and samples, worse than the "
                f"informed start's {self.start_error:.2%}: the start is kept")


class ChoiceTried(_Note):
    """The reading did not say which value a discrete choice takes: each was fitted briefly, the best kept."""

    kind: Literal["choice_tried"] = "choice_tried"
    errors: dict[str, float] = Field(description="Relative RMSE each choice reached at the level it was tried, "
                                                 "by choice (e.g. 'distribution=ggx').")
    chosen: str
    resolution: int

    def sentence(self) -> str:
        tried = ", ".join(f"{k} {v:.2%}" for k, v in self.errors.items())
        return f"the source does not say which to use: tried {tried} at {self.resolution} px; kept {self.chosen}"


class SmoothHeld(_Note):
    """A perfectly smooth source: the target held perfectly smooth where its model can be."""

    kind: Literal["smooth_held"] = "smooth_held"
    held: dict[str, float]

    def sentence(self) -> str:
        values = ", ".join(f"{k} {v:g}" for k, v in self.held.items())
        return (f"the source is perfectly smooth: the target's {values} held (an environment hardly tells a mirror "
                "from a nearly smooth one; a point light does)")


class SchemeChosen(_Note):
    kind: Literal["scheme_chosen"] = "scheme_chosen"
    scheme: Scheme
    why: str
    fallback: bool = Field(False, description="The scheme asked for could not run; this one ran instead.")

    def sentence(self) -> str:
        if self.fallback:
            return f"{self.why}; fell back to {self.scheme}-stage"
        return f"scheme auto: {self.scheme}-stage ({self.why})"


class DeadParameters(_Note):
    kind: Literal["dead_parameters"] = "dead_parameters"
    parameters: list[str]

    def sentence(self) -> str:
        return f"{', '.join(self.parameters)} did not change the image at the solution: left where the fit put it"


class JointRefined(_Note):
    kind: Literal["joint_refined"] = "joint_refined"
    before: float
    after: float
    rounds: int

    def sentence(self) -> str:
        return (f"two-stage result was not a minimum of the full image; joint refinement took it from "
                f"{self.before:.2%} to {self.after:.2%}" + (f" in {self.rounds} rounds" if self.rounds > 1 else ""))


class PredictionNotRealised(_Note):
    kind: Literal["prediction_not_realised"] = "prediction_not_realised"
    predicted_now: float
    rounds: int
    before: float
    after: float
    predicted_first: float

    def sentence(self) -> str:
        s = "s" if self.rounds > 1 else ""
        return (f"a joint step still predicts {self.predicted_now:.1%}, but {self.rounds} joint round{s} took the "
                f"error only from {self.before:.2%} to {self.after:.2%} (predicted {self.predicted_first:.2%}): the "
                "prediction does not hold here (render noise or curvature)")


class NoisePolished(_Note):
    kind: Literal["noise_polished"] = "noise_polished"
    error: float = Field(description="Relative RMSE before this polish, at the scene's samples.")
    source_noise: float
    factor: float
    spp: int
    before: float = Field(description="Relative RMSE at `spp` before the polish.")
    after: float = Field(description="Relative RMSE at `spp` after it.")

    def sentence(self) -> str:
        return (f"noise-limited (error {self.error:.2%}, within {self.factor:g}x the source's render noise "
                f"{self.source_noise:.2%}): polished at {self.spp} spp, {self.before:.3%} -> {self.after:.3%} there")


class InputsTried(_Note):
    """Held inputs of the target fitted for what the source's reading needs (`ParamSpec.fit_for`)."""

    kind: Literal["inputs_tried"] = "inputs_tried"
    inputs: dict[str, str] = Field(description="Each input tried, and what of the source's it was tried for.")
    before: float = Field(description="Relative RMSE on the fit scene without them.")
    after: float = Field(description="Relative RMSE with them.")
    kept: bool

    def sentence(self) -> str:
        why = "; ".join(f"{k} for {v}" for k, v in self.inputs.items())
        if self.kept:
            return f"fitted {why}: {self.before:.2%} -> {self.after:.2%} on the fit scene"
        return f"tried {why}: {self.before:.2%} -> {self.after:.2%}, not a tenth better, so held"


FINDINGS = (ErrorAboveThreshold, ModelMismatch, TableMismatch, HeldOutAbove, RenderersDisagree, RenderersFloor,
            AdapterOff,
            TransportUnchecked, CannotResolve, ImagePrecision, NoEffect, IllConditioned, NotAtMinimum,
            PinnedOnBound, RendererAlters, ValidationSkipped, NothingFitted, TableLookup, TexturedAbove, TexturedNotes,
            StartKept, ChoiceTried, SmoothHeld, SchemeChosen, DeadParameters,
            JointRefined, PredictionNotRealised, NoisePolished, InputsTried, Approximated, SameMaterial,
            UniformTarget, NotGiven, Uncalibrated, NoiseUnmeasured, Underdetermined)
Finding = Annotated[Union[FINDINGS], Field(discriminator="kind")]

FindingKind = StrEnum("FindingKind", {c.model_fields["kind"].default.upper(): c.model_fields["kind"].default
                                      for c in FINDINGS})
"""Every finding's kind, as an enum (built from the findings themselves, so none is written twice):
what a table's point keeps of its findings."""

class Status(StrEnum):
    """A result's verdict (`Verdict.of`)."""

    OK = "ok"
    MISMATCH = "mismatch"
    UNRELIABLE = "unreliable"
    UNCHECKED = "unchecked"


class Verdict(Strict):
    """The findings, and what they add up to: ok (nothing unreliable, and every condition resolved),
    mismatch (only a model mismatch, and the held-out lights it shows under: the closest this target
    model gets), unreliable, or unchecked (nothing unreliable where it was checked, but some condition
    could not resolve the material: not ok, and said apart)."""

    status: Status
    findings: list[Finding] = Field(default_factory=list)

    @classmethod
    def of(cls, findings: list) -> "Verdict":
        problems = [f for f in findings if f.severity == Severity.UNRELIABLE]
        if not problems:
            status = Status.UNCHECKED if any(f.severity == Severity.UNCHECKED for f in findings) else Status.OK
        elif any(isinstance(f, (ModelMismatch, TableMismatch)) for f in problems) and all(
                isinstance(f, (ModelMismatch, TableMismatch, HeldOutAbove)) for f in problems) and not any(
                isinstance(f, Approximated) for f in findings):
            # The closest this target model gets, under the held-out lights too; not claimed where a side is
            # drawn approximately (the gap may be the approximation's): unreliable then, and said.
            status = Status.MISMATCH
        else:
            status = Status.UNRELIABLE
        return cls(status=status, findings=list(findings))

    @property
    def reliable(self) -> bool:
        return self.status == Status.OK

    @property
    def problems(self) -> list:
        return [f for f in self.findings if f.severity == Severity.UNRELIABLE]

    @property
    def unchecked(self) -> list:
        return [f for f in self.findings if f.severity == Severity.UNCHECKED]

    @property
    def notes(self) -> list[str]:
        """The notes, and what was not checked where something else makes the result unreliable."""
        return [f.message for f in self.findings
                if f.severity == Severity.NOTE or (f.severity == Severity.UNCHECKED and self.problems)]

    @property
    def reason(self) -> str:
        """The unreliable findings' sentences, joined; else what was not checked and what was; "ok"
        when neither. A uniform target for a textured source is said in any case (`UniformTarget`)."""
        return self.told or "ok"

    @property
    def told(self) -> str:
        """What the verdict has to tell beside its status: `reason`, "" where that would be "ok"."""
        uniform = [f.message for f in self.findings if isinstance(f, UniformTarget)]
        return "; ".join(x for x in [self._reason(), *uniform] if x)

    def _reason(self) -> str:
        if self.problems:
            drawn = [f for f in self.findings if isinstance(f, Approximated)]
            return "; ".join(f.message for f in [*self.problems, *drawn])
        if self.unchecked:
            lights = [f for f in self.unchecked if hasattr(f, "checked")]  # conditions unresolved: which were
            if not lights:
                return "; ".join(f.message for f in self.unchecked)
            checked = lights[0].checked
            return "; ".join(f.message for f in self.unchecked) + (
                f"; checked under {', '.join(checked)}" if checked else "; checked under no light")
        return ""
