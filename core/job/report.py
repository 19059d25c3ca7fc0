"""The report of one job: `result.json`, a versioned pydantic model produced once (`build_report`)
and never edited. `remap schema report` prints its JSON Schema; `read_report` reads one back
and says clearly when it was written by another version of the format."""

from __future__ import annotations

import hashlib
import json
import math
import platform
from pathlib import Path
from typing import Any

from pydantic import Field, computed_field

from ..data.account import Account
from ..data.errors import ConfigError
from ..data.findings import Finding, Status, Verdict
from ..data.metrics import beyond_noise
from ..data.model import Strict as _Strict
from ..data.model import WithDerived
from ..data.scene import ProbeScene
from ..data.settings import Scheme
from ..data.versioned import JsonFormat, check_version, parse, read_json
from ..engine.results import Check, EngineResult, StageResult
from ..engine.tuning import ENGINE_VERSION
from .job import Job, Resolved
from .renders import rounded
from .texturing import Textured

SCHEMA_VERSION = 8
"""Bump whenever the fields change (an older reader refuses a field it does not know). 4: a job's
table lookup, a textured source's record; 5: the account of the job's renders; 6: the renderers'
difference on a white Lambertian in a held-out error (`renderers`) and its note (`renderers_floor`);
7: the held inputs the source needs (`inputs_tried`, `Settings.inputs`) and what a renderers'
floor was measured on (`reference`); 8: the fixed rule a start is (`start.rule`), the findings
`approximated` and `same_material`."""
READS_FROM = 7
"""The oldest format read. 4 and 5 only added fields (left out of the digest while absent), but 6
changed what a verdict is (an unresolved condition is unchecked, no longer a note of an ok) and what
its findings hold, and 7 what a fit varies (the inputs a source needs) and what a metal is judged
beyond (the renderers' metals): a result of 6 or before is run again (its engine is older too)."""

PARTING = "underdetermined.png"
"""A result's image of the target at the fit's parameters and at the others within its noise, side by side,
under the held-out condition where they part most (`core.engine.underdetermined`)."""


class NewerReportError(ConfigError):
    """A report written by a newer brdf-remap: not to be read, nor overwritten."""


class SourceRecord(_Strict):
    file: str = Field(description="Where the source came from (file, point or material).")
    name: str = Field(description="The material's name.")
    adapter: str
    model: str
    params: dict[str, Any] = Field(description="The source's parameters that mean something with its choices.")
    derived: dict[str, Any] = Field(default_factory=dict, description="Quantities that follow from them (a "
                                                                      "conductor's reflectivity), from its adapter.")


class TargetRecord(_Strict):
    adapter: str
    model: str


class Metrics(_Strict):
    relative_rmse: float = Field(description="||target - source|| / ||source|| over all pixels (the paper's L2).")
    perceptual: float = Field(description="Mean ΔE_ITP over the object (1 ≈ just noticeable).")
    noise_floor: float = Field(description="Relative RMSE expected between two renders of one material (source and "
                                           "target noise, each from a second seed).")
    noise_source: float
    noise_target: float
    beyond_noise: float = Field(description="The part of relative_rmse the noise floor does not explain: "
                                            "sqrt(max(0, error² - floor²)), what the threshold judges.")
    threshold: float = Field(description="The threshold on beyond_noise (here and under each held-out light).")
    start_error: float | None = Field(description="Relative RMSE of the fit's start at the scene: the result is "
                                                  "never worse.")
    jacobian_condition: float | None = Field(description="Condition number of the final Jacobian (None: not "
                                                         "defined, fewer than two live parameters).")


class Start(_Strict):
    informed: bool = Field(description="The fit started from the exporters' conversion of the source (or from the "
                                       "fixed rule its format defines: `rule`).")
    params: dict[str, Any] = Field(description="That conversion, or the job's own start (`job.start`), where one "
                                               "was used.")
    rule: str = Field("", description="The fixed rule that conversion is, where the source's format defines one for "
                                      "the target (a correspondence of its inputs to the target's, an importer's): "
                                      "`metrics.start_error` is then the rule's own error, the fit's beside it.")


