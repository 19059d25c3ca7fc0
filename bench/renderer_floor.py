"""How far two adapters' white Lambertians differ under each held-out light: the floor a material's
held-out error is judged beyond (`core.job.agreement.calibration_floors`).

    python bench/renderer_floor.py [--source mitsuba] [--target cycles] [--spp 16] [--metal smooth|rough | --dielectric]

Renders each adapter's calibration material (`Adapter.calibration`) under the held-out conditions of
the default probe at --spp (the scene's samples; the validation renders 4x that, in two halves, as a
remap does) and prints, per condition, the two renderers' relative RMSE, their noise floor and what is
left beyond it; with --metal, their aluminium of that kind (`Adapter.metals`: a metal's floor); with
--dielectric, their glossy grey dielectric (`Adapter.dielectrics`, where both declare one). Raise
--spp to see a difference the validation's samples cannot."""

from __future__ import annotations

import argparse

from common import open_adapters, registry

from brdfremap.core.job.agreement import _MEASURED, Reference, calibration_floors
from brdfremap.core.data.scene import ProbeScene
from brdfremap.core.job.validation import held_out_scenes


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--source", default="mitsuba")
    ap.add_argument("--target", default="cycles")
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--metal", choices=("smooth", "rough"))
    ap.add_argument("--dielectric", action="store_true")
    args = ap.parse_args()
    if args.dielectric:
        args.metal = "glossy"
    scene = ProbeScene(spp=args.spp)
    conditions = [(c.name, c.label, (a, b)) for c, a, b in held_out_scenes(scene, False, scene.lights)]
    with open_adapters(registry(), [args.source, args.target]) as pool:
        floors = calibration_floors(pool[args.source], pool[args.target], conditions, args.metal)
        kind = Reference(args.metal) if args.metal else None
        both = kind is not None and all(kind.value in kind.declared(pool[n]) for n in (args.source, args.target))
    what = {None: "white Lambertians", Reference.GLOSSY_DIELECTRIC: "glossy grey dielectrics"}.get(
        kind if both else None, f"{args.metal} aluminium")
    print(f"{args.source} against {args.target}, {what}, validation at {4 * args.spp} spp or more")
    print(f"{'condition':12} {'spp':>5} {'error':>8} {'noise':>8} {'beyond':>8}  at fault (off its analytic image)")
    measured = [v for k, v in _MEASURED.items() if k[0] == "calibration"]
    for (name, _, (a, _b)), (err, noise, own) in zip(conditions, measured):
        beyond = floors[name].beyond_noise if name in floors else 0.0
        fault = f"{own[0]} {own[1]:.2%}" if own else "-"
        print(f"{name:12} {2 * a.spp:5d} {err:8.2%} {noise:8.2%} {beyond:8.2%}  {fault}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
