"""Mitsuba 0.5's Ward, modified Phong and Ashikhmin-Shirley BSDFs as Mitsuba 3 Python plugins.

Mitsuba 3 ships only the Beckmann and GGX microfacet models; the paper (Sztrajman et al.
2017) remaps between the models of Mitsuba 0.5. These plugins reproduce Mitsuba 0.5's
evaluation formulas (ward.cpp, phong.cpp, and roughconductor/roughplastic with the `as`
distribution of microfacet.h), including its energy-conservation safeguard: when the
component-wise maximum of specular + diffuse reflectance exceeds 1, both are scaled by
0.99 / that maximum (BSDF::ensureEnergyConservation). The safeguard is what makes the
paper's conductor remap unstable; ``ensure_energy_conservation=false`` switches it off.

Sampling follows Mitsuba 0.5 where that is exact and otherwise samples the evaluated
density exactly (the tests check sample against pdf with `mitsuba.chi2`).

Use ``register_bsdfs()`` once after ``mitsuba.set_variant(...)`` (the classes are built then, in
`bsdf_classes`, for that variant); the plugins are then
available under the names ``ward``, ``phong`` and ``ashikhmin_shirley`` in dictionaries and
XML like any other Mitsuba BSDF.
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import Any

import numpy as np

INV_PI = 1.0 / math.pi
INV_TWOPI = 0.5 / math.pi
WARD_VARIANTS = ("ward", "ward-duer", "balanced")
ALPHA_MIN = 1e-4  # Mitsuba 0.5 clamps microfacet roughness here


def _has(props, name: str) -> bool:
    return name in props


def _get(props, name: str, default: Any) -> Any:
    return props.get(name) if name in props else default


def _color(props, name: str, default: float) -> tuple[float, float, float]:
    if not _has(props, name):
        return (default,) * 3
    v = props.get(name)
    if isinstance(v, (int, float)):
        return (float(v),) * 3
    try:
        return tuple(float(v[i]) for i in range(3))  # type: ignore[return-value]
    except Exception as exc:  # a texture or bitmap: these plugins take uniform values
        raise ValueError(f"{name!r} must be a number or an RGB value (textures are not supported)") from exc


def _bool(props, name: str, default: bool) -> bool:
    if not _has(props, name):
        return default
    v = props.get(name)
    if isinstance(v, str):
        if v.lower() not in ("true", "false"):
            raise ValueError(f"{name!r} must be true or false, got {v!r}")
        return v.lower() == "true"
    return bool(v)


def trim_scale(specular: Any, diffuse: Any, limit: float = 1.0) -> float:
    """Mitsuba 0.5's energy-conservation safeguard: the factor applied to both reflectances."""
    actual = float(np.max(np.asarray(specular, dtype=float) + np.asarray(diffuse, dtype=float)))
    return 0.99 * (limit / actual) if actual > limit else 1.0


def fresnel_conductor_np(cos_i: np.ndarray, eta: np.ndarray, k: np.ndarray) -> np.ndarray:
    """Exact unpolarised conductor Fresnel reflectance (Mitsuba 0.5's fresnelConductorExact)."""
    c2 = cos_i * cos_i
    s2 = 1.0 - c2
    s4 = s2 * s2
    t1 = eta * eta - k * k - s2
    a2pb2 = np.sqrt(np.maximum(t1 * t1 + 4 * k * k * eta * eta, 0.0))
    a = np.sqrt(np.maximum(0.5 * (a2pb2 + t1), 0.0))
    term1 = a2pb2 + c2
    term2 = 2 * a * cos_i
    rs = (term1 - term2) / (term1 + term2)
    term3 = a2pb2 * c2 + s4
    term4 = term2 * s2
    rp = rs * (term3 - term4) / (term3 + term4)
    return 0.5 * (rp + rs)


@lru_cache(maxsize=None)
def conductor_preset(name: str) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """RGB eta and k of a Mitsuba 3 conductor preset, as Mitsuba's own roughconductor reads them (in
the variant the adapter uses: chosen here where nothing has set one, as when a library is read
before any render)."""
    import mitsuba as mi

    if mi.variant() is None:
        from .variant import choose_variant

        mi.set_variant(choose_variant().variant)

    logger = mi.logger() if hasattr(mi, "logger") else mi.Thread.thread().logger()
    level = logger.log_level()
    logger.set_log_level(mi.LogLevel.Error)  # some presets' spectra clamp slightly out of gamut: not news here
    try:
        bsdf = mi.load_dict({"type": "roughconductor", "material": name})
    finally:
        logger.set_log_level(level)
    params = mi.traverse(bsdf)

    def rgb(key):
        v = np.array(params[key], dtype=float).ravel()
        return tuple(float(x) for x in (v if v.size == 3 else np.repeat(v[:1], 3)))

    return rgb("eta.value"), rgb("k.value")


def _as_exponent(alpha: float) -> float:
    return max(2.0 / (alpha * alpha) - 2.0, 0.0)


