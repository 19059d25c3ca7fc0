"""Shared helpers for benchmark scripts: run one remap through the library and return its figures."""

from __future__ import annotations

import statistics
from pathlib import Path

from brdfremap.core.plugins import collect_adapters
from brdfremap.core.remap import RemapOptions
from brdfremap.core.scene import ProbeScene
from brdfremap.core.schemas import Material, load_material, parse_fix
from brdfremap.core.session import prepare, run

ROOT = Path(__file__).resolve().parents[1]


def remap_once(registry, adapters, source: Material | str, adapter: str, model: str, *, fix=(), scene=None,
               **options):
    src = load_material(ROOT / source) if isinstance(source, str) else source
    spec = registry.get(adapter).models[model]
    fixed = dict(parse_fix(f, spec) for f in fix)
    job = prepare(registry, src, str(source), adapter, model, scene or ProbeScene(), fixed, RemapOptions(**options))
    return run(job, registry, adapters)


def median(xs):
    return statistics.median(xs) if xs else float("nan")


def registry():
    """Installed adapters plus the shipped external-renderer definitions (whatever the cwd)."""
    reg = collect_adapters()
    for path in sorted((ROOT / "configs" / "renderers").glob("*.yaml")):
        reg.resolve(str(path))
    return reg
