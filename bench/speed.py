"""Remap speed and quality against the baselines, measured side by side in one run.

    python bench/speed.py [--quick] [--subset] [--out docs/measurements/speed-bench.md]

For each case (a source material and a target model):
  paper     the paper-faithful baseline: one-stage TRF at 512² from the target's defaults, a
            finite-difference Jacobian every iteration
  analytic  today's exporters: fixed formulas (identity α, and α = roughness²); no renders
  floor     the best achievable: one-stage TRF from 8 starts (the target's defaults and a spread) at
            128², 64 spp, a finite-difference Jacobian every iteration
  default   brdf-remap's default (scheme auto: two-stage where the target's lobes divide its
            parameters, else one-stage; 4 starts, the first the exporters' conversion; most iterations at 32 px, polished at the
            scene's 128², 16 spp, and at 64 spp when the fit ends within 3x the render noise;
            Jacobians updated from the steps (Broyden) between rendered ones)
  default, ...   (--subset, --quick) the default with one speed-up undone, to measure it:
            starts from the target's defaults (not the conversion), no polish at more samples, unscaled starts (no per-start scale of a reflectance its lobe is proportional to),
            no Jacobian updates, polish at 64 px, the two-stage scheme, a polish of every parameter
            (none held as settled by the coarse fit), and the joint refinement of two-stage results as it was (one round, 0.5-point trigger)
Every method's parameters are scored on one evaluation render (128², 64 spp, seed 7) against
the source rendered alike, so the errors are comparable; renders and seconds are the
method's own, in a warm process (one untimed remap per target adapter first). Ratios are
printed per case and as medians."""

from __future__ import annotations

import argparse
import hashlib
import json
import time
from pathlib import Path

import baselines
from common import ROOT, median, open_adapters, registry, remap_once

from brdfremap.core.data.atomic import write_json_atomic, write_text_atomic
from brdfremap.core.data.metrics import delta_e_itp, relative_rmse
from brdfremap.core.data.scene import ProbeScene
from brdfremap.core.data.schemas import Material, parse_fix

EVAL = ProbeScene(resolution=128, spp=64, seed=7)
DEFAULT = ProbeScene()
PAPER = ProbeScene(resolution=512)
FLOOR = ProbeScene(spp=64)


def conductor(preset, alpha):
    return Material(adapter="mitsuba", model="roughconductor", name=f"{preset} β α={alpha:g}",
                    params={"distribution": "beckmann", "material": preset, "alpha": alpha})


def plastic(colour, rgb, alpha, ior):
    return Material(adapter="mitsuba", model="roughplastic", name=f"{colour} plastic α={alpha:g} η={ior:g}",
                    params={"distribution": "beckmann", "diffuse_reflectance": rgb, "alpha": alpha, "int_ior": ior})


COLOURS = {"blue": [0.05, 0.15, 0.6], "red": [0.6, 0.08, 0.05], "grey": [0.5, 0.5, 0.5]}
# A Latin square over colour x alpha x IOR: every value of each appears once per row and column.
PLASTICS = [plastic(c, COLOURS[c], a, i) for c, a, i in (
    ("blue", 0.05, 1.3), ("blue", 0.2, 1.5), ("blue", 0.5, 1.7), ("red", 0.05, 1.5), ("red", 0.2, 1.7),
    ("red", 0.5, 1.3), ("grey", 0.05, 1.7), ("grey", 0.2, 1.3), ("grey", 0.5, 1.5))]
CONDUCTORS = [conductor(p, a) for p in ("Au", "Ag", "Cu", "Al", "Cr") for a in (0.05, 0.1, 0.2, 0.4)]
TARGETS = {"roughconductor": ["cycles:principled", "cycles:glossy:beckmann", "mitsuba:roughconductor:ggx"],
           "roughplastic": ["cycles:principled", "mitsuba:roughplastic:ggx"]}


