"""A textured material through a table against the same texels fitted one by one.

    python bench/textured.py TABLE --out DIR [--size 8] [--jobs 2] [--seed 5]

A SIZE x SIZE texture of distinct source materials (drawn inside the table's range, nearest
filtering: each texel one material) is remapped two ways: through the table (every texel at once),
and by a direct fit of each texel's uniform material (SIZE² ordinary jobs, stored in DIR: an
interrupted run resumes). Both target texture sets are rendered on the probe sphere by the target's
renderer and compared with the textured source rendered by its own, under the table's scene
lights and under the studio environment (the textured check's two conditions, `core.job.texturing`).
Prints each error with its noise floor, and the per-texel errors of the uniform materials."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("table")
    p.add_argument("--out", default="out/bench-textured")
    p.add_argument("--size", type=int, default=8)
    p.add_argument("--jobs", type=int, default=2)
    p.add_argument("--seed", type=int, default=5)
    args = p.parse_args()

    from brdfremap.core.job.execute import adapter_pool
    from brdfremap.core.run.executors import workers
    from brdfremap.core.host.plugins import collect_adapters
    from brdfremap.core.tables import TableMap, read_table

    t0 = time.perf_counter()
    table = read_table(args.table)
    tmap = TableMap(table)
    registry = collect_adapters()
    n = args.size
    drawn, held = _drawn(table, registry, n * n, args.seed)
    with workers(args.jobs) as w, adapter_pool(registry) as adapters:
        fits, looked = _fit_each_texel(table, tmap, registry, w, adapters, drawn, args.out)
        src_maps = _source_maps(table, drawn, n)
        table_maps, fitted_maps, seconds = _target_maps(table, tmap, registry, src_maps, fits, n)
        rows = _render_and_compare(table, adapters, registry, src_maps, table_maps, fitted_maps)
    if held:
        print(f"held         {', '.join(f'{k} {np.round(v, 3).tolist()}' for k, v in held.items())} in every texel "
              f"(the source renderer's {table.spec.source.model} takes them as numbers only)")
    _print(table, tmap, n, rows, fits, looked, seconds, time.perf_counter() - t0)


def _drawn(table, registry, count: int, seed: int) -> tuple[list[dict], dict]:
    """The texels' source values; an axis the source renderer takes as a number only is held at its
    first drawn value in every texel."""
    drawn = table.layout.draw(count, seed)
    texturable = registry.get(table.spec.source.adapter).models[table.spec.source.model].texturable
    held = {k: drawn[0][k] for k in table.spec.axes if k not in texturable}
    if len(held) == len(table.spec.axes):
        sys.exit(f"{table.name}: the source model takes none of the axes ({', '.join(held)}) as an image")
    return [{**d, **held} for d in drawn], held


def _fit_each_texel(table, tmap, registry, w, adapters, drawn, out):
    """Each texel's uniform material fitted directly, and looked up (ordinary jobs, resumable)."""
    from brdfremap.core.job.job import Job, resolve
    from brdfremap.core.run.runner import Runner, Task
    from brdfremap.core.data.schemas import Material
    from brdfremap.core.data.settings import Validation
    from brdfremap.core.run.store import Store
    from brdfremap.core.tables.lookup import look_up

    spec = table.spec
    settings = spec.options.for_study().model_copy(update={"validation": Validation.NONE})
    tasks, lookups = [], []
    for i, values in enumerate(drawn):
        src = Material(adapter=spec.source.adapter, model=spec.source.model, params={**spec.source.params, **values},
                       name=f"t{i:03d}")
        resolved = resolve(Job(source=src, target=spec.target, scene=table.scene, settings=settings), registry)
        tasks.append(Task(f"texels/t{i:03d}", resolved, f"texel {i}"))
        lk = look_up(table, tmap, values).lookup
        lookups.append(Task(f"lookups/t{i:03d}", resolve(resolved.job.model_copy(update={"lookup": lk}), registry),
                            f"lookup {i}"))
    done = Runner(Store(out), w, adapters, quiet=True, stop_on_error=False).run(tasks + lookups)
    return done[:len(drawn)], done[len(drawn):]


def _source_maps(table, drawn, n):
    """The source's maps (texel i at row i // n, column i % n)."""
    out = {}
    for name in table.spec.axes:  # a held axis is a constant map (the table's remap reads it so)
        v = np.array([d[name] for d in drawn], np.float32)
        out[name] = v.reshape(n, n, 3) if v.ndim == 2 else v.reshape(n, n)
    return out


