"""Remap tables: how close a lookup comes to a direct fit, how fast lookups are, and what a build costs.

    python bench/tables.py accuracy TABLE... --out DIR [--n 50] [--jobs 2] [--maps rbf,rbf+colours]
    python bench/tables.py speed TABLE [--size 2048]
    python bench/tables.py builds TABLE...

accuracy: for each table, ``n`` source materials drawn at random inside its range (a Sobol' draw of
another seed than the table's own held-out set, colours not grey) are fitted directly and looked up
through the table, both as ordinary jobs (stored in DIR: an interrupted run resumes) with the
table's scene and settings, held-out lights off (the fit's error is what is compared); with the
table's chosen map, or each of `--maps`. Prints the
median and 95th percentile of lookup error / direct fit error, and the errors themselves.

speed: one material's lookup (the map's evaluation, warm; and reading the table), and a texture set
of SIZE² texels per input, written as 16-bit PNGs, read, remapped texel by texel and its maps encoded
(each step timed; the remap itself is the `--size` figure).

builds: each table's grid, fits, flagged points, renders and wall time as its build recorded them."""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
ACCURACY_SEED = 1000


def accuracy(args) -> None:
    from brdfremap.core.job.execute import adapter_pool
    from brdfremap.core.run.executors import workers
    from brdfremap.core.job.job import Job, resolve
    from brdfremap.core.host.plugins import collect_adapters
    from brdfremap.core.run.runner import Runner, Task
    from brdfremap.core.data.schemas import Material
    from brdfremap.core.data.settings import Validation
    from brdfremap.core.run.store import Store
    from brdfremap.core.tables import TableMap, read_table
    from brdfremap.core.tables.lookup import look_up

    registry = collect_adapters()
    rows, tails = [], []
    with workers(args.jobs) as w, adapter_pool(registry) as adapters:
        for path in args.tables:
            t0 = time.perf_counter()
            table = read_table(path)
            spec = table.spec
            settings = spec.options.for_study().model_copy(update={"validation": Validation.NONE})
            drawn = table.layout.draw(args.n, args.seed)
            store = Store(Path(args.out) / Path(path).resolve().name)
            jobs = [Job(source=Material(adapter=spec.source.adapter, model=spec.source.model,
                                        params={**spec.source.params, **values}, name=f"r{i:03d}"),
                        target=spec.target, scene=table.scene, settings=settings, label=f"bench r{i:03d}")
                    for i, values in enumerate(drawn)]
            direct = Runner(store, w, adapters, quiet=args.quiet, stop_on_error=False).run(
                [Task(f"direct/r{i:03d}", resolve(job, registry), f"direct r{i:03d}") for i, job in enumerate(jobs)])
            d_err = np.array([_err(d) for d in direct])
            a_err = np.array([_err(d, start=True) for d in direct])  # the exporters' conversion
            for method in (args.maps.split(",") if args.maps else [table.chosen]):
                if method not in table.candidates:
                    raise SystemExit(f"{path}: no map {method!r} (its maps: {', '.join(table.candidates)})")
                tmap = TableMap(table, method)
                lookups = [Task(f"lookup/{method}/r{i:03d}", resolve(job.model_copy(update={
                    "lookup": look_up(table, tmap, values).lookup}), registry), f"lookup r{i:03d}")
                    for i, (job, values) in enumerate(zip(jobs, drawn))]
                l_err = np.array([_err(d) for d in Runner(store, w, adapters, quiet=args.quiet,
                                                          stop_on_error=False).run(lookups)])
                ratio, analytic = l_err / d_err, a_err / d_err
                ok = np.isfinite(ratio)
                rows.append((table.name, method, int(ok.sum()), float(np.median(ratio[ok])),
                             float(np.percentile(ratio[ok], 95)), float(np.max(ratio[ok])),
                             float(np.mean(ratio[ok] <= 1.05)), float(np.nanmedian(analytic)),
                             float(np.median(d_err[ok])), float(np.median(l_err[ok])), time.perf_counter() - t0))
                tails.append((f"{table.name} ({method})", _worst(drawn, d_err, l_err)))
                t0 = time.perf_counter()
    print(f"{'table':<62} {'map':<16} {'n':>3} {'median':>7} {'p95':>6} {'max':>6} {'<=1.05':>7} {'analytic':>8} "
          f"{'direct':>7} {'lookup':>7} {'s':>6}")
    for name, method, n, med, p95, worst, frac, ana, d, lk, secs in rows:
        print(f"{name:<62} {method:<16} {n:>3} {med:>7.3f} {p95:>6.3f} {worst:>6.3f} {frac:>7.0%} {ana:>8.3f} "
              f"{d:>7.2%} {lk:>7.2%} {secs:>6.0f}")
    print("median, p95, max: lookup error / direct fit error over the drawn materials; <=1.05: the share within 5 %; "
          "analytic: the exporters' conversion's error / the direct fit's, median; direct, lookup: median relative RMSE")
    for name, lines in tails:
        print(f"worst of {name}:")
        for line in lines:
            print(f"  {line}")


