"""Folders of images as a library's sources: each folder one material rendered elsewhere of `remap scene
export`'s scenes (`core.images`), checked as `remap --source-images` checks it (`calibrate.checked`)."""

from __future__ import annotations

from pathlib import Path

from ..data.schemas import Material
from ..images.calibrate import checked
from ..images.reader import is_images
from .entries import Entry


class ImagesReader:
    name = "images"
    suffixes = ("",)
    """A folder (no ending)."""

    def accepts(self, path: Path) -> bool:
        return is_images(path)

    def read(self, path: Path) -> list:
        folder = checked(path)
        material = Material(adapter="images", model="", name=folder.folder.name, native=folder.native())
        return [Entry(name=folder.folder.name, file=str(folder.folder), material=material)]
