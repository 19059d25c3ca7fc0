"""Run one job: render the source, fit the target, and produce its report and files in memory.

This is where adapters meet the engine; it still knows no renderer by name. `run_job` is what
an executor calls, in this process with the caller's adapters, `run_in_worker` in a worker process
or on a Dask worker: each returns an `Outcome` (the report and the bytes of every file), which the
caller's store writes. The job arrives resolved (`Resolved`: checked once, by whoever made it)."""

from __future__ import annotations

import atexit
import functools
import hashlib
import math
import tempfile
import threading
import time
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterator

import numpy as np

from ..data.account import Ledger, Metered, purpose
from ..data.atomic import why
from ..data.errors import RemapError, RenderError
from ..data.findings import SameMaterial, SmoothHeld, Underdetermined, UniformTarget, Verdict
from ..data.imageio import display_exposure, preview, write_exr, write_png, write_previews
from ..data.schemas import Lobe, ParamKind, Value
from ..data.settings import FitScene, Inputs, Start
from ..engine import ProgressFn, remap
from ..host.plugins import AdapterRegistry, collect_adapters
from ..host.model import Model
from ..host.protocol import Adapter
from ..engine.results import EngineResult
from .fitscene import FitScene as Chosen, as_given as given_scene, choose as choose_scene
from .job import Job, Resolved
from .renders import CachedRenderer, ProbeRenders
from .report import PARTING
from .report import FileRecord, Report, build_report
from .texturing import Texturing, textured_findings
from ..data.scene import LightType, ProbeScene
from ..engine.schedule import highlight_pixels


IMAGES = ("source.exr", "target.exr", "source.png", "target.png", "error.png")
"""The files every result has, besides the target's native material."""


@dataclass
class Outcome:
    """What one job produced: its report, the two images, and the bytes of its files by name."""

    report: Report
    source_image: np.ndarray
    target_image: np.ndarray
    files: dict[str, bytes]


class AdapterPool:
    """The adapters one process has open: each constructed once (this is where renderers get
    imported and workers start) and closed together. Passed to whatever renders in the process
    that opened it; a worker process keeps its own (`_worker_adapters`)."""

    def __init__(self, registry: AdapterRegistry):
        self.registry = registry
        self.open: dict[str, Adapter] = {}

    def __getitem__(self, name: str) -> Adapter:
        if name not in self.open:
            self.open[name] = self.registry.create(name)
        return self.open[name]

    def close(self) -> None:
        for a in self.open.values():
            a.close()
        self.open.clear()


_ONE_AT_A_TIME = threading.Lock()
"""A process runs one job at a time: its adapters (a Mitsuba scene updated in place, a Blender
worker) are shared by every job of the process."""


@contextmanager
def adapter_pool(registry: AdapterRegistry) -> Iterator[AdapterPool]:
    """``registry``'s adapters, opened as jobs need them, closed when the block ends."""
    pool = AdapterPool(registry)
    try:
        yield pool
    finally:
        pool.close()


def run_job(resolved: Resolved, adapters: AdapterPool, progress: ProgressFn | None = None) -> Outcome:
    """Run a resolved job (its errors were reported before any render) with these adapters."""
    with _ONE_AT_A_TIME:
        return execute(resolved, adapters, progress)


@functools.lru_cache(maxsize=None)
def _worker_adapters(renderer_files: tuple[str, ...]) -> AdapterPool:
    """A worker process's adapters (a local pool's, a Dask worker's): opened at its first job and
    kept for its life, so that every job after the first finds its renderers started; closed when
    the process ends. Only `run_in_worker` uses them: the process that runs jobs itself passes its
    own pool. Called under the process's job lock: a Dask worker's threads open one pool."""
    registry = collect_adapters()
    for f in renderer_files:  # the renderer definitions the caller loaded from files
        registry.resolve(f)
    pool = AdapterPool(registry)
    atexit.register(pool.close)
    return pool


