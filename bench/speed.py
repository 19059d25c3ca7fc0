"""Remap speed and quality against the baselines, measured side by side in one run.

    python bench/speed.py [--quick] [--subset] [--out docs/speed.md]

For each case (a source material and a target model):
  paper     the paper-faithful baseline: one-stage TRF at 512² from the target's defaults
  analytic  today's exporters: fixed formulas (identity α, and α = roughness²); no renders
  floor     the best achievable: one-stage TRF from 8 starts at 128², 64 spp
  default   brdf-remap's default (two-stage, coarse-to-fine, 4 starts, 128², 16 spp)
  default, unscaled starts   the same without scaling each start's linear parameter (a
            reflectance its lobe is proportional to): the measure of that speed-up
Every method's parameters are scored on one evaluation render (128², 64 spp, seed 7) against
the source rendered alike, so the errors are comparable; renders and seconds are the
method's own. Ratios are printed per case and as medians."""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import baselines
from common import median, registry, remap_once

from brdfremap.core.atomic import write_text_atomic
from brdfremap.core.metrics import delta_e_itp, relative_rmse
from brdfremap.core.scene import ProbeScene
from brdfremap.core.schemas import Material, parse_fix
from brdfremap.core.session import open_adapters

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


def evaluate(reg, adapters, src: Material, target: str, params: dict):
    """Error of ``params`` on the evaluation scene (not counted as the method's renders)."""
    adapter, model, *_ = target.split(":")
    src_spec = reg.get(src.adapter).models[src.model]
    spec = reg.get(adapter).models[model]
    s_img = adapters[src.adapter].render(src.model, src_spec.complete(src.params), EVAL)
    t_img = adapters[adapter].render(model, spec.complete(params), EVAL)
    return relative_rmse(s_img, t_img), delta_e_itp(s_img, t_img)


def run_case(reg, adapters, src, target):
    adapter, model, *dist = target.split(":")
    fix = [f"distribution={dist[0]}"] if dist else []
    if model in ("roughconductor",) and src.model == "roughconductor":
        fix.append(f"material={src.params['material']}")
    rows = {}

    def fitted(label, scene, **options):
        t0 = time.perf_counter()
        o = remap_once(reg, adapters, src, adapter, model, fix=fix, scene=scene, **options)
        secs = time.perf_counter() - t0
        err, de = evaluate(reg, adapters, src, target, o.result.params)
        rows[label] = dict(renders=o.result.renders, seconds=secs, err=err, de=de, reliable=o.result.reliable)

    fitted("paper", PAPER, scheme="one", starts=1, coarse_resolution=None)
    for conv in ("identity", "squared"):
        p = baselines.convert(src.model, src.params, target, conv)
        if p is not None:
            spec = reg.get(adapter).models[model]
            p = {**{k: v for k, v in spec.complete({}).items()}, **dict(parse_fix(f, spec) for f in fix), **p}
            err, de = evaluate(reg, adapters, src, target, p)
            rows[f"analytic {conv}"] = dict(renders=0, seconds=0.0, err=err, de=de, reliable=None)
    fitted("floor", FLOOR, scheme="one", starts=8, coarse_resolution=None, max_renders_per_stage=160)
    fitted("default", DEFAULT)
    fitted("default, unscaled starts", DEFAULT, linear_starts=False)
    return rows


def main():
    ap = argparse.ArgumentParser()
    g = ap.add_mutually_exclusive_group()
    g.add_argument("--quick", action="store_true", help="the Mitsuba -> Mitsuba cases of the subset, under two minutes")
    g.add_argument("--subset", action="store_true", help="Au α 0.1, Cr α 0.4 and a blue plastic to every target (8 cases)")
    ap.add_argument("--out", default=None, help="write the table as Markdown here")
    args = ap.parse_args()
    which = "quick" if args.quick else "subset" if args.subset else "full"
    reg = registry()
    head = "| case | target | method | renders | seconds | rel. RMSE | ΔE_ITP | × paper time | × floor error |"
    lines = [head, "|---|---|---|---:|---:|---:|---:|---:|---:|"]
    print("\n".join(lines), flush=True)
    summary = []
    t_all = time.perf_counter()
    with open_adapters(reg, ["mitsuba", "cycles"]) as adapters:
        for src, target in cases(which):
            rows = run_case(reg, adapters, src, target)
            paper_s, floor_e = rows["paper"]["seconds"], rows["floor"]["err"]
            for label, r in rows.items():
                speed = f"{paper_s / r['seconds']:.1f}× faster" if r["seconds"] else "no renders"
                line = (f"| {src.name} | {target} | {label} | {r['renders']} | {r['seconds']:.2f} | {r['err']:.2%} | "
                        f"{r['de']:.2f} | {speed} | {r['err'] / max(floor_e, 1e-9):.2f} |")
                lines.append(line)
                print(line, flush=True)
            summary.append((src, target, rows))
    med = ["", "| target | method | cases | median renders | median seconds | median rel. RMSE | "
           "median speed-up vs paper | median error / floor | default within 5% of floor | default ≥3× better than best analytic |",
           "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for target in dict.fromkeys(t for _, t, _ in summary):
        group = [rows for _, t, rows in summary if t == target]
        for label in ("paper", "analytic identity", "analytic squared", "floor", "default", "default, unscaled starts"):
            rs = [g[label] for g in group if label in g]
            if not rs:
                continue
            speed = median([g["paper"]["seconds"] / g[label]["seconds"] for g in group if label in g and
                            g[label]["seconds"]]) if label not in ("analytic identity", "analytic squared") else float("nan")
            ratio = median([g[label]["err"] / max(g["floor"]["err"], 1e-9) for g in group if label in g])
            within = better = ""
            if label == "default":
                within = f"{sum(g['default']['err'] <= 1.05 * g['floor']['err'] + 1e-4 for g in group)}/{len(group)}"
                best_an = [min(g[k]["err"] for k in g if k.startswith("analytic")) for g in group
                           if any(k.startswith("analytic") for k in g)]
                if best_an:
                    better = f"{sum(b >= 3 * g['default']['err'] for b, g in zip(best_an, group))}/{len(best_an)}"
            med.append(f"| {target} | {label} | {len(rs)} | {median([r['renders'] for r in rs]):.0f} | "
                       f"{median([r['seconds'] for r in rs]):.2f} | {median([r['err'] for r in rs]):.2%} | "
                       f"{speed:.1f} | {ratio:.2f} | {within} | {better} |")
    print("\n".join(med))
    print(f"\ntotal {time.perf_counter() - t_all:.0f} s")
    if args.out:
        doc = [f"# Remap speed and quality against the baselines ({which} set)", "",
               f"Produced by `python bench/speed.py{' --' + which if which != 'full' else ''}`; see the script's "
               "docstring for the methods. Errors are on one evaluation render (128², 64 spp).", *med, "",
               *lines, ""]
        write_text_atomic(Path(args.out), "\n".join(doc))


if __name__ == "__main__":
    main()
