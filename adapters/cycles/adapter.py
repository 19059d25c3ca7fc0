"""Blender Cycles through bpy, in a persistent worker process owned by the adapter.

bpy is one global state per process and Blender can crash natively, so renders happen in a
child process (start-up ≈ 1.5 s, paid once); a crash becomes a RenderError with Blender's
output. Images travel as uncompressed float32 multi-part EXR files in /dev/shm."""

from __future__ import annotations

import importlib.util
import os
import sys
import tempfile
from collections import OrderedDict
from pathlib import Path
from typing import Any

import numpy as np

from brdfremap.core.atomic import temp_beside, write_text_atomic
from brdfremap.core.errors import RenderError
from brdfremap.core.protocol import Adapter
from brdfremap.core.scene import ProbeScene
from brdfremap.core.schemas import Value
from brdfremap.core.workerproc import JsonLinesWorker

from .material import python_snippet
from .models import MODELS

PASSES = ("Combined", "Diffuse Direct", "Diffuse Color", "Glossy Direct", "Glossy Color")


def _scratch_dir() -> str:
    shm = "/dev/shm"
    base = shm if os.path.isdir(shm) and os.access(shm, os.W_OK) else None
    return tempfile.mkdtemp(prefix="brdfremap-cycles-", dir=base)


def read_passes(path: str) -> dict[str, np.ndarray]:
    """Read the multi-part EXR Blender 5 writes: one part per pass, channels 'Layer.Pass.C'."""
    import OpenImageIO as oiio

    inp = oiio.ImageInput.open(path)
    if inp is None:
        raise RenderError(f"cycles: cannot read {path}: {oiio.geterror()}")
    out: dict[str, np.ndarray] = {}
    try:
        sub = 0
        while inp.seek_subimage(sub, 0):
            names = inp.spec().channelnames
            pixels = inp.read_image(sub, 0, 0, len(names), "float")
            if pixels is None:
                raise RenderError(f"cycles: truncated image {path}: {oiio.geterror()}")
            for i, cname in enumerate(names):
                parts = cname.split(".")
                if len(parts) >= 3:
                    out.setdefault(parts[-2], {})[parts[-1]] = pixels[..., i]
            sub += 1
    finally:
        inp.close()
    images = {}
    for pname, chans in out.items():
        if all(c in chans for c in "RGB"):
            images[pname] = np.stack([chans["R"], chans["G"], chans["B"]], axis=-1).astype(np.float32)
    missing = [p for p in PASSES if p not in images]
    if missing:
        raise RenderError(f"cycles: render passes missing from {path}: {missing} (found {sorted(images)})")
    return images


def lobe_image(passes: dict[str, np.ndarray], lobe: str | None) -> np.ndarray:
    if lobe is None:
        return passes["Combined"]
    if lobe == "diffuse":
        return passes["Diffuse Direct"] * passes["Diffuse Color"]
    if lobe == "specular":
        return passes["Glossy Direct"] * passes["Glossy Color"]
    raise RenderError(f"cycles: unknown lobe {lobe!r}")


class CyclesAdapter(Adapter):
    name = "cycles"
    summary = "Blender Cycles (bpy, CPU) in a persistent worker process"
    install_hint = "pip install 'brdf-remap[cycles]' (bpy 5.0, Python 3.11)"
    models = MODELS
    max_cached = 8

    @classmethod
    def unavailable_reason(cls) -> str | None:
        if sys.version_info[:2] != (3, 11):
            return f"bpy 5.0 needs Python 3.11, this is {sys.version_info[0]}.{sys.version_info[1]}"
        if importlib.util.find_spec("bpy") is None:
            return "the bpy package is not installed"
        return None

    @classmethod
    def environment(cls) -> dict[str, Any]:
        import importlib.metadata

        return {"renderer": f"Blender {importlib.metadata.version('bpy')} (Cycles, CPU)",
                "worker": f"{sys.executable} -m brdfremap.adapters.cycles.worker"}

    def __init__(self) -> None:
        self.scratch = _scratch_dir()
        self.worker = JsonLinesWorker([sys.executable, "-m", "brdfremap.adapters.cycles.worker"], name="cycles")
        self._passes: OrderedDict[str, dict[str, np.ndarray]] = OrderedDict()
        self.renders = 0

    def describe(self) -> dict[str, Any]:
        if not self.worker.alive():
            self.worker.request({"op": "ping"})
        return {"renderer": f"Blender {self.worker.hello.get('blender', '?')} (Cycles, CPU)",
                "worker_restarts": self.worker.restarts}

    def render(self, model: str, params: dict[str, Value], scene: ProbeScene, lobe: str | None = None) -> np.ndarray:
        import json

        req = {"model": model, "params": {k: list(v) if isinstance(v, tuple) else v for k, v in params.items()},
               "scene": scene.document()}
        key = json.dumps(req, sort_keys=True)
        passes = self._passes.get(key)
        if passes is None:
            # One render yields every lobe (passes): a lobe request after the full image is free.
            out = os.path.join(self.scratch, f"r{self.renders}.exr")
            try:
                self.worker.request({"op": "render", "out": out, **req})
                passes = read_passes(out)
            finally:
                try:
                    os.unlink(out)
                except OSError:
                    pass
            self.renders += 1
            self._passes[key] = passes
            if len(self._passes) > self.max_cached:
                self._passes.popitem(last=False)
        else:
            self._passes.move_to_end(key)
        return lobe_image(passes, lobe)

    def write_native(self, model: str, params: dict[str, Value], out_dir: Path) -> list[Path]:
        out_dir = Path(out_dir)
        blend = out_dir / "material.blend"
        tmp = temp_beside(blend)
        try:
            self.worker.request({"op": "save_blend", "model": model, "name": "brdf-remap",
                                 "params": {k: list(v) if isinstance(v, tuple) else v for k, v in params.items()},
                                 "path": str(tmp.resolve())})
            os.replace(tmp, blend)
        finally:
            tmp.unlink(missing_ok=True)
        snippet = write_text_atomic(out_dir / "material.py", python_snippet(model, params))
        return [blend, snippet]

    def close(self) -> None:
        self.worker.close()
        try:
            for f in os.listdir(self.scratch):
                os.unlink(os.path.join(self.scratch, f))
            os.rmdir(self.scratch)
        except OSError:
            pass