def _as_sample_m_np(alpha: float, u1: np.ndarray, u2: np.ndarray) -> np.ndarray:
    """Isotropic AS/Phong microfacet normals with density D(m) cos(theta_m) (numpy)."""
    e = _as_exponent(alpha)
    cos_t = u1 ** (1.0 / (e + 2.0))
    sin_t = np.sqrt(np.maximum(1 - cos_t**2, 0))
    phi = 2 * np.pi * u2
    return np.stack([sin_t * np.cos(phi), sin_t * np.sin(phi), cos_t], axis=-1)


def _g1_np(v: np.ndarray, m: np.ndarray, alpha: float) -> np.ndarray:
    vz = v[..., 2]
    ok = (np.sum(v * m, axis=-1) * vz) > 0
    tan = np.sqrt(np.maximum(1 - vz * vz, 0)) / np.maximum(np.abs(vz), 1e-12)
    a = 1.0 / np.maximum(alpha * tan, 1e-12)
    g = np.where(a >= 1.6, 1.0, (3.535 * a + 2.181 * a * a) / (1 + 2.276 * a + 2.577 * a * a))
    return np.where(ok, g, 0.0)


def _fresnel_dielectric_np(cos_i: np.ndarray, eta: float) -> np.ndarray:
    """Unpolarised dielectric Fresnel reflectance; eta = n_t / n_i; total internal reflection gives 1."""
    c = np.clip(cos_i, 1e-9, 1.0)
    s2t = (1 - c * c) / (eta * eta)
    ct = np.sqrt(np.maximum(1 - s2t, 0.0))
    rs = (c - eta * ct) / (c + eta * ct)
    rp = (eta * c - ct) / (eta * c + ct)
    return np.where(s2t >= 1, 1.0, 0.5 * (rs * rs + rp * rp))


TABLE_SIZE = 64


@lru_cache(maxsize=256)
def rough_transmittance_table(alpha: float, eta: float, n_m: int = 32) -> tuple[tuple[float, ...], float]:
    """Transmittance of a rough (AS-distribution) dielectric interface, for the plastic's diffuse term.

    T(mu) = 1 - (albedo of the interface's specular reflection at cos(theta_i) = mu), by quadrature
    over microfacet normals (n_m x n_m stratified samples of D cos). Returns T at TABLE_SIZE
    values of mu in [0, 1] and the internal diffuse reflectance Fdr (light from below, 1/eta,
    cosine-weighted). Mitsuba 0.5 read the same quantities from precomputed tables of the
    rough dielectric's transmission; this omits the small shadowing loss those include."""
    u = (np.arange(n_m) + 0.5) / n_m
    u1, u2 = np.meshgrid(u, u, indexing="ij")
    m = _as_sample_m_np(alpha, u1.ravel(), u2.ravel())

    def albedo(mu: np.ndarray, e: float) -> np.ndarray:
        mu = np.maximum(mu, 1e-4)
        wi = np.stack([np.sqrt(1 - mu * mu), np.zeros_like(mu), mu], axis=-1)[:, None, :]
        dot_im = np.sum(wi * m[None], axis=-1)
        wo = 2 * dot_im[..., None] * m[None] - wi
        ok = (dot_im > 0) & (wo[..., 2] > 0)
        g = _g1_np(wi, m[None], alpha) * _g1_np(wo, m[None], alpha)
        f = _fresnel_dielectric_np(dot_im, e)
        w = np.where(ok, f * g * dot_im / (mu[:, None] * m[None, :, 2]), 0.0)
        return w.mean(axis=1)

    mus = np.linspace(0.0, 1.0, TABLE_SIZE)
    t_ext = np.clip(1.0 - albedo(mus, eta), 0.0, 1.0)
    # Cosine-weighted hemispherical average of the internal transmittance (midpoint rule in mu^2).
    n_int = 32
    mu_i = np.sqrt((np.arange(n_int) + 0.5) / n_int)
    t_int = np.clip(1.0 - albedo(mu_i, 1.0 / eta), 0.0, 1.0).mean()
    return tuple(float(x) for x in t_ext), float(1.0 - t_int)


def register_bsdfs() -> None:
    """Register ``ward``, ``phong`` and ``ashikhmin_shirley`` with Mitsuba (current variant): their
    classes (`bsdf_classes`) are built once for each variant, after it is set."""
    import importlib.util

    import mitsuba as mi

    if mi.variant() is None:
        raise RuntimeError("call mitsuba.set_variant(...) before register_bsdfs()")
    key = mi.variant()
    if key in _REGISTERED:
        return
    where = importlib.util.find_spec("brdfremap.adapters.mitsuba.bsdf_classes").origin
    spec = importlib.util.spec_from_file_location(f"brdfremap.adapters.mitsuba.bsdf_classes_{key}", where)
    classes = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(classes)
    mi.register_bsdf("ward", lambda props: classes.Ward(props))
    mi.register_bsdf("phong", lambda props: classes.Phong(props))
    mi.register_bsdf("ashikhmin_shirley", lambda props: classes.AshikhminShirley(props))
    _REGISTERED[key] = (classes.Ward, classes.Phong, classes.AshikhminShirley)

_REGISTERED: dict[str, Any] = {}
