"""A stored remap of a MaterialX document to Cycles' Principled, its fixed rule and its fit rendered again
under the probe alone (one front view, no back light), against the document's own rendering.

    python bench/materialx_rule.py OUT/materials/NAME/result.json [--resolution 64] [--spp 64]

The report's `start_error` is the rule's error on the fit's scene, which may hold a second view lit
from behind; this says how much of it is the front view's."""

from __future__ import annotations

import argparse
import json

from common import open_adapters, registry

from brdfremap.core.data.metrics import relative_rmse
from brdfremap.core.data.scene import ProbeScene
from brdfremap.core.job.job import Job, Where, resolve
from brdfremap.core.job.validation import held_out_scenes


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("result")
    ap.add_argument("--resolution", type=int, default=64)
    ap.add_argument("--spp", type=int, default=64)
    args = ap.parse_args()
    report = json.loads(open(args.result).read())
    reg = registry()
    res = resolve(Job.model_validate(report["job"]), reg, Where())
    if res.rule is None:
        raise SystemExit(f"{args.result}: its source has no fixed rule for its target")
    scene = ProbeScene(resolution=args.resolution, spp=args.spp)
    with open_adapters(reg, sorted({res.job.source.adapter, res.job.target.adapter})) as pool:
        src = pool[res.job.source.adapter].render(res.source_spec, res.source_params, scene)
        target = pool[res.job.target.adapter]
        rule = target.render(res.target_spec, {**res.base, **res.rule.params}, scene)
        fit = target.render(res.target_spec, {**res.base, **report["params"]}, scene)
        held = []
        for cond, a, _ in held_out_scenes(scene, resolution=args.resolution):
            if cond.name in ("grazing", "rim", "headlight"):
                s, t = pool[res.job.source.adapter].render(res.source_spec, res.source_params, a), \
                    target.render(res.target_spec, {**res.base, **res.rule.params}, a)
                held.append(f"  {cond.label}: the rule {relative_rmse(s, t):.2%}, its image {t.sum() / s.sum():.2f}x "
                            "the source's light")
    print(f"{res.rule.name}\nunder the probe alone, {args.resolution} px, {args.spp} spp: "
          f"the rule {relative_rmse(src, rule):.2%}, the fit {relative_rmse(src, fit):.2%} "
          f"(on the fit's scene: the rule {report['metrics']['start_error']:.2%}, "
          f"the fit {report['metrics']['relative_rmse']:.2%})")
    print("\n".join(held))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