def run_in_worker(resolved: Resolved, renderer_files: tuple[str, ...] = ()) -> Outcome:
    """Run a resolved job sent to a worker process, with that process's adapters: only where they are
    the versions the job was resolved with (a worker with another renderer or adapter would store
    its renders under this machine's key)."""
    with _ONE_AT_A_TIME:  # one pool per process, opened by its first job
        adapters = _worker_adapters(tuple(renderer_files))
        versions = {name: adapters.registry.get(name).version for name in resolved.job.versions}
        if versions != resolved.job.versions:
            raise RenderError(f"the worker has other renderers than the job was planned with (adapters {versions}; "
                              f"here: {resolved.job.versions}): install the same brdf-remap and renderers on every "
                              "worker")
        return execute(resolved, adapters)


def source_highlight(source: CachedRenderer, resolved: Resolved, scene: ProbeScene) -> float:
    """The pixels the source's highlight covers on ``scene`` (`highlight_pixels`): of its specular lobe
    where it isolates one (a plastic's, not its diffuse shading), else of its image."""
    spec = resolved.source_spec.lobes.get(Lobe.SPECULAR) if source.separates_lobes else None
    lobe = Lobe.SPECULAR if spec is not None and not spec.empty else None
    return highlight_pixels(source(resolved.source_params, lobe, scene=scene))


def fit_policy(job: Job) -> str:
    """`Settings.fit_scene`, but a table's lookup is judged on the scene its direct fits saw: without
    the back light's view (tables are built on the job's scene alone: `Settings.for_study`)."""
    return FitScene.ONE_VIEW if job.lookup is not None and job.settings.fit_scene == FitScene.AUTO else job.settings.fit_scene


def execute(resolved: Resolved, adapters: AdapterPool, progress: ProgressFn | None = None) -> Outcome:
    if resolved.same_material:
        return same_material(resolved, adapters)
    t0 = time.perf_counter()
    job = resolved.job
    src, tgt = job.source, job.target
    ledger = Ledger()
    own = adapters[src.adapter] if src.native is None else adapters[src.adapter].for_native(src.native)
    src_adapter, tgt_adapter = Metered(own, "source", ledger), Metered(adapters[tgt.adapter], "target", ledger)
    source = CachedRenderer.source(src_adapter, src.adapter, resolved.source_spec, job.scene, src.native)
    target = CachedRenderer(tgt_adapter, tgt.adapter, resolved.target_spec, job.scene)
    if progress:
        progress("source", 0, float("nan"))
    env_ok = all(LightType.ENVIRONMENT in adapters[n].light_types for n in (src.adapter, tgt.adapter))
    with purpose("fit scene"):
        fit = given_scene(lambda sc: source(resolved.source_params, scene=sc), job.scene,
                          lambda sc: own.scene_problem(sc) is None, own.noise_of) if own.fixed_scenes else \
            choose_scene(lambda sc: source(resolved.source_params, scene=sc), job.scene, env_ok,
                           job.settings.resolve_limit, fit_policy(job),
                           smooth=resolved.source_spec.is_smooth(resolved.source_params) or resolved.target_spec.smooth,
                           transmissive=resolved.source_transmits,
                           source_smooth=resolved.source_spec.is_smooth(resolved.source_params),
                           highlight=lambda sc: source_highlight(source, resolved, sc))
    renders = ProbeRenders(source, resolved.source_params, resolved.source_spec, target, fit.scene, given=job.scene,
                           given_noise=fit.scene_noise, resolve_limit=job.settings.resolve_limit, sharp=fit.sharp,
                           look=resolved.look, transmits=resolved.source_transmits)
    informed = job.settings.start == Start.INFORMED and job.lookup is None and job.start is None
    smooth = smooth_held(resolved) if job.lookup is None else {}
    start = {**(informed_start(resolved) if informed else given_start(resolved)), **smooth}
    free = [p for p in fitted(resolved, start) if p not in smooth] if job.lookup is None else []
    # A textured source is a lookup (nothing fitted): its maps and their check come first, for the verdict.
    with purpose("textured"):
        texturing = resolved.textured(resolved, src_adapter, tgt_adapter, dict(resolved.base)) \
            if resolved.textured is not None else None
    notes = lookup_notes(job) + (textured_findings(texturing.record, job.settings.threshold,
                                                   job.settings.resolve_limit) if texturing else []) + \
        ([SmoothHeld(held=smooth)] if smooth else []) + \
        ([UniformTarget(driven=list(src.native.driven))] if src.native is not None and src.native.driven else []) + \
        own.native_findings()
    result = remap(resolved.target_spec, {**resolved.base, **start}, free, renders, job.settings, job.tuning,
                   progress, alternatives=alternatives(resolved, start, smooth) if informed else [], notes=notes,
                   needed=needed(resolved, start) if free and job.settings.inputs == Inputs.NEEDED else {})
    files = artifacts(adapters[tgt.adapter], resolved.target_spec, result.params, renders.source_image(), result.target_image,
                      texturing, parting(renders, result.params, result.verdict))
    info = describe(adapters, list(dict.fromkeys((src.adapter, tgt.adapter))))
    derived = (resolved.source_spec.derive(resolved.source_params), resolved.target_spec.derive(result.params))
    report = build_report(resolved, result, start=start, derived=derived, fit_scene=fit,
                          source_renders=renders.source_renders(),
                          renders_by_resolution=target.renders_by_resolution(), seconds=time.perf_counter() - t0,
                          account=ledger.account(time.perf_counter() - t0),
                          adapters=info, files=[FileRecord(name=n, sha256=hashlib.sha256(b).hexdigest(), bytes=len(b))
                                                for n, b in files.items()],
                          textures=texturing.record if texturing else None,
                          rule=resolved.rule.name if informed and resolved.rule is not None else "")
    return Outcome(report, renders.source_image(), result.target_image, files)


