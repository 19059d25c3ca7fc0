"""The probe scene as a .blend (`remap scene export`): the scene the Cycles adapter renders (its worker
builds it: camera, sphere, lights, world, render settings), with the calibration's white Lambertian on
the sphere as the material `material`, saved for a Blender user to open, put their material in its
place, and render (F12, then save the image as OpenEXR)."""

from __future__ import annotations

import importlib.util
import os
from pathlib import Path

from brdfremap.core.data.atomic import temp_beside
from brdfremap.core.data.scene import ProbeScene


class BlendSceneWriter:
    name = "blend"
    suffix = ".blend"
    swap = ("Blender: open the `.blend`, give the sphere your material in place of `material` (the white Lambertian), "
            "render (Cycles, as set: samples, seed, box filter, no denoiser) and save the image as OpenEXR, Float "
            "(Full), with the view transform Standard (an EXR is written linear).")

    def __init__(self) -> None:
        self._adapter = None

    @staticmethod
    def unavailable_reason() -> str | None:
        return None if importlib.util.find_spec("bpy") is not None else \
            "bpy is not installed: pip install 'brdf-remap[cycles]'"

    def _worker(self):
        if self._adapter is None:
            from .adapter import CyclesAdapter

            self._adapter = CyclesAdapter()
        return self._adapter

    def write(self, scene: ProbeScene, path: Path, maps: dict[str, Path]) -> list[Path]:
        adapter = self._worker()
        name, given = adapter.calibration
        model = adapter.models[name]
        params = {k: list(v) if isinstance(v, tuple) else v for k, v in model.complete(given).items()}
        tmp = temp_beside(path).with_suffix(".blend")
        backup = tmp.with_suffix(".blend1")  # Blender keeps the file it saves over as NAME.blend1
        tmp.unlink(missing_ok=True)
        try:
            adapter.worker.request({"op": "save_scene", "model": name, "params": params, "scene": scene.document(),
                                    "path": str(tmp.resolve())})
            os.replace(tmp, path)
        finally:
            tmp.unlink(missing_ok=True)
            backup.unlink(missing_ok=True)
        return [path]

    def close(self) -> None:
        if self._adapter is not None:
            self._adapter.close()
            self._adapter = None
