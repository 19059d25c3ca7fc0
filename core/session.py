"""One remap job: validate the inputs, render the source, fit the target, write the results.

This is where adapters meet the engine; it still knows no renderer by name."""

from __future__ import annotations

import collections
import json
import math
import platform
import time
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from .atomic import write_json_atomic
from .cache import RenderCache, render_key
from .errors import ConfigError
from .imageio import write_exr, write_previews
from .metrics import delta_e_itp, error_map, relative_rmse
from .plugins import AdapterRegistry
from .protocol import Adapter, check_image
from .remap import ENGINE, Level, ParamSpace, ProgressFn, RemapOptions, RemapResult, remap
from .scene import ProbeScene
from .schemas import Material, ModelSpec, Value


@dataclass
class Job:
    """A validated remap request."""

    source: Material
    source_file: str
    source_params: dict[str, Value]
    source_spec: ModelSpec
    target_adapter: str
    target_model: str
    target_spec: ModelSpec
    base: dict[str, Value]
    free: list[str]
    fixed: dict[str, Value]
    scene: ProbeScene
    options: RemapOptions


def _model(registry: AdapterRegistry, adapter: str, model: str, file: str | None, field_name: str) -> ModelSpec:
    entry = registry.get(adapter)
    if model not in entry.models:
        known = ", ".join(sorted(entry.models)) or "none"
        raise ConfigError(f"adapter {adapter!r} has no model {model!r} (models: {known})", file=file, field=field_name)
    return entry.models[model]


def prepare(
    registry: AdapterRegistry,
    source: Material,
    source_file: str,
    target_adapter: str,
    target_model: str,
    scene: ProbeScene,
    fixed: dict[str, Value],
    options: RemapOptions,
) -> Job:
    """Check everything before any render: adapters, models, parameters, bounds."""
    source = source.model_copy(update={"adapter": registry.resolve(source.adapter, file=source_file)})
    src_spec = _model(registry, source.adapter, source.model, source_file, "model")
    src_params = src_spec.complete(source.params, file=source_file)
    tgt_spec = _model(registry, target_adapter, target_model, None, "--model")
    base = tgt_spec.complete({})
    if (source.adapter, source.model) == (target_adapter, target_model):
        # Same model: discrete choices (distribution, material preset) carry over unless fixed.
        for p in tgt_spec.parameters:
            if p.kind == "choice":
                base[p.name] = src_params[p.name]
    base.update(fixed)
    free = tgt_spec.fittable(base, fixed=set(fixed))
    return Job(source, source_file, src_params, src_spec, target_adapter, target_model, tgt_spec, base, free,
               dict(fixed), scene, options)


@dataclass
class Outcome:
    job: Job
    result: RemapResult
    source_image: np.ndarray
    noise_floor: float
    source_renders: int
    adapters: dict[str, Any] = field(default_factory=dict)
    noise: dict[str, float] = field(default_factory=dict)
    renders_by_resolution: dict[str, int] = field(default_factory=dict)
    """Target renders by "32px", "128px" (the scene's samples) and e.g. "128px@64spp" (more samples)."""
    start: dict[str, Value] = field(default_factory=dict)


class _CachedRenderer:
    def __init__(self, adapter: Adapter, name: str, model: str, scene: ProbeScene, cache: RenderCache):
        self.adapter, self.name, self.model, self.scene, self.cache = adapter, name, model, scene, cache
        self.by_resolution: collections.Counter[tuple[int, int]] = collections.Counter()  # (resolution, spp)

    def _key(self, params: dict[str, Value], lobe: str | None, scene: ProbeScene) -> str:
        return render_key(self.name, self.model, {k: _round(v) for k, v in params.items()}, scene.cache_key(), lobe)

    def __call__(self, params: dict[str, Value], lobe: str | None = None, scene: ProbeScene | None = None):
        sc = scene or self.scene
        key = self._key(params, lobe, sc)
        who = f"adapter {self.name!r} model {self.model!r}"

        def render():
            self.by_resolution[sc.resolution, sc.spp] += 1
            return check_image(self.adapter.render(self.model, dict(params), sc, lobe), sc, who)

        return self.cache.get_or_render(key, render)

    def many(self, items: list[tuple[dict[str, Value], str | None]], scene: ProbeScene | None = None) -> None:
        """Render the uncached ones of several requests in one batch (in parallel where the adapter can)."""
        sc = scene or self.scene
        todo, seen = [], set()
        for params, lobe in items:
            key = self._key(params, lobe, sc)
            if key not in self.cache and key not in seen:
                seen.add(key)
                todo.append((key, params, lobe))
        if len(todo) < 2:
            return
        who = f"adapter {self.name!r} model {self.model!r}"
        images = self.adapter.render_batch([(self.model, dict(p), sc, lobe) for _, p, lobe in todo])
        for (key, _, _), img in zip(todo, images):
            self.by_resolution[sc.resolution, sc.spp] += 1
            checked = check_image(img, sc, who)
            self.cache.get_or_render(key, lambda: checked)


