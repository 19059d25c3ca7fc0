"""External renderers (subprocess adapter) next to the in-process adapters, one run each.

    python bench/external.py

The same remaps through Mitsuba in process and through Mitsuba's command-line renderer
(a process per render), and through the Cycles adapter and Blender as a persistent
external process. Prints error, renders, seconds and seconds per render, and the fitted
parameters' largest relative difference. Every fit starts from the target's defaults: a
renderer defined by a YAML file has no neutral reading of its models, so the in-process
adapter's informed start would make the pair differ in more than how the renderer runs."""

from __future__ import annotations

from common import figures, open_adapters, registry, remap_once


PAIRS = [
    ("configs/materials/copper.yaml", ("mitsuba", "mitsuba-cli"), "roughconductor", ("distribution=ggx",)),
    ("configs/materials/blue-plastic.yaml", ("mitsuba", "mitsuba-cli"), "roughplastic", ("distribution=ggx",)),
    ("configs/materials/copper.yaml", ("cycles", "cycles-subprocess"), "glossy", ("distribution=beckmann",)),
]


def _numbers(params, names):
    out = []
    for n in names:
        v = params[n]
        out += list(v) if isinstance(v, tuple) else [v]
    return out


def main():
    reg = registry()
    print(f"{'source':<18} {'target':<18} {'model':<15} {'rel.RMSE':>8} {'renders':>7} {'seconds':>7} "
          f"{'s/render':>8}  params")
    with open_adapters(reg, ["mitsuba", "mitsuba-cli", "cycles", "cycles-subprocess"]) as adapters:
        for src, targets, model, fix in PAIRS:
            fitted = []
            for target in targets:
                o = remap_once(reg, adapters, src, target, model, fix=fix, start="defaults")
                r = figures(o.report)
                names = [n for n in r.fitted]
                fitted.append(_numbers(r.params, names))
                shown = " ".join(f"{n}={r.params[n] if isinstance(r.params[n], str) else r.params[n]!r}"[:40]
                                 for n in names)
                print(f"{src.split('/')[-1]:<18} {target:<18} {model:<15} {r.relative_rmse:8.2%} {r.renders:7d} "
                      f"{r.seconds:7.2f} {r.seconds / r.renders:8.3f}  {shown}")
            a, b = fitted
            diff = max(abs(x - y) / max(abs(x), 1e-6) for x, y in zip(a, b))
            print(f"{'':<18} largest relative parameter difference: {diff:.2%}")


if __name__ == "__main__":
    main()