def _err(done, start=False) -> float:
    m = done.report.metrics if done.report else None
    return np.nan if m is None else (m.start_error if start else m.relative_rmse) or np.nan


def _worst(drawn: list[dict], d_err: np.ndarray, l_err: np.ndarray, k: int = 3) -> list[str]:
    """The k materials whose lookups are furthest from their direct fits (ratio), with both errors."""
    ratio = l_err / d_err
    ratio = np.where(np.isfinite(ratio), ratio, -np.inf)
    lines = []
    for i in np.argsort(-ratio)[:k]:
        shown = ", ".join(f"{n} {np.round(v, 3).tolist() if np.ndim(v) else round(float(v), 3)}"
                          for n, v in drawn[i].items())
        lines.append(f"r{i:03d} ({shown}): lookup {l_err[i]:.2%} / direct {d_err[i]:.2%} = {ratio[i]:.2f}")
    return lines


def speed(args) -> None:
    from brdfremap.core.tables import TableMap, read_table
    from brdfremap.core.tables.dense import DenseMap

    t0 = time.perf_counter()
    table = read_table(args.tables[0])
    tmap = TableMap(table)
    loaded = time.perf_counter() - t0
    drawn = table.layout.draw(256, 7)
    tmap.params(drawn[0])  # warm
    t0 = time.perf_counter()
    reps = 0
    while time.perf_counter() - t0 < 2.0:
        for values in drawn:
            tmap.params(values)
        reps += len(drawn)
    per = (time.perf_counter() - t0) / reps
    print(f"table        {table.name} ({tmap.method} map, {len(table.outputs)} outputs)")
    print(f"read         {loaded * 1e3:.0f} ms (the file read, checked and its maps rebuilt)")
    print(f"one lookup   {per * 1e6:.0f} µs per material (mean of {reps}, warm)")
    t0 = time.perf_counter()
    DenseMap(tmap)
    print(f"bake         {(time.perf_counter() - t0) * 1e3:.0f} ms (the map on a fine grid, once per texture set)")
    texture_set(table, tmap, args.size)