class _LevelRenderer:
    """The target at one resolution, as the engine calls it: render(params, lobe), and many(...)."""

    def __init__(self, tgt: _CachedRenderer, scene: ProbeScene):
        self.tgt, self.scene = tgt, scene

    def __call__(self, params: dict[str, Value], lobe: str | None = None) -> np.ndarray:
        return self.tgt(params, lobe, scene=self.scene)

    def many(self, items: list[tuple[dict[str, Value], str | None]]) -> None:
        self.tgt.many(items, scene=self.scene)


def _round(v: Value) -> Value:
    if isinstance(v, tuple):
        return tuple(float(f"{x:.9g}") for x in v)
    if isinstance(v, float):
        return float(f"{v:.9g}")
    return v


@contextmanager
def open_adapters(registry: AdapterRegistry, names: Iterable[str]) -> Iterator[dict[str, Adapter]]:
    """Construct each named adapter once (this is where renderers get imported) and close them all."""
    adapters: dict[str, Adapter] = {}
    try:
        for name in dict.fromkeys(names):
            adapters[name] = registry.create(name)
        yield adapters
    finally:
        for a in adapters.values():
            a.close()


def run(job: Job, registry: AdapterRegistry, adapters: dict[str, Adapter], progress: ProgressFn | None = None) -> Outcome:
    """Render the source (full, lobes, a second seed for the noise floor) and fit the target."""
    t0 = time.perf_counter()
    src_cache, tgt_cache = RenderCache(), RenderCache()
    src = _CachedRenderer(adapters[job.source.adapter], job.source.adapter, job.source.model, job.scene, src_cache)
    tgt = _CachedRenderer(adapters[job.target_adapter], job.target_adapter, job.target_model, job.scene, tgt_cache)
    if progress:
        progress("source", 0, float("nan"))
    source_image, lobes = _source_images(job, src, job.scene)
    source_noise = relative_rmse(source_image, src(job.source_params, scene=job.scene.with_(seed=job.scene.seed + 1)))
    opts = job.options
    # Source noise only here (the target's is measured at the end): two renders of one
    # material differ by `source_noise`, so matching closer than a third of it is noise.
    opts = replace(opts, threshold=max(opts.threshold, 2.0 * source_noise),
                   good_enough=max(opts.good_enough, source_noise / 3))
    coarse = polish = None
    if opts.coarse_resolution and 2 * opts.coarse_resolution <= job.scene.resolution:
        coarse = _level(job, src, tgt, job.scene.with_(resolution=opts.coarse_resolution))
        if opts.polish_resolution and 2 * opts.polish_resolution <= job.scene.resolution:
            polish = _level(job, src, tgt, job.scene.with_(resolution=opts.polish_resolution))
    start = informed_start(job, adapters) if opts.informed_start else {}
    result = remap(job.target_spec, tgt, source_image, lobes, base={**job.base, **start}, free=job.free,
                   options=opts, progress=progress, coarse=coarse, polish=polish)
    if opts.precise_spp > 1 and job.free and result.relative_rmse < opts.precise_below * source_noise:
        result = _precise_polish(job, src, tgt, result, source_image, source_noise, opts, progress)
    # The error two renders of the same material show, source and target noise combined:
    # n_x is the difference of two seeds (√2 σ_x), so the floor is sqrt((n_s² + n_t²) / 2).
    target_noise = relative_rmse(result.target_image, tgt(result.params, scene=job.scene.with_(seed=job.scene.seed + 1)))
    _renderer_notes(result, adapters[job.target_adapter].notes(job.target_model, result.params))
    # Renders the target adapter actually made: the engine's count includes repeats the cache served.
    result.renders = tgt_cache.misses
    noise_floor = math.sqrt((source_noise**2 + target_noise**2) / 2)
    result.seconds = time.perf_counter() - t0
    info = {n: {"plugin": registry.get(n).plugin, **a.describe()} for n, a in adapters.items()}
    return Outcome(job, result, source_image, noise_floor, src_cache.misses, info,
                   noise={"source": source_noise, "target": target_noise},
                   renders_by_resolution=_by_resolution(tgt.by_resolution, job.scene.spp), start=start)


