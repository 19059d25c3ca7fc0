"""Reference geometry and images every adapter is checked against (numpy only, no renderer).

``analytic_lambert`` is the ground truth every adapter's white diffuse sphere must match:
it is what "the same physical units" means (radiant intensity in W/sr, radiance out)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..data.scene import EnvironmentLight, PointLight, ProbeScene


@dataclass
class SphereHits:
    mask: np.ndarray  # H x W bool: the pixel centre's ray hits the sphere
    interior: np.ndarray  # H x W bool: the whole pixel footprint hits (no silhouette blending)
    position: np.ndarray  # H x W x 3
    normal: np.ndarray  # H x W x 3
    view: np.ndarray  # H x W x 3, unit vector from the surface to the camera


def _directions(scene: ProbeScene, px: np.ndarray, py: np.ndarray):
    """The eye and the unit ray directions through image points (px, py) in pixels (column, row; pixel
    (i, j)'s centre at (j + 0.5, i + 0.5)), of any shape."""
    cam = scene.camera
    eye = np.array(cam.position, dtype=np.float64)
    fwd = np.array(cam.target) - eye
    fwd /= np.linalg.norm(fwd)
    right = np.cross(fwd, np.array(cam.up, dtype=np.float64))
    right /= np.linalg.norm(right)
    up = np.cross(right, fwd)
    n = scene.resolution
    half = math.tan(math.radians(cam.fov) / 2)
    x = (np.asarray(px, np.float64) / n * 2 - 1) * half
    y = (1 - np.asarray(py, np.float64) / n * 2) * half
    d = fwd + x[..., None] * right + y[..., None] * up
    return eye, d / np.linalg.norm(d, axis=-1, keepdims=True)


def _rays(scene: ProbeScene, offsets: tuple[float, float]):
    idx = np.arange(scene.resolution, dtype=np.float64)
    xx, yy = np.meshgrid(idx + offsets[0], idx + offsets[1])
    return _directions(scene, xx, yy)


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
    interior = _hit(scene, eye, d)[0]
    for off in ((0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)):
        interior &= _hit(scene, *_rays(scene, off))[0]
    return _surface(scene, eye, d, interior)


def _surface(scene: ProbeScene, eye: np.ndarray, d: np.ndarray, interior: np.ndarray | None = None) -> SphereHits:
    mask, t = _hit(scene, eye, d)
    pos = eye + t[..., None] * d
    normal = (pos - np.array(scene.sphere.center)) / scene.sphere.radius
    return SphereHits(mask, mask if interior is None else interior, pos, normal, -d)


EDGE_MARGIN = 2
"""`box_filtered` integrates the pixels this close to the silhouette (in pixels), where the shading changes
within a pixel (a rim light's crescent peaks there); inside, a pixel's centre is its mean to a few 1e-4."""


def box_filtered(scene: ProbeScene, shade, k: int = 16) -> np.ndarray:
    """An image ``shade(hits) -> (..., 3)`` as a box pixel filter makes it: each pixel within `EDGE_MARGIN` of
    the silhouette the mean of k x k rays over its area, the others their centre's ray (zero off the sphere
    is ``shade``'s to give, as `point_light_irradiance` does). What a renderer that integrates its pixels draws
    at the edge, for the cost of the edge."""
    hits = sphere_hits(scene)
    img = np.array(shade(hits), np.float64)
    solid = hits.interior
    for _ in range(EDGE_MARGIN):
        solid = solid & np.roll(solid, 1, 0) & np.roll(solid, -1, 0) & np.roll(solid, 1, 1) & np.roll(solid, -1, 1)
    near = hits.mask
    for _ in range(EDGE_MARGIN):
        near = near | np.roll(near, 1, 0) | np.roll(near, -1, 0) | np.roll(near, 1, 1) | np.roll(near, -1, 1)
    rows, cols = np.nonzero(near & ~solid)
    if rows.size:
        off = (np.arange(k) + 0.5) / k
        eye, d = _directions(scene, cols[:, None, None] + off[None, None, :], rows[:, None, None] + off[None, :, None])
        img[rows, cols] = np.asarray(shade(_surface(scene, eye, d)), np.float64).reshape(rows.size, k * k, -1).mean(1)
    return img


def point_light_irradiance(scene: ProbeScene, hits: SphereHits, light: PointLight | None = None
                           ) -> tuple[np.ndarray, np.ndarray]:
    """(E, l): irradiance I cos(theta) / r^2 (W/m^2, zero where unlit) and the unit light vector,
    of ``light`` (default: the scene's first point light)."""
    light = light or scene.point_lights[0]
    lp = np.array(light.position, dtype=np.float64)
    to_l = lp - hits.position
    dist2 = (to_l**2).sum(-1)
    l = to_l / np.sqrt(dist2)[..., None]
    cos = np.clip((hits.normal * l).sum(-1), 0.0, None)
    return np.where(hits.mask, light.intensity * cos / dist2, 0.0), l


def scene_for(spec, scene: ProbeScene, environment_ok: bool = True, params: dict | None = None) -> ProbeScene:
    """The scene a model is seen in: under the studio environment for a smooth one (`ModelSpec.is_smooth`
    with ``params``, else its defaults: a point light shows in a mirror as a point at most), where
    the adapter renders one."""
    if spec.is_smooth(params if params is not None else spec.complete({})) and environment_ok:
        return scene.model_copy(update={"lights": [EnvironmentLight(type="environment", map="studio")]})
    return scene


def environment_irradiance(radiance: np.ndarray, normals: np.ndarray, width: int = 128) -> np.ndarray:
    """Irradiance (…, 3) an unoccluded surface of these normals receives from an equirectangular
    map (H x W x 3, `core.data.environment`'s orientation), integrated over the map box-averaged
    down to ``width`` columns: a few tenths of a percent from the exact integral for smooth maps."""
    from ..data.environment import pixel_directions

    h, w = radiance.shape[:2]
    f = max(1, w // width)
    small = radiance[: h // f * f, : w // f * f].reshape(h // f, f, w // f, f, 3).mean(axis=(1, 3))
    hh, ww = small.shape[:2]
    d = pixel_directions(ww, hh).reshape(-1, 3)
    theta = (np.arange(hh) + 0.5) / hh * math.pi
    solid = np.repeat(np.sin(theta) * (math.pi / hh) * (2 * math.pi / ww), ww)
    weighted = small.reshape(-1, 3) * solid[:, None]
    n = normals.reshape(-1, 3)
    out = np.zeros((n.shape[0], 3))
    for i in range(0, n.shape[0], 4096):
        cos = np.clip(n[i:i + 4096] @ d.T, 0.0, None)
        out[i:i + 4096] = cos @ weighted
    return out.reshape(*normals.shape[:-1], 3)


def analytic_lambert(scene: ProbeScene, albedo: float | tuple[float, float, float] = 0.8) -> np.ndarray:
    """Radiance image of a Lambertian sphere under the scene's lights: albedo / pi * E. Silhouette
    pixels are point-sampled here but box-filtered by renderers: compare on ``sphere_hits().interior``,
    or with `box_filtered_lambert`."""
    return lambert_radiance(scene, sphere_hits(scene), albedo).astype(np.float32)


def lambert_radiance(scene: ProbeScene, hits: SphereHits, albedo: float | tuple[float, float, float] = 0.8
                     ) -> np.ndarray:
    """The radiance (…, 3) a Lambertian sphere of this albedo sends along ``hits``' rays (0 where they miss)."""
    from ..data.environment import radiance

    e = sum(point_light_irradiance(scene, hits, light)[0] for light in scene.point_lights)
    e = np.broadcast_to(np.asarray(e, dtype=np.float64)[..., None], (*hits.mask.shape, 3))
    env = scene.environment
    if env is not None:
        e = e + np.where(hits.mask[..., None],
                         environment_irradiance(radiance(env.map, env.scale, env.rotation), hits.normal), 0.0)
    rho = np.broadcast_to(np.asarray(albedo, dtype=np.float64), (3,))
    return e * rho / math.pi


def box_filtered_lambert(scene: ProbeScene, albedo: float | tuple[float, float, float] = 0.8) -> np.ndarray:
    """`analytic_lambert` as a renderer's box pixel filter makes it, silhouette included (`box_filtered`, 16 x 16
    rays a pixel at the edge: under a rim light at 48 px, 4 x 4 leave its crescent 8.5 % from the exact filter;
    16 x 16 leave Mitsuba 3.1 %, Cycles 4.0 % from it, each within its 64 spp noise)."""
    k = 4 if scene.environment is not None else 16  # an environment lights the edge softly, at a map integral a ray
    return box_filtered(scene, lambda hits: lambert_radiance(scene, hits, albedo), k).astype(np.float32)


def _fresnel(cos_i: np.ndarray, eta: float) -> np.ndarray:
    """Unpolarised Fresnel reflectance of a smooth dielectric boundary (relative IOR ``eta``, light
    arriving from the side of index 1 at cosine ``cos_i``)."""
    sin_t2 = (1.0 - cos_i ** 2) / eta ** 2
    cos_t = np.sqrt(np.clip(1.0 - sin_t2, 0.0, None))
    rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
    return 0.5 * (rs ** 2 + rp ** 2)


def _refract(d: np.ndarray, n: np.ndarray, eta: float) -> np.ndarray:
    """Direction ``d`` refracted through a boundary of normal ``n`` (facing ``d``'s origin) into
    relative index ``eta``; no total internal reflection (none happens inside a sphere)."""
    cos_i = -(d * n).sum(-1, keepdims=True)
    k = 1.0 - (1.0 - cos_i ** 2) / eta ** 2
    return d / eta + (cos_i / eta - np.sqrt(np.clip(k, 0.0, None))) * n


def analytic_mirror(scene: ProbeScene, supersample: int = 6) -> np.ndarray:
    """Radiance image of a perfect mirror sphere (reflectance 1 at every angle) under the scene's environment:
    along each ray, the environment in the reflected direction. Point lights show in it as points: they add
    nothing. Pixels are averaged over ``supersample``² rays (a renderer's box filter)."""
    from ..data.environment import lookup, radiance

    env = scene.environment
    if env is None:
        return np.zeros((scene.resolution, scene.resolution, 3), np.float32)
    px = radiance(env.map, env.scale, env.rotation)

    def shade(hits: SphereHits) -> np.ndarray:
        d = -hits.view
        cos_i = np.clip(-(d * hits.normal).sum(-1, keepdims=True), 0.0, 1.0)
        return np.where(hits.mask[..., None], lookup(px, d + 2.0 * cos_i * hits.normal), 0.0)
    n, k = scene.resolution, supersample
    offsets = (np.arange(k) + 0.5) / k
    idx = np.arange(n, dtype=np.float64)
    xx = idx[None, :, None, None] + offsets[None, None, None, :]
    yy = idx[:, None, None, None] + offsets[None, None, :, None]
    xx, yy = np.broadcast_to(xx, (n, n, k, k)), np.broadcast_to(yy, (n, n, k, k))
    eye, d = _directions(scene, xx, yy)
    return shade(_surface(scene, eye, d)).mean(axis=(2, 3)).astype(np.float32)


def analytic_glass(scene: ProbeScene, ior: float = 1.5, supersample: int = 3, bounces: int = 8) -> np.ndarray:
    """Radiance image of a perfectly smooth, clear glass sphere (relative IOR ``ior``) under the
    scene's environment: its Fresnel reflection, and the light through it after 0 to ``bounces``
    internal reflections (in a sphere every one meets the boundary at the entry angle: the same
    Fresnel, no total internal reflection). Point lights show in it as points: they add nothing.
    Pixels are averaged over ``supersample``² rays (a renderer's box filter)."""
    from ..data.environment import lookup, radiance

    env = scene.environment
    out = np.zeros((scene.resolution, scene.resolution, 3))
    if env is None:
        return out.astype(np.float32)
    px = radiance(env.map, env.scale, env.rotation)
    c = np.array(scene.sphere.center, dtype=np.float64)
    offsets = [(i + 0.5) / supersample for i in range(supersample)]
    for ox in offsets:
        for oy in offsets:
            eye, d = _rays(scene, (ox, oy))
            mask, t = _hit(scene, eye, d)
            # Rays that miss follow one that hits the sphere's front head-on (then masked out).
            d = np.where(mask[..., None], d, np.array([0.0, 0.0, -1.0]))
            p = np.where(mask[..., None], eye + t[..., None] * d, c + [0.0, 0.0, scene.sphere.radius])
            n = (p - c) / scene.sphere.radius
            cos_i = np.clip(-(d * n).sum(-1), 0.0, 1.0)
            f = _fresnel(cos_i, ior)[..., None]
            colour = f * lookup(px, d + 2.0 * cos_i[..., None] * n)
            inside, weight = _refract(d, n, ior), 1.0 - f
            for _ in range(bounces + 1):
                # The chord to the far side: from p along the inside direction, length -2 (inside . n_p).
                p = p - 2.0 * ((inside * (p - c)).sum(-1, keepdims=True) / scene.sphere.radius) * \
                    scene.sphere.radius * inside
                n_out = (p - c) / scene.sphere.radius
                colour += weight * (1.0 - f) * lookup(px, _refract(inside, -n_out, 1.0 / ior))
                inside = inside - 2.0 * (inside * n_out).sum(-1, keepdims=True) * n_out
                weight = weight * f
            out += np.where(mask[..., None], colour, 0.0)
    return (out / supersample ** 2).astype(np.float32)