def same_material(resolved: Resolved, adapters: AdapterPool) -> Outcome:
    """A remap to the source's own model in the same renderer: the source's parameters, rendered once
    for the result's images, with nothing fitted and nothing to judge (`Resolved.same_material`)."""
    t0 = time.perf_counter()
    job = resolved.job
    ledger = Ledger()
    source = CachedRenderer(Metered(adapters[job.source.adapter], "source", ledger), job.source.adapter,
                            resolved.source_spec, job.scene)
    with purpose("source"):
        image = np.asarray(source(resolved.source_params), np.float32)
    params = {**resolved.base, **resolved.source_params}
    settings = job.settings
    result = EngineResult(params=params, fitted=[], scheme=settings.scheme, scheme_used=settings.scheme,
                          relative_rmse=0.0, perceptual=0.0, threshold=settings.threshold, source_noise=0.0,
                          target_noise=0.0, renders=0, seconds=time.perf_counter() - t0,
                          verdict=Verdict.of([SameMaterial()]), target_image=image)
    files = artifacts(adapters[job.target.adapter], resolved.target_spec, params, image, image)
    derived = (resolved.source_spec.derive(resolved.source_params), resolved.target_spec.derive(params))
    report = build_report(resolved, result, start={}, derived=derived, fit_scene=Chosen(job.scene),
                          source_renders=source.cache.misses, renders_by_resolution={},
                          seconds=time.perf_counter() - t0, account=ledger.account(time.perf_counter() - t0),
                          adapters=describe(adapters, [job.source.adapter]),
                          files=[FileRecord(name=n, sha256=hashlib.sha256(b).hexdigest(), bytes=len(b))
                                 for n, b in files.items()])
    return Outcome(report, image, image, files)


def _textured_files(d: Path, adapter: Adapter, model: Model, texturing: Texturing) -> list[Path]:
    paths = []
    for name, data in texturing.files.items():
        (d / name).write_bytes(data)
        paths.append(d / name)
    paths += [Path(p) for p in adapter.write_native(model, texturing.params, d, textures=texturing.native)]
    if texturing.images is not None:
        src, tgt = texturing.images
        write_exr(d / "source-textured.exr", src)
        write_exr(d / "target-textured.exr", tgt)
        write_previews(d, src, tgt, prefix="textured-")
        paths += [d / n for n in ("source-textured.exr", "target-textured.exr", "textured-source.png",
                                  "textured-target.png", "textured-error.png")]
    return paths


def lookup_notes(job: Job) -> list:
    """The finding that says a lookup's parameters came from a table ([] for a fit)."""
    from ..data.findings import TableLookup

    lk = job.lookup
    if lk is None:
        return []
    return [TableLookup(table=lk.table, method=lk.method, expected_error=lk.expected_error, outside=lk.outside)]