def _by_resolution(counts: dict[tuple[int, int], int], spp: int) -> dict[str, int]:
    return {f"{res}px" + ("" if n == spp else f"@{n}spp"): v for (res, n), v in sorted(counts.items())}


def _precise_polish(job: Job, src: _CachedRenderer, tgt: _CachedRenderer, result: RemapResult,
                    source_image: np.ndarray, source_noise: float, opts: RemapOptions,
                    progress: ProgressFn | None) -> RemapResult:
    """The fit ended within a few times the render noise: what is left is noise, which more
    samples halve (4×) where more iterations cannot. One short one-stage polish of every free
    parameter from the result, source and target at ``precise_spp`` times the samples; kept if
    it lowers the error there. The result's error is still measured at the scene's sampling."""
    scene = job.scene.with_(spp=job.scene.spp * opts.precise_spp)
    source = src(job.source_params, scene=scene)
    jac = ParamSpace(job.target_spec, result.params, job.free).jacobian_renders(opts.separable_rgb)
    popts = replace(opts, scheme="one", starts=1, coarse_resolution=None, polish_resolution=None, start_margin=0.0,
                    joint_rounds=0, good_enough=0.0, max_renders_per_stage=1 + jac + opts.fine_steps)
    fine = remap(job.target_spec, _LevelRenderer(tgt, scene), source, {}, base=result.params, free=job.free,
                 options=popts, progress=progress)
    before = fine.stages[0].start_error
    if not fine.relative_rmse < before:
        return result
    final = tgt(fine.params)
    note = (f"noise-limited (error {result.relative_rmse:.2%}, within {opts.precise_below:g}x the source's render noise "
            f"{source_noise:.2%}): polished at {scene.spp} spp, {before:.3%} -> {fine.relative_rmse:.3%} there")
    for stage in fine.stages:
        stage.name = f"precise@{scene.spp}spp"
        if stage.status.startswith("stopped at the render budget"):
            stage.status = f"converged (polished from the fit in {stage.renders} renders)"
    return replace(result, params=fine.params, relative_rmse=relative_rmse(source_image, final),
                   perceptual=delta_e_itp(source_image, final), target_image=final,
                   stages=result.stages + fine.stages, notes=result.notes + [note])


def informed_start(job: Job, adapters: dict[str, Adapter]) -> dict[str, Value]:
    """The exporters' conversion of the source into the target's fitted parameters (clipped to
    their bounds), or {} when either adapter has no neutral reading for its model. A value of
    the wrong shape or not finite is left out: the start is a hint, the fit does not need it."""
    look = adapters[job.source.adapter].appearance(job.source.model, job.source_params)
    if look is None:
        return {}
    conv = adapters[job.target_adapter].from_appearance(job.target_model, look, dict(job.base))
    out: dict[str, Value] = {}
    for name in job.free:
        try:
            v = job.target_spec.param(name).clip(conv[name])
        except (KeyError, TypeError, ValueError):
            continue
        if all(map(math.isfinite, v if isinstance(v, tuple) else (v,))):  # type: ignore[arg-type]
            out[name] = v
    return out


def _renderer_notes(result: RemapResult, notes: list[str]) -> None:
    """The renderer altered the fitted parameters (trimmed them): the values do not mean what they say."""
    if not notes:
        return
    result.notes = list(notes) + list(result.notes)
    why = "the renderer trims the fitted parameters (" + notes[0].split(":")[0] + ")"
    result.reason = why if result.reliable else f"{result.reason}; {why}"
    result.reliable = False
    result.verdict = "unreliable"


def _finite_or_none(x: float | None) -> float | None:
    return x if x is not None and math.isfinite(x) else None


