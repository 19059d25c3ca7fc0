"""Run one job: render the source, fit the target, and produce its report and files in memory.

This is where adapters meet the engine; it still knows no renderer by name. `run_job` is what
an executor calls, in this process or in a worker process or on a Dask worker: it returns an
`Outcome` (the report and the bytes of every file), which the caller's store writes."""

from __future__ import annotations

import atexit
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
from ..data.findings import SmoothHeld
from ..data.imageio import write_exr, write_previews
from ..data.schemas import Lobe, ParamKind, Value
from ..data.settings import FitScene, Inputs, Start
from ..engine import ProgressFn, remap
from ..host.plugins import AdapterRegistry, collect_adapters
from ..host.protocol import Adapter
from .fitscene import choose as choose_scene
from .job import Job, Resolved, resolve
from .renders import CachedRenderer, ProbeRenders
from .report import FileRecord, Report, build_report
from .texturing import Texturing, texture_result, textured_findings
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
    imported and workers start) and closed together."""

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


_POOL: AdapterPool | None = None
_ONE_AT_A_TIME = threading.Lock()
"""A process runs one job at a time: its adapters (a Mitsuba scene updated in place, a Blender
worker) are shared by every job of the process."""


@contextmanager
def adapter_pool(registry: AdapterRegistry) -> Iterator[AdapterPool]:
    """Jobs run in this process use ``registry``'s adapters until the block ends, then close them."""
    global _POOL
    previous, _POOL = _POOL, AdapterPool(registry)
    try:
        yield _POOL
    finally:
        _POOL.close()
        _POOL = previous


def _pool(renderer_files: tuple[str, ...]) -> AdapterPool:
    """This process's pool: the one a caller opened, or (a worker process) one of its own, kept
    for the worker's life so every job after the first finds its renderers started."""
    global _POOL
    if _POOL is None:
        _POOL = AdapterPool(collect_adapters())
        atexit.register(_POOL.close)  # a worker process's renderers end with it
    for f in renderer_files:
        _POOL.registry.resolve(f)
    return _POOL


def run_job(job: Job, renderer_files: tuple[str, ...] = (), progress: ProgressFn | None = None) -> Outcome:
    """Run a job (already resolved once by the caller, so its errors were reported before any
    render) with this process's adapters."""
    with _ONE_AT_A_TIME:
        pool = _pool(tuple(renderer_files))
        return execute(resolve(job, pool.registry), pool, progress)


def source_highlight(source: CachedRenderer, resolved: Resolved, scene: ProbeScene) -> float:
    """The pixels the source's highlight covers on ``scene`` (`highlight_pixels`): of its specular lobe
    where it isolates one (a plastic's, not its diffuse shading), else of its image."""
    spec = resolved.source_spec.lobes.get(Lobe.SPECULAR)
    lobe = Lobe.SPECULAR if spec is not None and not spec.empty else None
    return highlight_pixels(source(resolved.source_params, lobe, scene=scene))


def fit_policy(job: Job) -> str:
    """`Settings.fit_scene`, but a table's lookup is judged on the scene its direct fits saw: without
    the back light's view (tables are built on the job's scene alone: `Settings.for_study`)."""
    return FitScene.ONE_VIEW if job.lookup is not None and job.settings.fit_scene == FitScene.AUTO else job.settings.fit_scene


def execute(resolved: Resolved, adapters: AdapterPool, progress: ProgressFn | None = None) -> Outcome:
    t0 = time.perf_counter()
    job = resolved.job
    src, tgt = job.source, job.target
    ledger = Ledger()
    src_adapter, tgt_adapter = Metered(adapters[src.adapter], "source", ledger), Metered(adapters[tgt.adapter],
                                                                                          "target", ledger)
    source = CachedRenderer(src_adapter, src.adapter, src.model, job.scene)
    target = CachedRenderer(tgt_adapter, tgt.adapter, tgt.model, job.scene)
    if progress:
        progress("source", 0, float("nan"))
    env_ok = all(LightType.ENVIRONMENT in adapters[n].light_types for n in (src.adapter, tgt.adapter))
    with purpose("fit scene"):
        fit = choose_scene(lambda sc: source(resolved.source_params, scene=sc), job.scene, env_ok,
                           job.settings.resolve_limit, fit_policy(job),
                           smooth=resolved.source_spec.is_smooth(resolved.source_params) or resolved.target_spec.smooth,
                           transmissive=resolved.source_spec.transmissive(resolved.source_params),
                           source_smooth=resolved.source_spec.is_smooth(resolved.source_params),
                           highlight=lambda sc: source_highlight(source, resolved, sc))
    renders = ProbeRenders(source, resolved.source_params, resolved.source_spec, target, fit.scene, given=job.scene,
                           given_noise=fit.scene_noise, resolve_limit=job.settings.resolve_limit, sharp=fit.sharp)
    informed = job.settings.start == Start.INFORMED and job.lookup is None and job.start is None
    smooth = smooth_held(resolved) if job.lookup is None else {}
    start = {**(informed_start(resolved, adapters) if informed else given_start(resolved)), **smooth}
    free = [p for p in fitted(resolved, start) if p not in smooth] if job.lookup is None else []
    # A textured source is a lookup (nothing fitted): its maps and their check come first, for the verdict.
    with purpose("textured"):
        texturing = texture_result(resolved, src_adapter, tgt_adapter, dict(resolved.base)) if src.textures else None
    notes = lookup_notes(job) + (textured_findings(texturing.record, job.settings.threshold,
                                                   job.settings.resolve_limit) if texturing else []) + \
        ([SmoothHeld(held=smooth)] if smooth else [])
    result = remap(resolved.target_spec, {**resolved.base, **start}, free, renders, job.settings, job.tuning,
                   progress, alternatives=alternatives(resolved, start, smooth) if informed else [], notes=notes,
                   needed=needed(resolved, adapters, start) if free and job.settings.inputs == Inputs.NEEDED else {})
    files = artifacts(adapters[tgt.adapter], tgt.model, result.params, renders.source_image(), result.target_image,
                      texturing)
    info = describe(adapters, list(dict.fromkeys((src.adapter, tgt.adapter))))
    derived = (adapters[src.adapter].derived(src.model, resolved.source_params),
               adapters[tgt.adapter].derived(tgt.model, result.params))
    report = build_report(resolved, result, start=start, derived=derived, fit_scene=fit,
                          source_renders=renders.source_renders(),
                          renders_by_resolution=target.renders_by_resolution(), seconds=time.perf_counter() - t0,
                          account=ledger.account(time.perf_counter() - t0),
                          adapters=info, files=[FileRecord(name=n, sha256=hashlib.sha256(b).hexdigest(), bytes=len(b))
                                                for n, b in files.items()],
                          textures=texturing.record if texturing else None)
    return Outcome(report, renders.source_image(), result.target_image, files)