class FitSceneRecord(_Strict):
    why: str
    scene: ProbeScene
    source_noise_given: float = Field(description="The source's render noise on the job's scene.")
    source_noise: float = Field(description="... and on this one.")


class FileRecord(_Strict):
    name: str
    sha256: str
    bytes: int


class Report(WithDerived):
    """`result.json`: what one job produced and what it is worth."""

    derived_fields = ("reliable", "reason", "notes", "digest")

    schema_version: int = Field(description="Version of this format (see `SCHEMA_VERSION`).")
    tool: str = Field(description="The program and version that wrote it.")
    engine: int = Field(description="Engine version (see core/engine/tuning.py).")
    key: str = Field(description="The job's key: equal keys, equal results.")
    job: Job = Field(description="The job in canonical form (completed parameters).")
    source: SourceRecord
    target: TargetRecord
    params: dict[str, Any] = Field(description="The fitted target parameters that mean something (complete set "
                                               "less those inactive with its choices).")
    derived: dict[str, Any] = Field(default_factory=dict, description="Quantities that follow from the fitted "
                                                                      "parameters, from the target adapter.")
    fitted: list[str]
    fixed: dict[str, Any]
    metrics: Metrics
    start: Start
    renders: int = Field(description="Target renders made.")
    renders_by_resolution: dict[str, int]
    source_renders: int
    seconds: float
    scheme: Scheme
    scheme_used: Scheme
    verdict: Status = Field(description="ok (holds under the scene's lights and every held-out one); mismatch "
                                        "(only a model mismatch: the closest this target model gets); unreliable "
                                        "(see findings); unchecked (nothing unreliable where it was checked, but "
                                        "a condition could not resolve the material: not checked there).")
    findings: list[Finding]
    fit_scene: FitSceneRecord | None = Field(description="Where the fit ran when not on the job's scene (which "
                                                          "could not resolve the source), and why; None: the job's.")
    validation: list[Check] = Field(description="Source and target under held-out lights the fit never saw (empty "
                                                "with --validate none).")
    validation_skipped: dict[str, str] = Field(default_factory=dict, description="Held-out conditions not "
                                                                                 "rendered, and why.")
    stages: list[StageResult]
    adapters: dict[str, dict[str, Any]] = Field(description="Each adapter's runtime facts (renderer version, "
                                                            "variant).")
    host: dict[str, str]
    files: list[FileRecord] = Field(description="The files of this result beside result.json, with their hashes.")
    textures: Textured | None = Field(None, description="A textured source remapped texel by texel through a "
                                                        "table: its maps and the textured check.")
    account: Account | None = Field(None, description="Where the job's seconds went: renders by purpose and "
                                                      "side, and the time outside renderers.")

    @computed_field  # type: ignore[prop-decorator]
    @property
    def reliable(self) -> bool:
        return self.verdict == Status.OK

    @computed_field  # type: ignore[prop-decorator]
    @property
    def reason(self) -> str:
        """The unreliable findings' sentences, else what was not checked; "ok" when neither."""
        return self.as_verdict().reason

    @computed_field  # type: ignore[prop-decorator]
    @property
    def notes(self) -> list[str]:
        return self.as_verdict().notes

    @computed_field  # type: ignore[prop-decorator]
    @property
    def digest(self) -> str:
        """SHA-256 of the rest of the document: a report edited after it was written is not
        taken for the job's result. Fields of format 4 are left out while absent (see `READS_FROM`)."""
        doc = self.model_dump(mode="json", exclude={"digest"})
        for container, key in ((doc, "textures"), (doc, "account"), (doc["job"], "lookup"), (doc["job"], "start"),
                               (doc["job"], "fit_same_model"), (doc["job"]["source"], "textures"),
                               (doc["start"], "rule")):
            if not container.get(key):
                container.pop(key, None)
        return hashlib.sha256(json.dumps(doc, sort_keys=True, ensure_ascii=False).encode()).hexdigest()

    def as_verdict(self) -> Verdict:
        return Verdict(status=self.verdict, findings=self.findings)

    def document(self) -> dict[str, Any]:
        return self.model_dump(mode="json")


