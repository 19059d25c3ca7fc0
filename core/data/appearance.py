"""A material in renderer-neutral terms, and the Fresnel arithmetic exporters convert with.

No renderer knowledge: a source model reads its parameters into an ``Appearance`` and a
target model writes its own from one (``Model.appearance`` / ``Model.from_appearance``). The
session uses the pair as the fit's informed start; the fit corrects what the reading misses."""

from __future__ import annotations

import math
from enum import StrEnum
from typing import Any, Literal

import numpy as np
from pydantic import Field

from .schemas import Need, _Strict

RGB = tuple[float, float, float]


class Coat(_Strict):
    """A clear dielectric layer over the material."""

    weight: float = Field(ge=0.0, le=1.0, description="How much of a full layer (1: the whole surface coated).")
    alpha: float = Field(gt=0.0, description="Microfacet α of the coat's reflection.")
    ior: float = Field(1.5, gt=1.0, description="The coat's index of refraction.")
    tint: RGB = Field((1.0, 1.0, 1.0), description="The colour light takes through the coat.")


class Sheen(_Strict):
    """A soft retro-reflective layer at grazing angles (cloth, velvet)."""

    weight: float = Field(ge=0.0, description="Amount.")
    tint: RGB = Field((1.0, 1.0, 1.0), description="Colour of the sheen.")
    roughness: float = Field(0.5, ge=0.0, le=1.0, description="Spread of the sheen (Cycles' Sheen Roughness).")


class Kind(StrEnum):
    """A metal (coloured specular, no diffuse) or a dielectric (diffuse base, white specular)."""

    CONDUCTOR = "conductor"
    DIELECTRIC = "dielectric"


class DiffuseModel(StrEnum):
    """The diffuse lobe's shape."""

    LAMBERT = "lambert"
    BURLEY = "burley"
    OREN_NAYAR = "oren-nayar"


class Appearance(_Strict):
    """What today's exporters carry over: the kind of material, its specular lobe's α and
    normal-incidence reflectance, its diffuse albedo; a coat, a sheen, anisotropy and
    transmission when it has them. Conventions: α is the microfacet roughness (Blender's
    roughness is √α); reflectances are linear RGB; anisotropy is Disney's (α along the tangent
    α/√(1 − 0.9 a), across α·√(1 − 0.9 a)) and its rotation a fraction of a turn of the tangent,
    counter-clockwise about the outward normal, from the probe's (the sphere's latitudes)."""

    kind: Kind = Field(
        description="A metal (coloured specular, no diffuse) or a dielectric (diffuse base, white specular).")
    alpha: float | None = Field(None, gt=0.0, description="Microfacet α of the specular lobe; None: no specular lobe.")
    distribution: Literal["beckmann", "ggx"] | None = Field(None, description="Microfacet distribution, if one.")
    multiscatter: bool = Field(False, description="The specular lobe keeps the energy its microfacets' multiple "
                                                  "scattering returns (Cycles' Multiscatter GGX; three.js's energy "
                                                  "compensation): a rough metal brighter and more saturated than "
                                                  "single scattering makes it.")
    specular: RGB = Field((0.0, 0.0, 0.0), description="Normal-incidence reflectance F0 of the specular lobe.")
    diffuse: RGB = Field((0.0, 0.0, 0.0), description="Albedo of the diffuse lobe.")
    ior: float | None = Field(None, gt=0.0, description="A dielectric's index of refraction (in air).")
    eta: RGB | None = Field(None, description="A conductor's complex IOR, real part, when known.")
    k: RGB | None = Field(None, description="A conductor's complex IOR, imaginary part, when known.")
    anisotropy: float = Field(0.0, ge=0.0, le=1.0, description="Disney's anisotropy of the specular lobe.")
    rotation: float = Field(0.0, description="Rotation of the anisotropy's tangent, in turns.")
    diffuse_model: DiffuseModel = Field(
        DiffuseModel.LAMBERT, description="The diffuse lobe's shape: Lambert's, Burley's (brighter towards retro-reflection "
                               "as it roughens) or Oren-Nayar's (flatter).")
    coat: Coat | None = Field(None, description="A clear coat, if one.")
    sheen: Sheen | None = Field(None, description="A sheen, if one.")
    transmission: float = Field(0.0, ge=0.0, le=1.0, description="Fraction of the dielectric lobe transmitted "
                                                                 "(glass: 1).")
    transmittance: RGB = Field((1.0, 1.0, 1.0), description="The colour light takes through the sphere, in and "
                                                            "out (a Principled BSDF's glass Base Color; the square "
                                                            "of a transmittance applied at each crossing).")

    def conductor_ior(self, edge_tint: float = 0.5) -> tuple[RGB, RGB]:
        """The complex IOR: as given, else one with this F0 and edge tint (Gulbrandsen 2014)."""
        if self.eta is not None and self.k is not None:
            return self.eta, self.k
        n, kk = eta_k_from_reflectivity(self.specular, [edge_tint] * 3)
        return as_rgb(n), as_rgb(kk)

    def edge_tint(self) -> RGB | None:
        """A conductor's F82 tint (Hoffman 2019, as Blender's Principled BSDF takes it): its reflectance
        at 82 degrees over Schlick's from its F0 there, clipped to [0, 1]; None without a complex IOR."""
        if self.kind != Kind.CONDUCTOR or self.eta is None or self.k is None:
            return None
        ratio = conductor_fresnel(self.eta, self.k, EDGE_COS) / np.maximum(schlick(self.specular, EDGE_COS), 1e-9)
        return as_rgb(np.clip(ratio, 0.0, 1.0))

    def needs(self) -> dict[Need, str]:
        """What this material has that a target's default inputs may not render, each with why."""
        out: dict[Need, str] = {}
        if self.kind == Kind.CONDUCTOR and self.eta is not None and self.k is not None:
            true = conductor_fresnel(self.eta, self.k, EDGE_COS)
            off = float(np.max(np.abs(true - schlick(self.specular, EDGE_COS))))
            if off > EDGE_MIN:
                out[Need.EDGE_TINT] = f"its complex IOR reflects {off:.3f} away from Schlick's at 82 degrees"
        if self.kind == Kind.DIELECTRIC and max(self.diffuse) > 0.0 and self.diffuse_model != DiffuseModel.LAMBERT:
            need = Need.RETRO_DIFFUSE if self.diffuse_model == DiffuseModel.BURLEY else Need.ROUGH_DIFFUSE
            out[need] = f"its diffuse lobe is {_DIFFUSE_NAMES[self.diffuse_model]}, not Lambert's"
        return out

    def base_color(self) -> RGB:
        """The colour a base-colour model (glTF's, Blender's Principled, three.js's) shows: a metal's F0 (its
        ``specular``, else from its complex IOR), else the diffuse base before transmission (`opaque_base`)."""
        if self.kind != Kind.CONDUCTOR:
            return self.opaque_base()
        if max(self.specular) > 0.0 or self.eta is None or self.k is None:
            return self.specular
        return conductor_f0(self.eta, self.k)

    def opaque_base(self) -> RGB:
        """A dielectric's base colour whose untransmitted part is the diffuse albedo (a Principled BSDF's); a
        metal's is `base_color`."""
        keep = 1.0 - self.transmission
        return tuple(c / keep for c in self.diffuse) if 0.0 < keep < 1.0 else self.diffuse  # type: ignore

    def dielectric_ior(self) -> float:
        """The IOR: as given, else the one whose F0 is the mean specular reflectance."""
        if self.ior is not None:
            return self.ior
        return ior_from_f0(float(np.mean(self.specular)))