def cases(which: str):
    if which == "quick":
        # Mitsuba targets only: a Cycles case takes minutes (the paper baseline renders at 512²).
        srcs = [conductor("Au", 0.1), conductor("Cr", 0.4), PLASTICS[1]]
        return [(s, t) for s in srcs for t in TARGETS[s.model] if t.startswith("mitsuba")]
    if which == "subset":
        srcs = [conductor("Au", 0.1), conductor("Cr", 0.4), PLASTICS[1]]
        return [(s, t) for s in srcs for t in TARGETS[s.model]]
    return [(s, t) for s in CONDUCTORS + PLASTICS for t in TARGETS[s.model]]


# Cycles' paper baseline costs 1-4 minutes a case at 512²: on the full set it runs on the
# subset's cases and a few more (every preset once, both plastics' extremes of alpha).
PAPER_SAMPLE = {(f"{m} β α={a:g}", t) for m, a, t in (
    ("Au", 0.1, "cycles:principled"), ("Cr", 0.4, "cycles:principled"), ("Cu", 0.2, "cycles:principled"),
    ("Ag", 0.05, "cycles:principled"), ("Al", 0.4, "cycles:principled"),
    ("Au", 0.1, "cycles:glossy:beckmann"), ("Cr", 0.4, "cycles:glossy:beckmann"))} | \
    {(PLASTICS[i].name, "cycles:principled") for i in (1, 3)}
VARIANTS = {"default, starts from the defaults": dict(start="defaults"),
            "default, no polish at more samples": dict(precise_spp=1),
            "default, unscaled starts": dict(linear_starts=False),
            "default, no Jacobian updates": dict(jacobian_updates=0),
            "default, polish at 64 px": dict(polish_resolution=64),
            "default, two-stage": dict(scheme="two"),
            "default, polish holds nothing": dict(hold_settled=False),
            "default, one joint round, 0.5-point trigger": dict(joint_rounds=1, joint_min_gain=0.005)}
CACHED = ("paper", "floor")
OLD_ENGINE = {"start": "defaults", "start_margin": 0.0}
LEGACY, LEGACY_VALUES = {"coarse": "coarse_resolution"}, {("coarse", 0): None}
"""Options by the names the cache's keys were first written with, so its rows stay valid."""
"""The paper's and the floor's fits start from the target's defaults as given (on a bound, if
that is where a default lies), as they did when their rows were first cached."""
CACHE_NOTE = (" Paper and floor rows come from the script's cache when it has them (a run of it with the same"
              " options, on this machine): the paper's ran alone; the floor's seconds may include other jobs, and a"
              " cached row keeps the seconds of the code that made it (delete its file in the cache to redo it).")
"""Methods whose results are kept in --cache: their options are fixed here, so a rerun after a
change to the default reuses them (the default and its variants always run)."""


def evaluate(reg, adapters, src: Material, target: str, params: dict):
    """Error of ``params`` on the evaluation scene (not counted as the method's renders)."""
    adapter, model, *_ = target.split(":")
    src_spec = reg.get(src.adapter).models[src.model]
    spec = reg.get(adapter).models[model]
    s_img = adapters[src.adapter].render(src.model, src_spec.complete(src.params), EVAL)
    t_img = adapters[adapter].render(model, spec.complete(params), EVAL)
    return relative_rmse(s_img, t_img), delta_e_itp(s_img, t_img)