def build_report(resolved: Resolved, result: EngineResult, *, start: dict, derived: tuple[dict, dict], fit_scene,
                 source_renders: int, renders_by_resolution: dict[str, int], seconds: float,
                 adapters: dict[str, dict[str, Any]], files: list[FileRecord],
                 textures: Textured | None = None, account: Account | None = None, rule: str = "") -> Report:
    """The report, in one place: ``derived`` holds the source's and the target's derived quantities."""
    from .. import __version__

    job = resolved.job
    src, tgt = job.source, job.target
    active = resolved.target_spec.active(result.params)
    v = result.verdict
    return Report(
        schema_version=SCHEMA_VERSION, tool=f"brdf-remap {__version__}", engine=ENGINE_VERSION, key=job.key(), job=job,
        source=SourceRecord(file=job.label, name=src.name, adapter=src.adapter, model=src.model,
                            params=resolved.source_spec.active(resolved.source_params), derived=derived[0]),
        target=TargetRecord(adapter=tgt.adapter, model=tgt.model), params=active, derived=derived[1],
        fitted=list(result.fitted),
        fixed=dict(resolved.fixed),
        metrics=Metrics(relative_rmse=result.relative_rmse, perceptual=result.perceptual,
                        noise_floor=result.noise_floor, noise_source=result.source_noise,
                        noise_target=result.target_noise, beyond_noise=beyond_noise(result.relative_rmse,
                                                                                    result.noise_floor),
                        threshold=result.threshold, start_error=result.start_error,
                        jacobian_condition=_finite(result.jacobian_condition)),
        start=Start(informed=bool(start) and job.start is None, params=rounded(start), rule=rule), renders=result.renders,
        renders_by_resolution=renders_by_resolution, source_renders=source_renders, seconds=seconds,
        scheme=result.scheme, scheme_used=result.scheme_used, verdict=v.status, findings=v.findings,
        validation=result.validation.checks, validation_skipped=result.validation.skipped, stages=result.stages,
        fit_scene=None if not fit_scene.why else FitSceneRecord(why=fit_scene.why, scene=fit_scene.scene,
                                                                 source_noise_given=fit_scene.scene_noise,
                                                                 source_noise=fit_scene.noise), adapters=adapters,
        host={"python": platform.python_version(), "machine": platform.machine()}, files=files, textures=textures,
        account=account)


def for_job(report: Report, job: Job) -> Report:
    """A result under another job of the same key: the same material met again elsewhere (in
    another file of a library), its result the same, its labels that job's own."""
    if job.key() != report.key:
        raise ValueError("for_job: the job's key is not the report's")
    return report.model_copy(update={"job": job, "source": report.source.model_copy(update={
        "file": job.label, "name": job.source.name})})


def _finite(x: float | None) -> float | None:
    return x if x is not None and math.isfinite(x) else None


def report_schema() -> dict[str, Any]:
    """The JSON Schema of `result.json` as written (derived fields included)."""
    return Report.model_json_schema(mode="serialization")


REPORT_FORMAT = JsonFormat(kind="report schema", reads=tuple(range(READS_FROM, SCHEMA_VERSION + 1)),
                           older="run the job again to replace it", newer_error=NewerReportError,
                           edited="was edited after it was written (its digest does not match its content): it is "
                                  "not taken for the job's result")


def parse_report(doc: Any, file: str) -> Report:
    """A report from its JSON document; a clear ConfigError for another version of the format."""
    if not isinstance(doc, dict):
        raise ConfigError("not a brdf-remap report (expected a JSON object)", file=file)
    check_version(doc, REPORT_FORMAT, file)
    return parse(doc, Report, REPORT_FORMAT, file, digest="digest")


def read_report(path: str | Path) -> Report:
    return parse_report(read_json(Path(path), REPORT_FORMAT), str(path))
