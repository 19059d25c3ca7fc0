"""A stored remap's source and target rendered again under one held-out condition at more samples and
other seeds: is a held-out error the material's, or the renders' noise?

    python bench/held_out_converged.py OUT/result.json --condition rim [--spp 32 256 2048] [--start]

Takes the result's job (its source, its fitted parameters; --start: the parameters the fit started from
instead), renders each side at four seeds for each sample count, and prints the error between the
means of four, between the first pair's means (as the verdict measures it) and each side's pair noise.
The condition is the one the result was judged under (as a disc where its fit scene was sharp)."""

from __future__ import annotations

import argparse
import json

import numpy as np
from common import open_adapters, registry

from brdfremap.core.data.metrics import relative_rmse
from brdfremap.core.data.scene import ProbeScene
from brdfremap.core.job.job import Job, Where, resolve
from brdfremap.core.job.validation import held_out_scenes


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("result")
    ap.add_argument("--condition", default="rim")
    ap.add_argument("--spp", type=int, nargs="*", default=[32, 256, 2048])
    ap.add_argument("--start", action="store_true", help="the fit's start instead of its result")
    args = ap.parse_args()
    report = json.loads(open(args.result).read())
    reg = registry()
    res = resolve(Job.model_validate(report["job"]), reg, Where())
    params = {**res.base, **report["params"], **(report["start"]["params"] if args.start else {})}
    scene = ProbeScene.model_validate(report["job"]["scene"])
    sharp = "as a disc" in report["fit_scene"]["why"]
    found = [(c, a) for c, a, _ in held_out_scenes(scene, resolution=64, sharp=sharp) if c.name == args.condition]
    if not found:
        raise SystemExit(f"--condition {args.condition}: not a held-out condition of this result")
    cond, a = found[0]
    src_name, tgt_name = res.job.source.adapter, res.job.target.adapter
    print(f"{cond.label}, {a.resolution} px; {'the start' if args.start else 'the fit'}: {params}")
    with open_adapters(reg, sorted({src_name, tgt_name})) as pool:
        for spp in args.spp:
            s = [np.asarray(pool[src_name].render(res.source_spec, res.source_params, a.with_(spp=spp, seed=k)),
                            np.float64) for k in (1000, 1001, 1002, 1003)]
            t = [np.asarray(pool[tgt_name].render(res.target_spec, params, a.with_(spp=spp, seed=k)), np.float64)
                 for k in (2000, 2001, 2002, 2003)]
            print(f"{spp:5d} spp: error {relative_rmse(sum(s) / 4, sum(t) / 4):.2%} (means of four), "
                  f"{relative_rmse((s[0] + s[1]) / 2, (t[0] + t[1]) / 2):.2%} (a pair's); pair noise: source "
                  f"{relative_rmse(s[0], s[1]) / 2:.2%}, target {relative_rmse(t[0], t[1]) / 2:.2%}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