def _textured_files(d: Path, adapter: Adapter, model: str, texturing: Texturing) -> list[Path]:
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


def artifacts(adapter: Adapter, model: str, params: dict[str, Value], source: np.ndarray,
              target: np.ndarray, texturing: Texturing | None = None) -> dict[str, bytes]:
    """The result's files, by name: linear EXRs, PNG previews, the material in the target's own form
    (made in a temporary folder, where this process runs, and handed over as bytes); a textured
    source's maps, the native material reading them, and the textured check's images."""
    try:
        with tempfile.TemporaryDirectory(prefix="brdfremap-") as tmp:
            d = Path(tmp)
            write_exr(d / "source.exr", source)
            write_exr(d / "target.exr", target)
            write_previews(d, source, target)
            paths = [d / n for n in IMAGES]
            if texturing is None:
                paths += [Path(p) for p in adapter.write_native(model, params, d)]
            else:
                paths += _textured_files(d, adapter, model, texturing)
            return {p.name: p.read_bytes() for p in paths}
    except (OSError, RemapError) as exc:
        reason = why(exc) if isinstance(exc, OSError) else exc.message
        raise RenderError(f"cannot make the result's files in the temporary folder {tempfile.gettempdir()}: "
                          f"{reason} (set TMPDIR to a folder with space)") from None


def informed_start(resolved: Resolved, adapters: AdapterPool) -> dict[str, Value]:
    """The exporters' conversion of the source into the target's fitted parameters (clipped to
    their bounds) and its discrete choices (a distribution the source names, unless held), or {}
    when either adapter has no neutral reading for its model. A value of the wrong shape or not
    finite is left out: the start is a hint, the fit does not need it."""
    job = resolved.job
    look = adapters[job.source.adapter].appearance(job.source.model, resolved.source_params)
    if look is None:
        return {}
    conv = adapters[job.target.adapter].from_appearance(job.target.model, look, dict(resolved.base))
    out: dict[str, Value] = {}
    spec = resolved.target_spec
    for p in spec.parameters:
        if (p.kind == ParamKind.CHOICE and p.name not in resolved.fixed and conv.get(p.name) in p.choices
                and _named(adapters[job.target.adapter], job.target.model, look, resolved.base, p, conv[p.name])):
            out[p.name] = conv[p.name]
    # Held ones too (the source's coat tint is rendered, not fitted), where the choices make them count.
    chosen = {**resolved.base, **out}
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
    if not resolved.source_spec.is_smooth(resolved.source_params):
        return {}
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


def needed(resolved: Resolved, adapters: AdapterPool, start: dict[str, Value]) -> dict[str, str]:
    """The target's held inputs that the source's reading needs (`Appearance.needs` against
    `ParamSpec.fit_for`), each with why: those the user did not fix, that mean something and can
    change the image with the start's values. {} without a reading."""
    job = resolved.job
    look = adapters[job.source.adapter].appearance(job.source.model, resolved.source_params)
    if look is None:
        return {}
    has, spec, params = look.needs(), resolved.target_spec, {**resolved.base, **start}
    return {p.name: f"{n.value} ({has[n]})" for p in spec.parameters for n in p.fit_for
            if n in has and p.name not in resolved.fixed and spec.is_active(p.name, params)
            and not spec.is_inert(p.name, params)}


def _named(adapter, model: str, look, base: dict[str, Value], p, value: Value) -> bool:
    """Whether the reading names this choice: it differs from the base, or it stays when the base
    holds another value (a source's GGX where GGX is also the default is named all the same)."""
    if value != base[p.name]:
        return True
    other = next((c for c in p.choices if c != value), None)
    if other is None:
        return False
    return adapter.from_appearance(model, look, {**base, p.name: other}).get(p.name) == value


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