def _level(job: Job, src: _CachedRenderer, tgt: _CachedRenderer, scene: ProbeScene) -> Level:
    full, lobes = _source_images(job, src, scene)
    return Level(_LevelRenderer(tgt, scene), full, lobes)


def _source_images(job: Job, src: _CachedRenderer, scene: ProbeScene):
    """The source's full image and its lobes (None: cannot isolate; zeros: has no such lobe).
    The lobes come first: an adapter whose render yields every lobe at once (Cycles' passes)
    then serves the full image from it, where a full image alone is rendered without them."""
    specs = {lobe: job.source_spec.lobes.get(lobe) for lobe in ("diffuse", "specular")}
    rendered = {lobe: src(job.source_params, lobe, scene=scene)
                for lobe, spec in specs.items() if spec is not None and not spec.empty}
    full = src(job.source_params, scene=scene)
    lobes: dict[str, np.ndarray | None] = {
        lobe: None if spec is None else np.zeros_like(full) if spec.empty else rendered[lobe]
        for lobe, spec in specs.items()}
    return full, lobes


def _jsonable(v: Value) -> Any:
    return list(v) if isinstance(v, tuple) else v


def result_document(outcome: Outcome) -> dict[str, Any]:
    job, r = outcome.job, outcome.result
    return {
        "source": {
            "file": job.source_file,
            "adapter": job.source.adapter,
            "model": job.source.model,
            "params": {k: _jsonable(v) for k, v in job.source_spec.active(job.source_params).items()},
        },
        "target": {"adapter": job.target_adapter, "model": job.target_model},
        "params": {k: _jsonable(v) for k, v in job.target_spec.active(r.params).items()},
        "fitted": r.fitted,
        "fixed": {k: _jsonable(v) for k, v in job.fixed.items()},
        "metrics": {
            "relative_rmse": r.relative_rmse,
            "perceptual": r.perceptual,
            "perceptual_metric": "mean ΔE_ITP over the object (1 ≈ just noticeable)",
            "noise_floor": outcome.noise_floor,
            "noise_floor_definition": "relative RMSE expected between two renders of one material "
                                      "(source and target noise, each from a second seed)",
            "noise_source": outcome.noise.get("source"),
            "noise_target": outcome.noise.get("target"),
            "jacobian_condition": _finite_or_none(r.jacobian_condition),
        },
        "start": {"informed": bool(outcome.start),
                  "params": {k: _jsonable(_round(v)) for k, v in outcome.start.items()}},
        "renders": r.renders,
        "renders_by_resolution": dict(outcome.renders_by_resolution),
        "source_renders": outcome.source_renders,
        "seconds": r.seconds,
        "scheme": r.scheme,
        "scheme_used": r.scheme_used,
        "reliable": r.reliable,
        "verdict": r.verdict,
        "reason": r.reason,
        "notes": r.notes,
        "stages": [
            {"name": s.name, "lobe": s.lobe, "fitted": s.free, "renders": s.renders, "start_error": s.start_error,
             "error": s.error, "status": s.status, "seconds": s.seconds, "jacobians": s.jacobians,
             "jacobian_updates": s.updates}
            for s in r.stages
        ],
        "scene": json.loads(job.scene.model_dump_json()),
        "options": {k: getattr(job.options, k) for k in job.options.__dataclass_fields__},
        "engine": ENGINE,
        "adapters": outcome.adapters,
        "host": {"python": platform.python_version(), "machine": platform.machine()},
    }


def write_outputs(outcome: Outcome, out_dir: Path, target_adapter: Adapter | None = None) -> list[Path]:
    """Images first, native material next, result.json last: a result.json always describes a complete run."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    # A result.json from an earlier run must not vouch for the images about to be replaced.
    (out_dir / "result.json").unlink(missing_ok=True)
    src, tgt = outcome.source_image, outcome.result.target_image
    write_exr(out_dir / "source.exr", src)
    write_exr(out_dir / "target.exr", tgt)
    write_previews(out_dir, src, tgt, error_map(src, tgt))
    files = [out_dir / n for n in ("source.exr", "target.exr", "source.png", "target.png", "error.png")]
    if target_adapter is not None:
        files += target_adapter.write_native(outcome.job.target_model, outcome.result.params, out_dir)
    doc = result_document(outcome)
    doc["files"] = [p.name for p in files]
    write_json_atomic(out_dir / "result.json", doc)
    return files + [out_dir / "result.json"]
