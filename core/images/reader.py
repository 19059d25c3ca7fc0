"""Which folders are one material's images (`remap convert renders/gold renders/plastic`, or the export's
`renders` folder for every material in it), and their job's scene; `core.library.image_reader` reads them."""

from __future__ import annotations

from pathlib import Path

from ..data.errors import ConfigError
from ..data.scene import ProbeScene
from .exported import CALIBRATION, Shot

PROBE = Shot.model_construct(name="probe").file(0)
"""A folder of images holds at least the probe's first seed."""


def is_images(path: Path) -> bool:
    return path.is_dir() and (path / PROBE).is_file() and path.name != CALIBRATION


def image_folders(path: Path) -> list[Path]:
    """The folder itself where it is one material's images, else the ones in it (the export's `renders`)."""
    if is_images(path):
        return [path]
    return sorted(p for p in path.iterdir() if is_images(p)) if path.is_dir() else []


def images_scene(paths: list[Path]) -> ProbeScene | None:
    """The probe shot of the export the folders of images come from, where every input is one (their job's
    scene); None otherwise."""
    from .folder import ImageFolder

    if not paths or not all(is_images(p) for p in paths):
        return None
    scenes: dict[str, tuple[ProbeScene, list[Path]]] = {}
    for p in paths:
        probe = ImageFolder.open(p).probe_scene
        scenes.setdefault(probe.cache_key(), (probe, []))[1].append(p)
    if len(scenes) > 1:
        raise ConfigError("come from exports of different scenes (" + "; ".join(
            ", ".join(str(p) for p in ps) for _, ps in scenes.values()) + "): convert each export's folders apart")
    return next(iter(scenes.values()))[0]