def parting(renders: ProbeRenders, params: dict[str, Value], verdict) -> tuple[np.ndarray, np.ndarray] | None:
    """The two images an `Underdetermined` finding compares (cached renders), or None where there is none."""
    found = next((f for f in verdict.findings if isinstance(f, Underdetermined)), None)
    if found is None:
        return None
    scene = next(sc for name, _, sc in renders.held_out() if name == found.condition)
    return renders.target_at(params, scene), renders.target_at({**params, **found.other}, scene)


def _parting_png(d: Path, images: tuple[np.ndarray, np.ndarray]) -> Path:
    k = display_exposure(images[0])
    write_png(d / PARTING, np.concatenate([preview(images[0], k), preview(images[1], k)], axis=1))
    return d / PARTING


def artifacts(adapter: Adapter, model: Model, params: dict[str, Value], source: np.ndarray,
              target: np.ndarray, texturing: Texturing | None = None,
              parted: tuple[np.ndarray, np.ndarray] | None = None) -> dict[str, bytes]:
    """The result's files, by name: linear EXRs, PNG previews, the material in the target's own form
    (made in a temporary folder, where this process runs, and handed over as bytes); a textured
    source's maps, the native material reading them, and the textured check's images."""
    try:
        with tempfile.TemporaryDirectory(prefix="brdfremap-") as tmp:
            d = Path(tmp)
            write_exr(d / "source.exr", source)
            write_exr(d / "target.exr", target)
            write_previews(d, source, target)
            paths = [d / n for n in IMAGES] + ([_parting_png(d, parted)] if parted is not None else [])
            if texturing is None:
                paths += [Path(p) for p in adapter.write_native(model, params, d)]
            else:
                paths += _textured_files(d, adapter, model, texturing)
            return {p.name: p.read_bytes() for p in paths}
    except (OSError, RemapError) as exc:
        reason = why(exc) if isinstance(exc, OSError) else exc.message
        raise RenderError(f"cannot make the result's files in the temporary folder {tempfile.gettempdir()}: "
                          f"{reason} (set TMPDIR to a folder with space)") from None


def informed_start(resolved: Resolved) -> dict[str, Value]:
    """The source's fixed rule for the target where its format defines one (`Resolved.rule`), else the
    exporters' conversion of the source into the target's fitted parameters (clipped to their bounds)
    and its discrete choices (a distribution the source names, unless held), or {} when either adapter
    has no neutral reading for its model. A value of the wrong shape or not finite is left out: the
    start is a hint, the fit does not need it."""
    look, spec, base = resolved.look, resolved.target_spec, resolved.base
    if resolved.rule is not None:  # every value the rule gives: the fitted ones, and what differs from the base
        conv = {k: v for k, v in resolved.rule.params.items() if spec.param(k).fit or v != base[k]}
        named = set(conv)
    elif look is None:
        return {}
    else:
        conv = spec.from_appearance(look, dict(base))
        named = {p.name for p in spec.parameters if p.kind == ParamKind.CHOICE and p.name in conv
                 and conv[p.name] in p.choices and _named(spec, look, base, p, conv[p.name])}
    out: dict[str, Value] = {p.name: conv[p.name] for p in spec.parameters if p.kind == ParamKind.CHOICE
                             and p.name not in resolved.fixed and p.name in named and conv[p.name] in p.choices}
    # Held ones too (the source's coat tint is rendered, not fitted), where the choices make them count.
    chosen = {**base, **out}
    for name in (p.name for p in spec.parameters
                 if p.kind != ParamKind.CHOICE and p.name not in resolved.fixed and spec.is_active(p.name, chosen)):
        try:
            v = spec.param(name).clip(conv[name])
        except (KeyError, TypeError, ValueError):
            continue
        if all(map(math.isfinite, v if isinstance(v, tuple) else (v,))):  # type: ignore[arg-type]
            out[name] = v
    return out


