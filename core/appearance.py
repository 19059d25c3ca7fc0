"""A material in renderer-neutral terms, and the Fresnel arithmetic exporters convert with.

No renderer knowledge: a source adapter reads its parameters into an ``Appearance`` and a
target adapter writes its own from one (``Adapter.appearance`` / ``from_appearance``). The
session uses the pair as the fit's informed start; the fit corrects what the reading misses."""

from __future__ import annotations

from typing import Any, Literal

import numpy as np
from pydantic import Field

from .schemas import _Strict

RGB = tuple[float, float, float]


class Appearance(_Strict):
    """What today's exporters carry over: the kind of material, its specular lobe's α and
    normal-incidence reflectance, its diffuse albedo. Conventions: α is the microfacet roughness
    (Blender's roughness is √α); reflectances are linear RGB."""

    kind: Literal["conductor", "dielectric"] = Field(
        description="A metal (coloured specular, no diffuse) or a dielectric (diffuse base, white specular).")
    alpha: float | None = Field(None, gt=0.0, description="Microfacet α of the specular lobe; None: no specular lobe.")
    distribution: Literal["beckmann", "ggx"] | None = Field(None, description="Microfacet distribution, if one.")
    specular: RGB = Field((0.0, 0.0, 0.0), description="Normal-incidence reflectance F0 of the specular lobe.")
    diffuse: RGB = Field((0.0, 0.0, 0.0), description="Albedo of the diffuse lobe.")
    ior: float | None = Field(None, gt=0.0, description="A dielectric's index of refraction (in air).")
    eta: RGB | None = Field(None, description="A conductor's complex IOR, real part, when known.")
    k: RGB | None = Field(None, description="A conductor's complex IOR, imaginary part, when known.")

    def conductor_ior(self, edge_tint: float = 0.5) -> tuple[RGB, RGB]:
        """The complex IOR: as given, else one with this F0 and edge tint (Gulbrandsen 2014)."""
        if self.eta is not None and self.k is not None:
            return self.eta, self.k
        n, kk = eta_k_from_reflectivity(self.specular, [edge_tint] * 3)
        return as_rgb(n), as_rgb(kk)

    def dielectric_ior(self) -> float:
        """The IOR: as given, else the one whose F0 is the mean specular reflectance."""
        if self.ior is not None:
            return self.ior
        return ior_from_f0(float(np.mean(self.specular)))


def as_rgb(v: Any) -> RGB:
    """Three floats from a triple or a number (an array, a tuple, a list)."""
    a = np.broadcast_to(np.asarray(v, dtype=float), (3,))
    return (float(a[0]), float(a[1]), float(a[2]))


def dielectric_f0(ior: float) -> float:
    """Normal-incidence Fresnel reflectance of a dielectric in air."""
    return ((ior - 1.0) / (ior + 1.0)) ** 2


def ior_from_f0(f0: float) -> float:
    """The dielectric IOR (above 1) with this normal-incidence reflectance."""
    s = min(max(f0, 0.0), 0.999) ** 0.5
    return (1.0 + s) / (1.0 - s)


def conductor_f0(eta: Any, k: Any) -> RGB:
    """Normal-incidence Fresnel reflectance of a conductor in air, per channel."""
    return as_rgb(reflectivity_edge_tint(eta, k)[0])


def reflectivity_edge_tint(eta: Any, k: Any) -> tuple[np.ndarray, np.ndarray]:
    """Normal-incidence reflectivity r and edge tint g of a conductor (Gulbrandsen 2014)."""
    n, kk = np.asarray(eta, dtype=float), np.asarray(k, dtype=float)
    r = ((n - 1) ** 2 + kk**2) / ((n + 1) ** 2 + kk**2)
    r = np.clip(r, 0.0, 0.999999)
    sr = np.sqrt(r)
    n_min, n_max = (1 - r) / (1 + r), (1 + sr) / (1 - sr)
    span = n_max - n_min  # 0 for a black conductor (r = 0), where every tint is the same material
    g = np.where(span > 0, (n_max - n) / np.where(span > 0, span, 1.0), 0.5)
    return r, g


def eta_k_from_reflectivity(r: Any, g: Any) -> tuple[np.ndarray, np.ndarray]:
    """The complex IOR with reflectivity r and edge tint g (Gulbrandsen 2014, exact inverse)."""
    r = np.clip(np.asarray(r, dtype=float), 0.0, 0.999999)
    g = np.asarray(g, dtype=float)
    sr = np.sqrt(r)
    n_min, n_max = (1 - r) / (1 + r), (1 + sr) / (1 - sr)
    n = g * n_min + (1 - g) * n_max
    k2 = (r * (n + 1) ** 2 - (n - 1) ** 2) / (1 - r)
    return n, np.sqrt(np.maximum(k2, 0.0))