def texture_set(table, tmap, n: int) -> None:
    """A texture set of n² texels per input, written as files, read, remapped and its maps encoded."""
    from brdfremap.core.host.plugins import collect_adapters
    from brdfremap.core.data.schemas import Material
    from brdfremap.core.tables.texels import read_inputs, remap_texels
    from brdfremap.core.data.textures import Texture, encode, kind_of_file, texture

    spec = table.spec
    src_spec = collect_adapters().get(spec.source.adapter).models[spec.source.model]
    rng = np.random.default_rng(3)
    with tempfile.TemporaryDirectory() as tmp:
        textures: dict[str, Texture] = {}
        t0 = time.perf_counter()
        for name, ax in spec.axes.items():
            p = src_spec.param(name)
            shape = (n, n, 3) if p.kind == "rgb" else (n, n)
            values = ax.sample(_smooth(rng, shape)).astype(np.float32)
            suffix, space = kind_of_file(p.lower, p.upper, p.kind == "rgb")
            f = Path(tmp) / f"{name}{suffix}"
            f.write_bytes(encode(values, suffix, space))
            textures[name] = texture(f, space)
        made = time.perf_counter() - t0
        material = Material(adapter=spec.source.adapter, model=spec.source.model, params=dict(spec.source.params),
                            textures=textures)
        t0 = time.perf_counter()
        inputs = read_inputs(table, material, src_spec)
        read = time.perf_counter() - t0
        out = remap_texels(table, tmap, inputs)
        t0 = time.perf_counter()
        written = 0
        tspec = collect_adapters().get(spec.target.adapter).models[spec.target.model]
        for name, values in out.maps.items():
            p = tspec.param(name)
            written += len(encode(values, *kind_of_file(p.lower, p.upper, p.kind == "rgb")))
        encoded = time.perf_counter() - t0
    print(f"texture set  {n} x {n}: {', '.join(f'{k} ({v.colorspace})' for k, v in textures.items())} "
          f"({made:.1f} s to make)")
    print(f"  read       {read:.2f} s (decoded to linear values through OpenColorIO)")
    print(f"  remap      {out.seconds:.2f} s for {n * n} texels ({out.seconds / (n * n) * 1e9:.0f} ns a texel; "
          f"{len(out.maps)} maps: {', '.join(out.maps)}; constant: {', '.join(out.constants) or 'none'})")
    print(f"  encode     {encoded:.2f} s ({written / 1e6:.1f} MB of 16-bit PNG / EXR)")
    print(f"  in all     {read + out.seconds + encoded:.2f} s")


def _smooth(rng, shape) -> np.ndarray:
    """Unit values that vary smoothly over the texture, as a real map does (and cover the range)."""
    n = shape[0]
    y, x = np.mgrid[0:n, 0:n] / n
    chans = shape[2] if len(shape) == 3 else 1
    out = np.stack([0.5 + 0.5 * np.sin(2 * np.pi * (x * rng.uniform(1, 4) + y * rng.uniform(1, 4))
                                       + rng.uniform(0, 6)) for _ in range(chans)], axis=-1)
    return out if len(shape) == 3 else out[..., 0]


def builds(args) -> None:
    from brdfremap.core.tables import read_table

    print(f"{'table':<62} {'points':>6} {'held':>5} {'flagged':>8} {'left out':>8} {'renders':>8} {'wall s':>7}  where")
    for path in args.tables:
        t = read_table(path)
        b = t.build
        print(f"{t.name:<62} {b.points:>6} {b.holdout:>5} {b.flagged / b.points:>8.0%} {b.left_out:>8} "
              f"{b.renders:>8} {b.wall_seconds:>7.0f}  {b.ran_in}")


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("what", choices=("accuracy", "speed", "builds"))
    p.add_argument("tables", nargs="+", metavar="TABLE")
    p.add_argument("--out", default="out/bench-tables", help="accuracy: where the fits are stored")
    p.add_argument("--n", type=int, default=50, help="accuracy: materials drawn per table")
    p.add_argument("--seed", type=int, default=ACCURACY_SEED, help="accuracy: the draw's seed (another draw checks a "
                                                                   "change made after looking at the first's worst)")
    p.add_argument("--maps", default="", help="accuracy: the table's maps to look up with, comma-separated "
                                              "(default: its chosen one)")
    p.add_argument("--jobs", type=int, default=2)
    p.add_argument("--size", type=int, default=2048, help="speed: texels across the texture set")
    p.add_argument("--quiet", action="store_true")
    args = p.parse_args()
    {"accuracy": accuracy, "speed": speed, "builds": builds}[args.what](args)


if __name__ == "__main__":
    sys.exit(main())