def _target_maps(table, tmap, registry, src_maps, fits, n):
    """The target's maps through the table, and of the per-texel fits."""
    from brdfremap.core.tables.texels import Inputs, remap_texels

    tgt_spec = registry.get(table.spec.target.adapter).models[table.spec.target.model]
    inputs = Inputs({k: v.reshape(n * n, -1).squeeze() for k, v in src_maps.items()}, n, n, list(table.spec.axes))
    through = remap_texels(table, tmap, inputs)
    table_maps = {**through.maps, **{k: _full(v, n, tgt_spec.param(k).kind) for k, v in through.constants.items()}}
    fitted_maps = {}
    for name in table_maps:
        vals = np.array([f.report.params.get(name, table.target_params[name]) for f in fits], np.float32)
        fitted_maps[name] = vals.reshape(n, n, 3) if vals.ndim == 2 else vals.reshape(n, n)
    return table_maps, fitted_maps, through.seconds


def _render_and_compare(table, adapters, registry, src_maps, table_maps, fitted_maps):
    """Both target texture sets and the source's, each by its renderer, under the check's conditions."""
    from brdfremap.core.data.metrics import relative_rmse

    spec = table.spec
    tgt_spec = registry.get(spec.target.adapter).models[spec.target.model]
    src_spec = registry.get(spec.source.adapter).models[spec.source.model]
    texturable = [k for k in table_maps if k in tgt_spec.texturable]
    rows = []
    for condition, sc in _conditions(table.scene):
        src_img, src_noise = _pair(adapters[spec.source.adapter], spec.source.model,
                                   {**table.source_params, **_means(src_maps)},
                                   {k: v for k, v in src_maps.items() if k in src_spec.texturable}, sc, 0)
        for label, maps in (("through the table", table_maps), ("each texel fitted", fitted_maps)):
            tgt_img, tgt_noise = _pair(adapters[spec.target.adapter], spec.target.model,
                                       {**table.target_params, **_means(maps)},  # a number-only input: its mean
                                       {k: maps[k] for k in texturable}, sc, 2)
            rows.append((condition, label, relative_rmse(src_img, tgt_img), float(np.hypot(src_noise, tgt_noise))))
    return rows


def _print(table, tmap, n, rows, fits, looked, seconds, wall) -> None:
    fit_err = np.array([f.report.metrics.relative_rmse for f in fits])
    look_err = np.array([d.report.metrics.relative_rmse for d in looked])
    print(f"table          {table.name} ({tmap.method} map)")
    print(f"texture        {n} x {n} texels, each a distinct material drawn in the table's range (nearest filter)")
    print(f"{'condition':<14} {'target maps':<20} {'error':>8} {'noise':>8}")
    for condition, label, err, noise in rows:
        print(f"{condition:<14} {label:<20} {err:>8.2%} {noise:>8.2%}")
    ratio = look_err / fit_err
    print(f"uniform        each texel's material alone: direct fits median {np.median(fit_err):.2%}, lookups median "
          f"{np.median(look_err):.2%}; lookup / fit median {np.median(ratio):.3f}, 95th percentile "
          f"{np.percentile(ratio, 95):.3f}")
    print(f"cost           {sum(f.report.renders for f in fits)} target renders for the {n * n} fits "
          f"({sum(f.report.seconds for f in fits):.0f} s of fits), the table's remap {seconds * 1e3:.1f} ms; "
          f"{wall:.0f} s in all")


def _full(v, n: int, kind: str) -> np.ndarray:
    return np.full((n, n, 3) if kind == "rgb" else (n, n), v, np.float32)


def _means(maps: dict) -> dict:
    return {k: (tuple(float(x) for x in v.reshape(-1, 3).mean(0)) if v.ndim == 3 else float(v.mean()))
            for k, v in maps.items()}


def _conditions(scene):
    from brdfremap.core.data.scene import EnvironmentLight
    from brdfremap.core.job.texturing import CHECK_RESOLUTION, CHECK_SPP

    first = scene.view_scenes()[0]
    spp = max(CHECK_SPP, scene.spp * 4)
    base = first.with_(resolution=max(CHECK_RESOLUTION, first.resolution), spp=spp)
    studio = base.model_copy(update={"lights": [EnvironmentLight(type="environment", map="studio")], "spp": 4 * spp})
    return [("scene", base), ("environment", studio)]


def _pair(adapter, model, params, maps, scene, offset):
    from brdfremap.core.data.metrics import relative_rmse
    from brdfremap.core.data.textures import TextureMap

    tm = {k: TextureMap(np.ascontiguousarray(v, np.float32), "nearest") for k, v in maps.items()}
    a, b = (adapter.render_textured(model, dict(params), tm, scene.with_(seed=scene.seed + offset + k))
            for k in (0, 1))
    return (a + b) / 2, relative_rmse(a, b) / 2


if __name__ == "__main__":
    sys.exit(main())
