"""Reference geometry and images for testing adapters (numpy only, no renderer).

``analytic_lambert`` is the ground truth every adapter's white diffuse sphere must match:
it is what "the same physical units" means (radiant intensity in W/sr, radiance out)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .scene import ProbeScene


@dataclass
class SphereHits:
    mask: np.ndarray  # H x W bool: the pixel centre's ray hits the sphere
    interior: np.ndarray  # H x W bool: the whole pixel footprint hits (no silhouette blending)
    position: np.ndarray  # H x W x 3
    normal: np.ndarray  # H x W x 3
    view: np.ndarray  # H x W x 3, unit vector from the surface to the camera


def _rays(scene: ProbeScene, offsets: tuple[float, float]):
    cam = scene.camera
    eye = np.array(cam.position, dtype=np.float64)
    fwd = np.array(cam.target) - eye
    fwd /= np.linalg.norm(fwd)
    right = np.cross(fwd, np.array(cam.up, dtype=np.float64))
    right /= np.linalg.norm(right)
    up = np.cross(right, fwd)
    n = scene.resolution
    half = math.tan(math.radians(cam.fov) / 2)
    idx = np.arange(n, dtype=np.float64)
    x = ((idx + offsets[0]) / n * 2 - 1) * half
    y = (1 - (idx + offsets[1]) / n * 2) * half
    xx, yy = np.meshgrid(x, y)
    d = fwd + xx[..., None] * right + yy[..., None] * up
    return eye, d / np.linalg.norm(d, axis=-1, keepdims=True)


def _hit(scene: ProbeScene, eye, d):
    c = np.array(scene.sphere.center, dtype=np.float64)
    oc = eye - c
    b = d @ oc
    disc = b * b - (oc @ oc - scene.sphere.radius**2)
    mask = disc > 0
    t = -b - np.sqrt(np.where(mask, disc, 0.0))
    return mask & (t > 0), t


def sphere_hits(scene: ProbeScene) -> SphereHits:
    eye, d = _rays(scene, (0.5, 0.5))
    mask, t = _hit(scene, eye, d)
    interior = mask.copy()
    for off in ((0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)):
        interior &= _hit(scene, *_rays(scene, off))[0]
    pos = eye + t[..., None] * d
    normal = (pos - np.array(scene.sphere.center)) / scene.sphere.radius
    return SphereHits(mask, interior, pos, normal, -d)


def point_light_irradiance(scene: ProbeScene, hits: SphereHits) -> tuple[np.ndarray, np.ndarray]:
    """(E, l): irradiance I cos(theta) / r^2 (W/m^2, zero where unlit) and the unit light vector."""
    lp = np.array(scene.light.position, dtype=np.float64)
    to_l = lp - hits.position
    dist2 = (to_l**2).sum(-1)
    l = to_l / np.sqrt(dist2)[..., None]
    cos = np.clip((hits.normal * l).sum(-1), 0.0, None)
    return np.where(hits.mask, scene.light.intensity * cos / dist2, 0.0), l


def analytic_lambert(scene: ProbeScene, albedo: float | tuple[float, float, float] = 0.8) -> np.ndarray:
    """Radiance image of a Lambertian sphere: albedo / pi * E. Silhouette pixels are
    point-sampled here but box-filtered by renderers: compare on ``sphere_hits().interior``."""
    hits = sphere_hits(scene)
    e, _ = point_light_irradiance(scene, hits)
    rho = np.broadcast_to(np.asarray(albedo, dtype=np.float64), (3,))
    return (e[..., None] * rho / math.pi).astype(np.float32)
