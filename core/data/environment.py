"""Environment maps: light from every direction, as an equirectangular (latitude-longitude) image.

The convention every adapter realises (Mitsuba's ``envmap`` with an identity transform): a
direction d = (x, y, z) in scene coordinates (+y up in the image, the camera on +z looking
down -z) is at

    u = atan2(x, -z) / 2π  (mod 1),   v = acos(y) / π

with u across the image from its left edge and v down from its top row: the top row is
straight up, the left and right edges look away from the camera (-z), the centre column
looks back at it (+z), and the left half is +x. Pixel values are linear RGB radiance
(W m⁻² sr⁻¹). A map is a file (EXR or HDR, 2:1) or one the project generates itself:
``studio`` (a key, a fill and a rim light over a dim gradient, asymmetric in every axis) and
``constant`` (radiance 1 everywhere: a white Lambertian under it has radiance 1 exactly), and
the discs (`DISCS`): one round light of finite size, far away, in the direction of one of the
held-out point lights (a point light shows a near-mirror's highlight smaller than a pixel; a
disc shows it as the disc's image, which a few samples resolve), and the backdrops (`BACKDROPS`): a soft
box where a held-out point light is over a dim pattern on every side, where a transmissive source is
judged (what is behind a glass seen through it).

`realise` writes the map with its scale and rotation applied to a scratch EXR that adapters
hand their renderer (one per process, content-addressed, so every process renders the same)."""

from __future__ import annotations

import functools
import hashlib
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .errors import ConfigError

MAP_VERSION = 1
"""Bump when a built-in map or the realisation changes (it is in every scene's cache key)."""
MIN_SIZE = (8, 4)
MAX_PIXELS = 8192 * 4096


def direction_to_uv(d: np.ndarray) -> np.ndarray:
    """(…, 3) unit directions → (…, 2) (u, v) in [0, 1): the convention above."""
    d = np.asarray(d, dtype=np.float64)
    u = np.mod(np.arctan2(d[..., 0], -d[..., 2]) / (2 * math.pi), 1.0)
    v = np.arccos(np.clip(d[..., 1], -1.0, 1.0)) / math.pi
    return np.stack([u, v], axis=-1)


def pixel_directions(width: int, height: int) -> np.ndarray:
    """(height, width, 3) unit directions of the pixel centres of a map."""
    u = (np.arange(width) + 0.5) / width
    v = (np.arange(height) + 0.5) / height
    phi, theta = np.meshgrid(2 * math.pi * u, math.pi * v)
    s = np.sin(theta)
    return np.stack([s * np.sin(phi), np.cos(theta), -s * np.cos(phi)], axis=-1)


def _lobe(d: np.ndarray, centre: tuple[float, float, float], radius_deg: float, edge_deg: float) -> np.ndarray:
    """1 inside a disc of light of this angular radius around ``centre``, 0 outside, a linear edge."""
    c = np.asarray(centre, dtype=np.float64)
    c = c / np.linalg.norm(c)
    angle = np.degrees(np.arccos(np.clip((d * c).sum(-1), -1.0, 1.0)))
    return np.clip((radius_deg + edge_deg / 2 - angle) / edge_deg, 0.0, 1.0)