def as_rgb(v: Any) -> RGB:
    """Three floats from a triple or a number (an array, a tuple, a list)."""
    a = np.broadcast_to(np.asarray(v, dtype=float), (3,))
    return (float(a[0]), float(a[1]), float(a[2]))


_DIFFUSE_NAMES = {"lambert": "Lambert's", "burley": "Burley's", "oren-nayar": "Oren-Nayar's"}
EDGE_COS = math.cos(math.radians(82.0))
"""Where a metal's edge is read: 82 degrees from the normal, where Schlick's error is largest (F82)."""
EDGE_MIN = 0.01
"""A complex IOR whose reflectance at 82 degrees is within this of Schlick's needs no edge tint."""


def conductor_fresnel(eta: Any, k: Any, cos_i: float) -> np.ndarray:
    """Unpolarised Fresnel reflectance of a conductor in air at this incidence, per channel."""
    n, kk = np.asarray(eta, dtype=float), np.asarray(k, dtype=float)
    c2 = cos_i * cos_i
    s2 = 1.0 - c2
    t0 = n * n - kk * kk - s2
    a2b2 = np.sqrt(t0 * t0 + 4.0 * n * n * kk * kk)
    a = np.sqrt(np.maximum(0.5 * (a2b2 + t0), 0.0))
    rs = (a2b2 + c2 - 2.0 * a * cos_i) / (a2b2 + c2 + 2.0 * a * cos_i)
    t1 = c2 * a2b2 + s2 * s2
    rp = rs * (t1 - 2.0 * a * cos_i * s2) / (t1 + 2.0 * a * cos_i * s2)
    return 0.5 * (rs + rp)


def schlick(f0: Any, cos_i: float) -> np.ndarray:
    """Schlick's approximation of the reflectance at this incidence from F0."""
    f = np.asarray(f0, dtype=float)
    return f + (1.0 - f) * (1.0 - cos_i) ** 5


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


def anisotropy_from_alphas(alpha_u: float, alpha_v: float) -> tuple[float, float, float]:
    """(α, anisotropy, rotation) of an α_u (along the tangent) and α_v (across): Disney's aspect
    √(1 − 0.9 a) is α_v/α_u's square root, the tangent turned a quarter when α_v is the larger
    (aspect is at most 1); anisotropy clipped to 1 (a ratio of 10)."""
    alpha = math.sqrt(alpha_u * alpha_v)
    rotation = 0.0 if alpha_u >= alpha_v else 0.25
    ratio = min(alpha_u, alpha_v) / max(alpha_u, alpha_v)
    return alpha, min((1.0 - ratio) / 0.9, 1.0), rotation


def alphas_from_anisotropy(alpha: float, anisotropy: float, rotation: float) -> tuple[float, float]:
    """(α_u, α_v) of a Disney anisotropy whose tangent is turned by a whole number of quarter turns
    (the nearest one otherwise: Mitsuba's anisotropic BSDFs have no rotation)."""
    aspect = math.sqrt(1.0 - 0.9 * anisotropy)
    along, across = alpha / aspect, alpha * aspect
    return (across, along) if round(rotation * 4) % 2 else (along, across)
