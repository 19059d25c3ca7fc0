"""Validation figures of the Mitsuba 0.5 models (ward, phong, ashikhmin_shirley plugins).

    python bench/bsdf_validation.py > docs/measurements/bsdf-validation.txt

Prints, per model and parameter set: the chi-square p-value of sampling against the pdf at
three incident directions (Mitsuba's own test; accepted above 0.01), the largest relative
reciprocity error, and the largest RGB white-furnace albedo over cos(theta_i) in
{1, 0.7, 0.4, 0.2, 0.1} (and at 0.05)."""

from __future__ import annotations

import json

from brdfremap.adapters.mitsuba.adapter import MitsubaAdapter
from brdfremap.adapters.mitsuba.validation import (CHI2_CASES, FURNACE_CASES, FURNACE_COS, INCIDENT, albedo, chi2,
                                                   reciprocity)


def main():
    adapter = MitsubaAdapter()
    mi = adapter.mi
    print(f"variant {adapter.describe()['variant']}, 1e6 samples per chi-square test")
    print(f"{'case':32s} {'p (normal)':>11s} {'p (45°)':>9s} {'p (64°)':>9s} {'reciprocity':>12s}")
    accepted = total = 0
    for label, d, res in CHI2_CASES:
        ps = []
        for wi in INCIDENT:
            ok, p, _ = chi2(mi, d, wi, res)
            ps.append(f"{p:.3f}" + ("" if ok else "!"))
            accepted += ok
            total += 1
        print(f"{label:32s} {ps[0]:>11s} {ps[1]:>9s} {ps[2]:>9s} {reciprocity(mi, d):12.1e}")
    print(f"chi-square: {accepted}/{total} accepted at the 1% level ('!': rejected)")
    print()
    print(f"{'furnace case':104s} {'max albedo':>10s} {'at 0.05':>8s}")
    for d in FURNACE_CASES:
        worst = max(albedo(mi, d, mu).max() for mu in FURNACE_COS)
        grazing = albedo(mi, d, 0.05).max()
        print(f"{json.dumps(d):104s} {worst:10.4f} {grazing:8.4f}")
    d = {"type": "ward", "variant": "ward-duer", "alpha": 0.5, "specular_reflectance": 1.0, "diffuse_reflectance": 0.0}
    print(f"{json.dumps(d):104s} {max(albedo(mi, d, mu).max() for mu in FURNACE_COS):10.4f} "
          f"{albedo(mi, d, 0.05).max():8.4f}  (Dür's normalisation is unbounded at grazing angles)")
    adapter.close()


if __name__ == "__main__":
    main()
