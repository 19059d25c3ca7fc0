"""Shared helpers for benchmark scripts: run one remap through the library and return its figures."""

from __future__ import annotations

import statistics
from contextlib import contextmanager
from pathlib import Path
from types import SimpleNamespace

from brdfremap.core.engine import Tuning
from brdfremap.core.job.execute import AdapterPool, Outcome, execute
from brdfremap.core.job.job import Job, Target, resolve
from brdfremap.core.host.plugins import collect_adapters
from brdfremap.core.data.scene import ProbeScene
from brdfremap.core.data.schemas import Material, load_material, parse_fix
from brdfremap.core.data.settings import Settings

ROOT = Path(__file__).resolve().parents[1]


def split_options(options: dict) -> tuple[Settings, Tuning]:
    """Benchmark knobs by name: each is a field of `Settings` (what users choose) or of the
    engine's `Tuning`; an unknown name is an error."""
    unknown = set(options) - set(Settings.model_fields) - set(Tuning.model_fields)
    if unknown:
        raise SystemExit(f"unknown option(s) {sorted(unknown)}: see core/data/settings.py and core/engine/tuning.py")
    return (Settings(**{k: v for k, v in options.items() if k in Settings.model_fields}),
            Tuning(**{k: v for k, v in options.items() if k in Tuning.model_fields}))


def job_for(registry, source: Material | str, adapter: str, model: str, *, fix=(), scene=None, **options) -> Job:
    src = load_material(ROOT / source) if isinstance(source, str) else source
    spec = registry.get(adapter).models[model]
    fixed = dict(parse_fix(f, spec) for f in fix)
    settings, tuning = split_options(options)
    job = Job(source=src, target=Target(adapter=adapter, model=model, fix=fixed), scene=scene or ProbeScene(),
              settings=settings, tuning=tuning, label=str(source) if isinstance(source, str) else src.name)
    return resolve(job, registry).job


def remap_once(registry, adapters: AdapterPool, source: Material | str, adapter: str, model: str, *, fix=(),
               scene=None, **options) -> Outcome:
    """One remap in this process with ``adapters`` (kept warm across calls); nothing written."""
    job = job_for(registry, source, adapter, model, fix=fix, scene=scene, **options)
    return execute(resolve(job, registry), adapters)


@contextmanager
def open_adapters(registry, names):
    """The named adapters, started now (renderers imported, workers up) and closed at the end."""
    pool = AdapterPool(registry)
    try:
        for n in names:
            pool[n]
        yield pool
    finally:
        pool.close()


def figures(report):
    """The figures of one report the tables show, flat."""
    m = report.metrics
    return SimpleNamespace(relative_rmse=m.relative_rmse, perceptual=m.perceptual, renders=report.renders,
                           seconds=report.seconds, reliable=report.reliable, reason=report.reason,
                           params=report.params, fitted=report.fitted)


def median(xs):
    return statistics.median(xs) if xs else float("nan")


def registry():
    """Installed adapters plus the shipped external-renderer definitions (whatever the cwd)."""
    reg = collect_adapters()
    for path in sorted((ROOT / "configs" / "renderers").glob("*.yaml")):
        reg.resolve(str(path))
    return reg