def smooth_held(resolved: Resolved) -> dict[str, float]:
    """For a perfectly smooth source, the values that make the target perfectly smooth
    (`ModelSpec.smooth_when`: roughness 0) that the user did not fix: held there, not fitted. Under
    the studio a fit hardly tells roughness 0 from a little more, which a point light shows."""
    native = resolved.job.source.native
    if not resolved.source_spec.is_smooth(resolved.source_params) or (native is not None and native.driven):
        return {}  # (a reading whose roughness a texture drives took the socket's value: not a mirror's word)
    return {k: v for k, v in resolved.target_spec.smooth_when.items() if k not in resolved.fixed}


def given_start(resolved: Resolved) -> dict[str, Value]:
    """The job's own start (`Job.start`, coerced by `resolve`), or {}."""
    spec = resolved.target_spec
    return {k: spec.param(k).clip(tuple(v) if isinstance(v, list) else v) if spec.param(k).kind != ParamKind.CHOICE else v
            for k, v in (resolved.job.start or {}).items()}


def fitted(resolved: Resolved, start: dict[str, Value]) -> list[str]:
    """The parameters the fit varies: the target's fittable ones with the start's choices (an
    anisotropic roughconductor fits alpha_u and alpha_v), and the held ones the source has
    (`ParamSpec.fit_when_carried`: its coat's weight and roughness, its sheen, its anisotropy)."""
    spec, params = resolved.target_spec, {**resolved.base, **start}
    free = spec.fittable(params, fixed=set(resolved.fixed))
    return free + [p.name for p in spec.parameters
                   if p.fit_when_carried and p.name in start and p.name not in resolved.fixed and p.name not in free
                   and spec.is_active(p.name, params) and not spec.is_inert(p.name, params)]


def needed(resolved: Resolved, start: dict[str, Value]) -> dict[str, str]:
    """The target's held inputs that the source's reading needs (`Appearance.needs` against
    `ParamSpec.fit_for`), each with why: those the user did not fix, that mean something and can
    change the image with the start's values. {} without a reading."""
    look = resolved.look
    if look is None:
        return {}
    has, spec, params = look.needs(), resolved.target_spec, {**resolved.base, **start}
    return {p.name: f"{n.value} ({has[n]})" for p in spec.parameters for n in p.fit_for
            if n in has and p.name not in resolved.fixed and spec.is_active(p.name, params)
            and not spec.is_inert(p.name, params)}


def _named(model: Model, look, base: dict[str, Value], p, value: Value) -> bool:
    """Whether the reading names this choice: it differs from the base, or it stays when the base
    holds another value (a source's GGX where GGX is also the default is named all the same)."""
    if value != base[p.name]:
        return True
    other = next((c for c in p.choices if c != value), None)
    if other is None:
        return False
    return model.from_appearance(look, {**base, p.name: other}).get(p.name) == value


def alternatives(resolved: Resolved, start: dict[str, Value],
                 smooth: dict[str, Value] | None = None) -> list[dict[str, Value]]:
    """The discrete choices to try: every value of each explorable choice (`ParamSpec.explore`)
    that neither the user held, nor the source carried (same model), nor the start named; none
    where ``smooth`` holds the target perfectly smooth (`smooth_held`: a mirror, whatever its
    distribution).
    [] when there is nothing to try."""
    same = (resolved.job.source.adapter, resolved.job.source.model) == (resolved.job.target.adapter,
                                                                        resolved.job.target.model)
    spec = resolved.target_spec
    if smooth and spec.smooth_when and all(smooth.get(k) == v for k, v in spec.smooth_when.items()):
        return []  # a mirror: every microfacet distribution renders it alike (tests/adapters/test_cycles.py)
    open_ = [p for p in spec.parameters if p.kind == ParamKind.CHOICE and p.explore and not same
             and p.name not in resolved.fixed and p.name not in start]
    combos: list[dict[str, Value]] = [{}]
    for p in open_:
        combos = [{**c, p.name: v} for c in combos for v in p.choices]
    return combos if len(combos) > 1 else []


def describe(adapters: AdapterPool, names: list[str]) -> dict[str, dict[str, Any]]:
    """Each adapter's runtime facts for the report (renderer version, variant)."""
    return {n: {"plugin": adapters.registry.get(n).plugin, **adapters[n].describe()} for n in names}
