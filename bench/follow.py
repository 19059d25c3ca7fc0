"""Path following, on one line of a table's grid: Principled dielectrics of one grey and IOR at
roughness from LOW to HIGH (evenly in the logarithm) remapped to Mitsuba's roughplastic, each fitted
as `remap` fits it (from the exporters' conversion, several starts) and fitted again from the previous
roughness's followed fit (one start), as a table spec's `follow` does.

    python bench/follow.py [--grey 0.26] [--ior 1.7] [--low 0.4] [--high 0.8] [--steps 9]

Prints each fit's parameters and error, and the followed fit's error over the direct one's. Held-out
lights off (the fit's own error is compared); 2 × steps − 1 fits, about 15 s here."""

from __future__ import annotations

import argparse

import numpy as np


def fit(roughness: float, grey: float, ior: float, start: dict | None = None) -> tuple[dict, float]:
    from brdfremap.core.job.execute import adapter_pool, run_job
    from brdfremap.core.job.job import Job, Target, resolve
    from brdfremap.core.host.plugins import collect_adapters
    from brdfremap.core.data.schemas import Material
    from brdfremap.core.data.settings import Settings

    source = Material(adapter="cycles", model="principled", params={
        "distribution": "multi_ggx", "base_color": [grey] * 3, "metallic": 0.0, "roughness": roughness, "ior": ior})
    settings = Settings(validation="none", **({"starts": 1} if start else {}))
    job = Job(source=source, target=Target(adapter="mitsuba", model="roughplastic", fix={"distribution": "ggx"}),
              settings=settings, start=start)
    registry = collect_adapters()
    with adapter_pool(registry) as adapters:
        report = run_job(resolve(job, registry), adapters).report
    return dict(report.params), report.metrics.relative_rmse


def shown(p: dict) -> str:
    return f"diffuse {p['diffuse_reflectance'][0]:.3f}  alpha {p['alpha']:.3f}  IOR {p['int_ior']:.3f}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--grey", type=float, default=0.26)
    ap.add_argument("--ior", type=float, default=1.7)
    ap.add_argument("--low", type=float, default=0.4)
    ap.add_argument("--high", type=float, default=0.8)
    ap.add_argument("--steps", type=int, default=9)
    args = ap.parse_args()
    followed = None
    print(f"Principled grey {args.grey}, IOR {args.ior} -> Mitsuba roughplastic (GGX)")
    for r in np.geomspace(args.low, args.high, args.steps):
        direct, e_direct = fit(float(r), args.grey, args.ior)
        if followed is None:
            followed, e_followed = direct, e_direct
        else:
            start = {k: v for k, v in followed.items() if k != "distribution"}
            followed, e_followed = fit(float(r), args.grey, args.ior, start)
        print(f"roughness {r:.3f}  direct {shown(direct)}  {e_direct:6.2%}   followed {shown(followed)}  "
              f"{e_followed:6.2%}   ratio {e_followed / e_direct:.3f}", flush=True)


if __name__ == "__main__":
    main()