def studio(width: int = 512) -> np.ndarray:
    """The built-in studio: a warm key disc upper left in front, a cool fill right, a rim strip
    behind and above, over a sky-to-ground gradient. Its irradiance on a surface facing the key
    is about that of the default point light (so images are exposed alike)."""
    d = pixel_directions(width, width // 2)
    y = d[..., 1]
    sky = np.where(y >= 0, 0.04 + 0.08 * y, 0.02 + 0.01 * y)[..., None] * np.array([0.9, 0.95, 1.0])
    key = 6.0 * _lobe(d, (-0.6, 0.5, 0.62), 14.0, 2.0)[..., None] * np.array([1.0, 0.93, 0.82])
    fill = 0.8 * _lobe(d, (0.85, 0.05, 0.45), 24.0, 8.0)[..., None] * np.array([0.75, 0.85, 1.0])
    strip = (np.abs(np.degrees(np.arcsin(np.clip(y, -1, 1))) - 40.0) < 4.0) & (d[..., 2] < -0.3) & (d[..., 0] > -0.2)
    rim = 3.0 * strip[..., None] * np.array([1.0, 1.0, 1.0])
    return (sky + key + fill + rim).astype(np.float32)


def constant(width: int = 64) -> np.ndarray:
    return np.ones((width // 2, width, 3), dtype=np.float32)


DISC_RADIUS = 12.0
"""A disc light's angular radius, degrees: a soft box's, about. A mirror sphere shows it as a highlight
about 18 pixels across at the probe's 128 px (resolved by tens of samples), where a point light's is a
fraction of one; its edge is a 2-degree linear ramp (about 3 pixels of the 512-wide map)."""
DISC_EDGE = 2.0


@dataclass(frozen=True)
class Disc:
    """A disc light's direction, as a point light's is written: ``theta`` from the view axis (+z),
    ``phi`` in the image plane from +x towards +y, degrees."""

    theta: float
    phi: float

    @property
    def direction(self) -> tuple[float, float, float]:
        t, p = math.radians(self.theta), math.radians(self.phi)
        return (math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t))


DISCS = {"probe-disc": Disc(45.0, 125.0), "grazing-disc": Disc(80.0, 125.0), "rim-disc": Disc(120.0, 125.0),
         "headlight-disc": Disc(0.0, 125.0)}
"""The built-in discs: where the probe's light and the held-out grazing, rim and head lights are
(`core.job.validation`, `core.job.fitscene`)."""


def disc(where: Disc, width: int = 512) -> np.ndarray:
    """One disc of white light, `DISC_RADIUS` across, black elsewhere, its radiance set so that it gives
    an irradiance of 1 on a surface facing it (summed over the map's pixels, as a renderer integrates
    them): ``scale`` is then the irradiance, as a point light's I / r² is."""
    return _light(where, DISC_RADIUS, DISC_EDGE, width)


BACKDROP_LEVEL = 0.15
"""The backdrop's mean radiance against a light of irradiance 1: its hemisphere gives about half the
light's irradiance (pi x 0.15), enough that what is seen through a glass is lit by more than the rare
path that finds the light (two renders of a clear glass at 512 spp: 1.1-1.8 % over this backdrop, 2.6-3.7 %
over a third of it)."""
SOFT_RADIUS, SOFT_EDGE = 25.0, 8.0
"""The light over a backdrop: a soft box in the held-out point light's direction, larger than a disc
(`DISC_RADIUS`), so that a path reflected off a glass finds it more often (a rough glass under its
12-degree disc: 12-35 % between two renders at 256 spp; over the backdrop under this light 2-3 %)."""


def backdrop(width: int = 512) -> np.ndarray:
    """A pattern on every side, seen through a transmissive sphere: a sky brighter than the ground and
    soft bands across both (8 around, 4 from top to bottom), so that refraction's bend, a rough glass's
    blur and the colour a glass lets through show (with black behind a glass only the rare path that
    reflects the light lights a pixel: two renders of a clear glass part by 60-1450 % at 64 spp)."""
    d = pixel_directions(width, width // 2)
    y = d[..., 1]
    azimuth = np.arctan2(d[..., 0], -d[..., 2])
    elevation = np.arcsin(np.clip(y, -1.0, 1.0))
    bands = 1.0 + 0.6 * np.cos(4 * azimuth) * np.cos(4 * elevation)
    sky = np.where(y >= 0, 1.3 + 0.4 * y, 0.7 + 0.2 * y)
    tint = np.array([0.95, 1.0, 1.05])
    return (BACKDROP_LEVEL * (bands * sky)[..., None] * tint).astype(np.float32)


def _light(where: Disc, radius: float, edge: float, width: int) -> np.ndarray:
    """One round white light of this angular radius in ``where``'s direction, black elsewhere, its
    radiance set so that it gives an irradiance of 1 on a surface facing it (summed over the map's pixels,
    as a renderer integrates them)."""
    d = pixel_directions(width, width // 2)
    lobe = _lobe(d, where.direction, radius, edge)
    h = width // 2
    solid = (2 * math.pi / width) * (math.pi / h) * np.sin(math.pi * (np.arange(h) + 0.5) / h)[:, None]
    cosine = np.clip((d * np.asarray(where.direction)).sum(-1), 0.0, None)
    irradiance = float((lobe * cosine * solid).sum())
    return np.repeat((lobe / irradiance)[..., None], 3, axis=-1).astype(np.float32)


def lit_backdrop(where: Disc, width: int = 512) -> np.ndarray:
    """A soft box (`SOFT_RADIUS`) of irradiance 1 where a held-out point light is, over `backdrop`: how a
    transmissive source is judged (`core.job.validation`), what is behind it seen through it."""
    return _light(where, SOFT_RADIUS, SOFT_EDGE, width) + backdrop(width)


BACKDROPS = {f"{name.removesuffix('-disc')}-backdrop": where for name, where in DISCS.items()}
"""A soft box over `backdrop` in each disc's direction: ``scale`` is its light's irradiance, as a disc's."""


_BUILTINS = {"studio": studio, "constant": constant,
             **{name: functools.partial(disc, where) for name, where in DISCS.items()},
             **{name: functools.partial(lit_backdrop, where) for name, where in BACKDROPS.items()}}


def is_builtin(name: str) -> bool:
    return name in _BUILTINS


@functools.lru_cache(maxsize=16)
def _file_digest(path: str, mtime_ns: int, size: int) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()[:20]


def digest(name: str) -> str:
    """What identifies a map's pixels: a built-in's name and version, a file's content hash."""
    if is_builtin(name):
        return f"builtin:{name}:{MAP_VERSION}"
    st = Path(name).stat()
    return "sha256:" + _file_digest(str(Path(name).resolve()), st.st_mtime_ns, st.st_size)


def check_file(path: Path) -> str | None:
    """Why this file cannot be an environment map, or None (reads its header only)."""
    import OpenImageIO as oiio

    from .imageio import captured_stderr

    if not path.is_file():
        return ("file not found (give the path of an equirectangular EXR or HDR, or a built-in map: "
                f"{', '.join(_BUILTINS)})")
    with captured_stderr() as err:
        inp = oiio.ImageInput.open(str(path))
        spec = None if inp is None else inp.spec()
        if inp is not None:
            inp.close()
    if spec is None:
        return f"not an image OpenImageIO can read ({oiio.geterror() or err['text'] or 'unknown format'})"
    if spec.nchannels < 3:
        return f"has {spec.nchannels} channel(s): an environment map needs RGB"
    if spec.width != 2 * spec.height:
        return f"is {spec.width}x{spec.height}: an equirectangular map is twice as wide as it is high"
    if spec.width < MIN_SIZE[0] or spec.width * spec.height > MAX_PIXELS:
        return f"is {spec.width}x{spec.height}: use a map from {MIN_SIZE[0]}x{MIN_SIZE[1]} to 8192x4096"
    return None


def pixels(name: str) -> np.ndarray:
    """The map's radiance as stored (before scale and rotation)."""
    if is_builtin(name):
        return _BUILTINS[name]()
    from .imageio import read_rgb

    px, why, _ = read_rgb(Path(name))
    if px is None:
        raise ConfigError(f"cannot read the environment map: {why}", file=name)
    if not np.isfinite(px).all() or (px < 0).any():
        raise ConfigError("the environment map has negative, NaN or infinite pixels: radiance is finite and "
                          "non-negative", file=name)
    return px


def rotated(px: np.ndarray, degrees: float) -> np.ndarray:
    """The map turned about the up axis: a feature at azimuth u moves to u + degrees/360
    (linear interpolation between columns, wrapping around)."""
    w = px.shape[1]
    shift = (degrees / 360.0 * w) % w
    if shift == 0:
        return px
    whole, frac = int(math.floor(shift)), shift - math.floor(shift)
    a = np.roll(px, whole, axis=1)
    return ((1 - frac) * a + frac * np.roll(a, 1, axis=1)).astype(np.float32)


def radiance(name: str, scale: float = 1.0, rotation: float = 0.0) -> np.ndarray:
    """The map as rendered: its pixels turned by ``rotation`` and multiplied by ``scale``."""
    return (rotated(pixels(name), rotation) * np.float32(scale)).astype(np.float32)


_REALISED: dict[tuple[str, float, float], Path] = {}
_DIR: list[Path] = []


def realise(name: str, scale: float = 1.0, rotation: float = 0.0) -> Path:
    """An EXR of the map as rendered, in this process's scratch folder (made once per map)."""
    from .imageio import write_exr
    from .scratch import scratch_dir

    key = (digest(name), float(scale), float(rotation))
    path = _REALISED.get(key)
    if path is not None and path.exists():
        return path
    if not _DIR or not _DIR[0].is_dir():
        _DIR[:] = [scratch_dir("env")]
    tag = hashlib.sha256(repr(key).encode()).hexdigest()[:16]
    path = _DIR[0] / f"env-{tag}.exr"
    write_exr(path, radiance(name, scale, rotation))
    _REALISED[key] = path
    return path


def lookup(px: np.ndarray, d: np.ndarray) -> np.ndarray:
    """Bilinear radiance of a map (H x W x 3) in directions ``d`` (…, 3): for analytic checks."""
    h, w = px.shape[:2]
    uv = direction_to_uv(d)
    x, y = uv[..., 0] * w - 0.5, np.clip(uv[..., 1] * h - 0.5, 0, h - 1)
    x0, y0 = np.floor(x).astype(int), np.floor(y).astype(int)
    fx, fy = (x - x0)[..., None], (y - y0)[..., None]
    y1 = np.minimum(y0 + 1, h - 1)
    x0w, x1w = x0 % w, (x0 + 1) % w
    top = (1 - fx) * px[y0, x0w] + fx * px[y0, x1w]
    bottom = (1 - fx) * px[y1, x0w] + fx * px[y1, x1w]
    return (1 - fy) * top + fy * bottom
