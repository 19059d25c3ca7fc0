"""Checks of the Python BSDFs the way Mitsuba checks its own: chi-square sampling tests,
reciprocity, white-furnace albedo. Shared by the tests and ``bench/bsdf_validation.py``.
Call with the ``mitsuba`` module after ``set_variant`` and ``register_bsdfs()``."""

from __future__ import annotations

import contextlib
import io
import os
import tempfile
from typing import Any

import numpy as np

INCIDENT = ([0.0, 0.0, 1.0], [0.6, 0.2, 0.7745966692414834], [0.9, 0.0, 0.4358898943540673])

# (label, plugin dictionary, chi2 histogram resolution); sharp lobes need the finer grid.
CHI2_CASES: list[tuple[str, dict[str, Any], int]] = [
    ("ward balanced", {"type": "ward", "alpha": 0.2, "specular_reflectance": 0.3, "diffuse_reflectance": 0.4}, 101),
    ("ward original, anisotropic", {"type": "ward", "variant": "ward", "alpha_u": 0.1, "alpha_v": 0.3,
                                    "specular_reflectance": 0.5, "diffuse_reflectance": 0.0}, 101),
    ("ward-duer rough", {"type": "ward", "variant": "ward-duer", "alpha": 0.5}, 101),
    ("ward balanced sharp", {"type": "ward", "alpha": 0.05, "specular_reflectance": 0.8,
                             "diffuse_reflectance": 0.1}, 201),
    ("phong", {"type": "phong", "exponent": 20.0}, 101),
    ("phong sharp", {"type": "phong", "exponent": 200.0, "diffuse_reflectance": 0.0}, 201),
    ("as conductor Au", {"type": "ashikhmin_shirley", "alpha": 0.3, "material": "Au"}, 101),
    ("as conductor anisotropic", {"type": "ashikhmin_shirley", "alpha_u": 0.1, "alpha_v": 0.4,
                                  "material": "Cu"}, 101),
    ("as conductor sharp", {"type": "ashikhmin_shirley", "alpha": 0.05, "reflectivity": 0.9,
                            "edge_tint": 0.5}, 201),
    ("as plastic", {"type": "ashikhmin_shirley", "form": "plastic", "alpha": 0.2, "int_ior": 1.5,
                    "diffuse_reflectance": 0.5}, 101),
    ("as plastic sharp", {"type": "ashikhmin_shirley", "form": "plastic", "alpha": 0.05, "int_ior": 1.7,
                          "diffuse_reflectance": [0.8, 0.2, 0.1]}, 201),
]

# Reflectances at their maximum with the safeguard on: white base, perfect specular.
FURNACE_CASES: list[dict[str, Any]] = [
    {"type": "ward", "alpha": 0.1, "specular_reflectance": 1.5, "diffuse_reflectance": 0.0},  # trimmed to 0.99
    {"type": "ward", "alpha": 0.5, "specular_reflectance": 0.6, "diffuse_reflectance": 0.6},  # trimmed
    {"type": "ward", "variant": "ward", "alpha": 0.3, "specular_reflectance": 0.5, "diffuse_reflectance": 0.5},
    {"type": "phong", "exponent": 2.0, "specular_reflectance": 1.0, "diffuse_reflectance": 0.0},
    {"type": "phong", "exponent": 100.0, "specular_reflectance": 0.6, "diffuse_reflectance": 0.6},  # trimmed
    {"type": "ashikhmin_shirley", "alpha": 0.05, "material": "Ag"},
    {"type": "ashikhmin_shirley", "alpha": 0.3, "material": "Al"},
    {"type": "ashikhmin_shirley", "form": "plastic", "alpha": 0.3, "int_ior": 1.5, "diffuse_reflectance": 1.0},
    {"type": "ashikhmin_shirley", "form": "plastic", "alpha": 0.05, "int_ior": 1.9, "diffuse_reflectance": 1.0},
]
FURNACE_COS = (1.0, 0.7, 0.4, 0.2, 0.1)


def chi2(mi, d: dict[str, Any], wi: list[float], res: int = 101) -> tuple[bool, float, str]:
    """Mitsuba's chi-square test of the BSDF's sampling against its pdf: (accepted, p-value, log)."""
    import drjit as dr
    from mitsuba.chi2 import BSDFAdapter, ChiSquareTest, SphericalDomain

    sample, pdf = BSDFAdapter(d["type"], d, wi=dr.normalize(mi.ScalarVector3f(wi)))
    test = ChiSquareTest(domain=SphericalDomain(), sample_func=sample, pdf_func=pdf, sample_dim=3,
                         res=res, ires=8 if res > 101 else 4, sample_count=1_000_000)
    here = os.getcwd()
    with tempfile.TemporaryDirectory() as tmp:
        os.chdir(tmp)  # a rejected test writes chi2_data.py into the working folder
        try:
            with contextlib.redirect_stdout(io.StringIO()):  # the test narrates; its log is returned
                ok = bool(test.run())
        finally:
            os.chdir(here)
    return ok, float(getattr(test, "p_value", float("nan"))), str(test.messages)


def _uniform_dirs(mi, n: int, seed: int):
    rng = np.random.default_rng(seed)
    return mi.warp.square_to_uniform_hemisphere(mi.Point2f(mi.Float(rng.random(n)), mi.Float(rng.random(n))))


def reciprocity(mi, d: dict[str, Any], n: int = 4000) -> float:
    """Largest relative difference between f(a, b) and f(b, a) over random direction pairs."""
    import drjit as dr

    bsdf = mi.load_dict(d)
    a, b = _uniform_dirs(mi, n, 1), _uniform_dirs(mi, n, 2)
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = a
    f_ab = np.array(bsdf.eval(mi.BSDFContext(), si, b)) / np.array(b.z)
    si.wi = b
    f_ba = np.array(bsdf.eval(mi.BSDFContext(), si, a)) / np.array(a.z)
    return float((np.abs(f_ab - f_ba) / np.maximum(np.abs(f_ab) + np.abs(f_ba), 1e-6)).max())


def albedo(mi, d: dict[str, Any], mu: float, n: int = 384) -> np.ndarray:
    """RGB directional albedo at cos(theta_i) = mu: stratified uniform-hemisphere quadrature of eval."""
    import drjit as dr

    bsdf = mi.load_dict(d)
    u = (np.arange(n) + 0.5) / n
    u1, u2 = np.meshgrid(u, u)
    wo = mi.warp.square_to_uniform_hemisphere(mi.Point2f(mi.Float(u1.ravel()), mi.Float(u2.ravel())))
    si = dr.zeros(mi.SurfaceInteraction3f, n * n)
    si.wi = mi.Vector3f(float(np.sqrt(1 - mu * mu)), 0.0, float(mu))
    v = np.array(bsdf.eval(mi.BSDFContext(), si, wo))
    v = v.reshape(-1, 3) if v.shape[-1] == 3 else v.T
    return v.mean(axis=0) * 2 * np.pi
