"""The images adapter: a source given as the images of the exported scenes (`core.images.folder`).

Unbound (as the registry makes it) it only says what it is; `for_native` binds it to one material's
folder, whose shots are the scenes it renders (any other is not given: `Unrendered`) and whose
calibration folder's white Lambertian is its calibration material, measured against the target's
like any adapter's (`core.job.agreement`)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from brdfremap.core.data.errors import RenderError
from brdfremap.core.data.findings import NoiseUnmeasured, Uncalibrated
from brdfremap.core.data.scene import ProbeScene
from brdfremap.core.data.schemas import Native, Value
from brdfremap.core.host.model import Model
from brdfremap.core.host.protocol import Adapter
from brdfremap.core.images.folder import ImageFolder

WHITE = Model(name="white", description="The export's calibration material as the user's renderer drew it: a white "
                                        "Lambertian of albedo 0.8 (its folder's `calibration` images).",
              parameters=())

NOT_A_TARGET = ("renders nothing: it reads the images a user rendered of `remap scene export`'s scenes, a source "
                "(`remap --source-images DIR`), never a target")


class ImagesAdapter(Adapter):
    name = "images"
    version = "1"
    summary = "images rendered elsewhere of `remap scene export`'s scenes: a source, never a target"
    models = {"white": WHITE}
    light_types = frozenset({"point", "environment"})
    natives = True
    fixed_scenes = True

    def render(self, model: Model, params: dict[str, Value], scene: ProbeScene, lobe: str | None = None) -> np.ndarray:
        raise RenderError(f"adapter 'images' {NOT_A_TARGET}")

    def render_native(self, native: Native, scene: ProbeScene, lobe: str | None = None,
                      transmissive: bool = False) -> np.ndarray:
        return self.for_native(native).render_native(native, scene, lobe, transmissive)

    def for_native(self, native: Native) -> "BoundImages":
        return BoundImages(ImageFolder.open(native.file))


class BoundImages(ImagesAdapter):
    """The images of one material (`ImageFolder`), its calibration beside it."""

    def __init__(self, folder: ImageFolder):
        self.folder = folder
        self.calibration = ("white", {}) if folder.calibration is not None else None  # type: ignore[misc]
        self.scene_problem = folder.problem  # type: ignore[method-assign]

    def identity(self) -> str:  # type: ignore[override]
        return f"{self.version} images-{self.folder.digest}"

    def describe(self) -> dict:
        return {"renderer": f"images of {self.folder.folder}", "shots": [s.name for s in self.folder.given]}

    def render(self, model: Model, params: dict[str, Value], scene: ProbeScene, lobe: str | None = None) -> np.ndarray:
        if model.name != WHITE.name or self.folder.calibration is None or lobe is not None:
            raise RenderError(f"adapter 'images' {NOT_A_TARGET}")
        return self.folder.calibration.render(scene)

    def render_native(self, native: Native, scene: ProbeScene, lobe: str | None = None,
                      transmissive: bool = False) -> np.ndarray:
        if lobe is not None:
            raise RenderError("adapter 'images' has the full images only, no lobe apart")
        return self.folder.render(scene)

    def noise_of(self, scene: ProbeScene) -> float | None:
        return self.folder.noise(scene)

    def for_native(self, native: Native) -> "BoundImages":
        return self if Path(native.file) == self.folder.folder else ImagesAdapter.for_native(self, native)

    def native_findings(self) -> list:
        out: list = [] if self.folder.calibration is not None else [Uncalibrated(folder=str(self.folder.folder))]
        if not self.folder.paired:
            out.append(NoiseUnmeasured(shots=[s.name for s in self.folder.given if len(self.folder.files(s)) < 2]))
        return out