def run_case(reg, adapters, src, target, *, paper=True, variants=True, cache: Path | None = None, methods=None,
             tries=()):
    adapter, model, *dist = target.split(":")
    fix = [f"distribution={dist[0]}"] if dist else []
    if model in ("roughconductor",) and src.model == "roughconductor":
        fix.append(f"material={src.params['material']}")
    rows = {}

    def fitted(label, scene, **options):
        if methods is not None and label not in methods:
            return
        # Options that reproduce the engine as it was before they existed stay out of the key, so the
        # rows cached before them remain valid (they were made exactly so).
        keyed = {LEGACY.get(k, k): LEGACY_VALUES.get((k, v), v) for k, v in options.items()
                 if (k, v) not in OLD_ENGINE.items()}
        key = json.dumps([src.name, src.params, target, fix, label, scene.model_dump(), keyed], sort_keys=True)
        path = cache / f"{hashlib.sha256(key.encode()).hexdigest()[:20]}.json" if cache and label in CACHED else None
        if path is not None and path.exists():
            rows[label] = json.loads(path.read_text())["row"]
            return
        t0 = time.perf_counter()
        o = remap_once(reg, adapters, src, adapter, model, fix=fix, scene=scene, **options)
        secs = time.perf_counter() - t0
        err, de = evaluate(reg, adapters, src, target, o.report.params)
        rows[label] = dict(renders=o.report.renders, seconds=secs, err=err, de=de, reliable=o.report.reliable)
        if path is not None:
            write_json_atomic(path, {"key": json.loads(key), "row": rows[label]})

    if paper:
        fitted("paper", PAPER, scheme="one", starts=1, coarse=0, jacobian_updates=0,
               linear_starts=False, fit_scene="one-view", **OLD_ENGINE)  # the paper's probe alone
    for conv in ("identity", "squared") if methods is None or "analytic" in methods else ():
        p = baselines.convert(src.model, src.params, target, conv)
        if p is not None:
            spec = reg.get(adapter).models[model]
            p = {**{k: v for k, v in spec.complete({}).items()}, **dict(parse_fix(f, spec) for f in fix), **p}
            err, de = evaluate(reg, adapters, src, target, p)
            rows[f"analytic {conv}"] = dict(renders=0, seconds=0.0, err=err, de=de, reliable=None)
    fitted("floor", FLOOR, scheme="one", starts=8, coarse=0, max_renders_per_stage=160,
           jacobian_updates=0, **OLD_ENGINE)
    fitted("default", DEFAULT)
    if variants:
        for label, opts in VARIANTS.items():
            fitted(label, DEFAULT, **opts)
    for label, opts in tries:
        fitted(label, DEFAULT, **opts)
    return rows


def main():
    ap = argparse.ArgumentParser()
    g = ap.add_mutually_exclusive_group()
    g.add_argument("--quick", action="store_true", help="the Mitsuba -> Mitsuba cases of the subset, under two minutes")
    g.add_argument("--subset", action="store_true", help="Au α 0.1, Cr α 0.4 and a blue plastic to every target (8 cases)")
    ap.add_argument("--out", default=None, help="write the table as Markdown here")
    ap.add_argument("--cache", default=str(ROOT / "out" / "bench-speed"),
                    help="folder keeping the paper and floor results (fixed options), reused by a rerun; '' for none")
    ap.add_argument("--methods", default=None, help="comma-separated methods to run (e.g. paper,floor); default all")
    ap.add_argument("--try", dest="tries", action="append", default=[], metavar="KEY=VALUE[,KEY=VALUE]",
                    help="add a row: the default with these engine options changed (repeatable)")
    ap.add_argument("--only", default=None, metavar="TEXT[,TEXT]",
                    help="only the cases whose 'name target' contains one of these (e.g. 'principled')")
    args = ap.parse_args()
    tries = [(f"default, {t}", {k: _value(v) for k, v in (kv.split("=", 1) for kv in t.split(","))})
             for t in args.tries]
    which = "quick" if args.quick else "subset" if args.subset else "full"
    methods = set(args.methods.split(",")) if args.methods else None
    cache = Path(args.cache) if args.cache else None
    if cache:
        cache.mkdir(parents=True, exist_ok=True)
    reg = registry()
    head = "| case | target | method | renders | seconds | rel. RMSE | ΔE_ITP | × paper time | × floor error |"
    lines = [head, "|---|---|---|---:|---:|---:|---:|---:|---:|"]
    print("\n".join(lines), flush=True)
    summary = []
    t_all = time.perf_counter()
    with open_adapters(reg, ["mitsuba", "cycles"]) as adapters:
        chosen = [(src, target) for src, target in cases(which)
                  if not args.only or any(t in f"{src.name} {target}" for t in args.only.split(","))]
        # Warm-up, not timed: the first remap on each target adapter pays its start-up (Blender's
        # workers, Mitsuba's first kernel compilations: 0.8 s against 0.2 s for the same case).
        for first in {t.split(":")[0]: (s, t) for s, t in reversed(chosen)}.values():
            adapter, model, *dist = first[1].split(":")
            remap_once(reg, adapters, first[0], adapter, model, fix=[f"distribution={d}" for d in dist])
        for src, target in chosen:
            paper = which != "full" or target.startswith("mitsuba") or (src.name, target) in PAPER_SAMPLE
            rows = run_case(reg, adapters, src, target, paper=paper, variants=which != "full", cache=cache,
                            methods=methods and methods | {label for label, _ in tries}, tries=tries)
            paper_s = rows.get("paper", {}).get("seconds")
            floor_e = rows.get("floor", {}).get("err")
            for label, r in rows.items():
                speed = (f"{paper_s / r['seconds']:.1f}× faster" if r["seconds"] and paper_s else
                         "no renders" if not r["seconds"] else "")
                vs_floor = f"{r['err'] / max(floor_e, 1e-9):.2f}" if floor_e is not None else ""
                line = (f"| {src.name} | {target} | {label} | {r['renders']} | {r['seconds']:.2f} | {r['err']:.2%} | "
                        f"{r['de']:.2f} | {speed} | {vs_floor} |")
                lines.append(line)
                print(line, flush=True)
            summary.append((src, target, rows))
    med = summarise(summary)
    print("\n".join(med))
    print(f"\ntotal {time.perf_counter() - t_all:.0f} s")
    if args.out:
        note = ("" if which != "full" else
                f" The paper baseline ran on every Mitsuba case and on {len(PAPER_SAMPLE)} sampled Cycles cases "
                "(PAPER_SAMPLE in the script: at 512² it costs 1-4 minutes a case); its speed-ups are over those.")
        doc = [f"# Remap speed and quality against the baselines ({which} set)", "",
               f"Produced by `python bench/speed.py{' --' + which if which != 'full' else ''}`; see the script's "
               "docstring for the methods. Errors are on one evaluation render (128², 64 spp)." + note + CACHE_NOTE,
               *med, "",
               *lines, ""]
        write_text_atomic(Path(args.out), "\n".join(doc))


