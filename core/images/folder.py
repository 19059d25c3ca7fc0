"""A folder of images rendered elsewhere from `remap scene export`'s scenes: one material's (or the
calibration's), each shot's two seeds. It answers a render of a scene from the shot that shows it
(`exported.view_key`), box-filtered down where a condition is judged at a coarser resolution; a scene
no shot shows is not given (`Unrendered`), which leaves that condition unchecked."""

from __future__ import annotations

import functools
import hashlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..data.errors import ConfigError, RenderError
from ..data.findings import Unrendered
from ..data.imageio import read_rgb
from ..data.scene import ProbeScene
from ..data.schemas import Native
from .noise import estimated_noise
from .exported import CALIBRATION, Manifest, Shot, SEEDS, find_manifest, gain, view_key


@dataclass(frozen=True)
class ImageFolder:
    folder: Path
    manifest_path: Path
    manifest: Manifest

    @classmethod
    def open(cls, folder: str | Path) -> "ImageFolder":
        path = Path(folder).expanduser()
        if not path.is_dir():
            raise ConfigError("is not a folder of images (`remap scene export`'s renders/MATERIAL)", file=str(folder))
        where, manifest = find_manifest(path)
        return cls(path.resolve(), where.resolve(), manifest)

    def files(self, shot: Shot) -> list[Path]:
        """The shot's images present, seed 0 first (seed 1 only with seed 0)."""
        found = [self.folder / shot.file(i) for i in range(SEEDS)]
        return found[:1 + int(found[1].is_file())] if found[0].is_file() else []

    @functools.cached_property
    def given(self) -> list[Shot]:
        """The shots of which this folder has an image."""
        return [s for s in self.manifest.shots if self.files(s)]

    @property
    def paired(self) -> bool:
        """Every given shot has both seeds: the noise is measured, not estimated."""
        return all(len(self.files(s)) == SEEDS for s in self.given)

    @functools.cached_property
    def calibration(self) -> "ImageFolder | None":
        """The calibration's images: the folder beside this one (none for the calibration itself)."""
        if self.folder.name == CALIBRATION:
            return None
        other = self.folder.parent / CALIBRATION
        found = ImageFolder(other, self.manifest_path, self.manifest) if other.is_dir() else None
        return found if found is not None and found.given else None

    @functools.cached_property
    def digest(self) -> str:
        """The manifest's and every image's content (the calibration's too): other images, another job."""
        h = hashlib.sha256(self.manifest_path.read_bytes())
        for folder in (self, self.calibration):
            for shot in (folder.given if folder is not None else []):
                for f in folder.files(shot):
                    h.update(f"{folder.folder.name}/{f.name}".encode())
                    h.update(f.read_bytes())
        return h.hexdigest()[:20]

    @property
    def probe_scene(self) -> ProbeScene:
        """The export's probe shot: a source of images' job scene."""
        return self.manifest.shot("probe").scene

    def native(self) -> Native:
        return Native(file=str(self.folder), name=self.folder.name, sha256=self.digest)

    def shot_for(self, scene: ProbeScene) -> Shot | None:
        """The given shot that shows ``scene``: of those of its view (`view_key`), the one of the same light
        intensity, else a material's (the calibration's bright shot is the probe's light, brighter)."""
        key = view_key(scene)
        found = [s for s in self.given if view_key(s.scene) == key]
        return next((s for s in found if gain(s, scene) == 1.0), None) or \
            next((s for s in found if not s.calibration_only), None)

    def problem(self, scene: ProbeScene) -> Unrendered | None:
        shot = self.shot_for(scene)
        if shot is not None:
            return None
        named = next((s.name for s in self.manifest.shots if view_key(s.scene) == view_key(scene)), None)
        return Unrendered(f"has no image of it: render {named}.seed0.exr and .seed1.exr into {self.folder}" if named
                          else "has no image of it: it is not a shot of the export (rendered elsewhere, a source of "
                               "images shows only those)")

    def image(self, shot: Shot, seed: int) -> np.ndarray:
        files = self.files(shot)
        path = files[min(seed, len(files) - 1)]
        pixels, why, _ = read_rgb(path)
        if pixels is None:
            raise ConfigError(f"cannot be read: {why}", file=str(path))
        n = shot.scene.resolution
        if pixels.shape[:2] != (n, n):
            raise ConfigError(f"is {pixels.shape[1]}x{pixels.shape[0]} pixels where its shot is {n}x{n}: render it at "
                              "the sheet's resolution", file=str(path))
        return pixels

    def noise(self, scene: ProbeScene) -> float | None:
        """Where the shot showing ``scene`` was given with one seed: two such renders' difference, estimated
        from the image (`noise.estimated_noise`); None where both seeds were given (the difference is
        measured)."""
        shot = self.shot_for(scene)
        if shot is None or len(self.files(shot)) == SEEDS:
            return None
        return estimated_noise(self.render(scene))

    def render(self, scene: ProbeScene) -> np.ndarray:
        """The image of the shot that shows this scene: seed 0 for the shot's seed and every other one after
        it, seed 1 between (a fit's seed and the next, a held-out condition's pair), scaled to its light's
        intensity (`exported.gain`), box-filtered down to the scene's resolution."""
        shot = self.shot_for(scene)
        if shot is None:
            raise RenderError(f"{self.folder}: {self.problem(scene)}")
        img = self.image(shot, (scene.seed - shot.scene.seed) % SEEDS) * np.float32(gain(shot, scene))
        return downsampled(img, scene.resolution, shot.name)


def _area_weights(size: int, n: int) -> np.ndarray:
    """n x size: how much of each of ``size`` pixels falls in each of ``n`` (each row sums to 1)."""
    edges = np.linspace(0.0, size, n + 1)
    lo, hi = edges[:-1, None], edges[1:, None]
    px = np.arange(size)[None, :]
    overlap = np.clip(np.minimum(hi, px + 1) - np.maximum(lo, px), 0.0, None)
    return overlap / overlap.sum(axis=1, keepdims=True)


def downsampled(img: np.ndarray, n: int, name: str) -> np.ndarray:
    """An image area-averaged to n x n pixels, as a renderer's box pixel filter would have made it at that size
    (a fit's coarse levels are 32, 40, 48 ... pixels: any size at most the image's)."""
    size = img.shape[0]
    if size == n:
        return img
    if n > size:
        raise RenderError(f"shot {name} is {size} pixels wide and a fit asks for {n}: export the scenes at {n} pixels "
                          "or more (`remap scene export --resolution`)")
    w = _area_weights(size, n)
    return np.einsum("ai,ijc,bj->abc", w, img.astype(np.float64), w).astype(np.float32)