def _value(text: str):
    for cast in (int, float):
        try:
            return cast(text)
        except ValueError:
            pass
    return {"true": True, "false": False, "none": None}.get(text.lower(), text)


def summarise(summary) -> list[str]:
    med = ["", "| target | method | cases | median renders | median seconds | median rel. RMSE | "
           "median speed-up vs paper | median error / floor | default within 5% of floor | "
           "default ≥3× better than best analytic |",
           "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    labels = ("paper", "analytic identity", "analytic squared", "floor", "default", *VARIANTS)
    for target in [*dict.fromkeys(t for _, t, _ in summary), "all"]:
        group = [rows for _, t, rows in summary if t == target or target == "all"]
        for label in [*labels, *dict.fromkeys(k for _, _, rows in summary for k in rows if k not in labels)]:
            rs = [g[label] for g in group if label in g]
            if not rs or (target == "all" and label != "default"):
                continue
            timed = [g["paper"]["seconds"] / g[label]["seconds"] for g in group
                     if label in g and "paper" in g and g[label]["seconds"]]
            speed = f"{median(timed):.1f} (n={len(timed)})" if timed and not label.startswith("analytic") else ""
            with_floor = [g for g in group if label in g and "floor" in g]
            ratio = median([g[label]["err"] / max(g["floor"]["err"], 1e-9) for g in with_floor])
            within = better = ""
            if label == "default" and with_floor:
                within = (f"{sum(g['default']['err'] <= 1.05 * g['floor']['err'] + 1e-4 for g in with_floor)}"
                          f"/{len(with_floor)}")
                pairs = [(min(g[k]["err"] for k in g if k.startswith("analytic")), g) for g in group
                         if "default" in g and any(k.startswith("analytic") for k in g)]
                if pairs:
                    better = f"{sum(b >= 3 * g['default']['err'] for b, g in pairs)}/{len(pairs)}"
            med.append(f"| {target} | {label} | {len(rs)} | {median([r['renders'] for r in rs]):.0f} | "
                       f"{median([r['seconds'] for r in rs]):.2f} | {median([r['err'] for r in rs]):.2%} | "
                       f"{speed} | {ratio:.2f} | {within} | {better} |")
    return med


if __name__ == "__main__":
    main()
