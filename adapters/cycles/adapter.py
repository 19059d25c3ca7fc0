"""Blender Cycles through bpy, in a persistent worker process owned by the adapter.

bpy is one global state per process and Blender can crash natively, so renders happen in a
child process (start-up ≈ 1.5 s, paid once); a crash becomes a RenderError with Blender's
output. Images travel as uncompressed float32 multi-part EXR files in /dev/shm."""

from __future__ import annotations

import importlib.util
import json
import os
import sys
import threading
from collections import OrderedDict
from pathlib import Path
from typing import Any

import numpy as np
from brdfremap.core.data.appearance import Appearance
from brdfremap.core.data.atomic import temp_beside, write_text_atomic
from brdfremap.core.data.errors import ConfigError, RenderError
from brdfremap.core.host.model import Model
from brdfremap.core.protocol import Adapter, ModelChoice
from brdfremap.core.data.scene import ProbeScene
from brdfremap.core.data.schemas import Lobe, Native, TRANSMISSION_DEPTH, Value
from brdfremap.core.data.textures import Texture, TextureMap
from brdfremap.core.data.scratch import scratch_dir
from brdfremap.core.run.workerproc import JsonLinesWorker

from . import appearance as _appearance
from .material import python_snippet
from .models import MODELS

PASSES = ("Combined", "Diffuse Direct", "Diffuse Color", "Glossy Direct", "Glossy Color")


def _worker_count() -> int:
    raw = os.environ.get("BRDFREMAP_CYCLES_WORKERS", "")
    if raw.strip():
        try:
            n = int(raw)
        except ValueError:
            raise ConfigError(f"must be a whole number of worker processes, got {raw!r}",
                              field="BRDFREMAP_CYCLES_WORKERS") from None
        most = max(1, os.cpu_count() or 1)
        if not 1 <= n <= most:
            # Each worker is a Blender (about 275 MB) rendering on every core already: more than
            # one per core only competes (the third trial's 100000 ran the machine out of memory).
            raise ConfigError(f"must be from 1 to {most} (this machine's cores), got {n}",
                              field="BRDFREMAP_CYCLES_WORKERS")
        return n
    # One: each Blender renders on every core already, and two of them on 2 cores compete
    # (bench/workers.py: a warm remap to Principled 0.56x as fast with two; a 32² render 70 ms
    # in a batch over two workers against 10 ms alone). Once 1.03x as fast, before the fits
    # rendered their Jacobians' tries and polishes at small sizes, where Blender's start-up and
    # the two processes' contention outweigh the overlap.
    return 1


def read_passes(path: str, expected: tuple[str, ...] = PASSES) -> dict[str, np.ndarray]:
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
    missing = [p for p in expected if p not in images]
    if missing:
        raise RenderError(f"cycles: render passes missing from {path}: {missing} (found {sorted(images)})")
    return images


LOBE_PASSES = {Lobe.DIFFUSE: ("Diffuse Direct", "Diffuse Color"), Lobe.SPECULAR: ("Glossy Direct", "Glossy Color")}
"""Each lobe's image: its direct light times its colour pass."""


def lobe_image(passes: dict[str, np.ndarray], lobe: str | None) -> np.ndarray:
    if lobe is None:
        return passes["Combined"]
    if lobe not in LOBE_PASSES:
        raise RenderError(f"cycles: unknown lobe {lobe!r}")
    direct, colour = LOBE_PASSES[Lobe(lobe)]
    return passes[direct] * passes[colour]


def depth(transmissive: bool) -> int:
    """Cycles' bounces for a material: none for an opaque sphere (direct light alone), as many as
    Mitsuba's path depth for a transmissive one (its max_depth counts the camera's segment and
    the light's: two more)."""
    return TRANSMISSION_DEPTH - 2 if transmissive else 0


def texture_request(folder: Path, textures: dict[str, Texture] | None) -> dict[str, dict[str, str]]:
    """Textures as the worker takes them: absolute files (of names relative to ``folder``)."""
    return {k: {"file": str((Path(folder) / t.file).resolve()), "colorspace": t.colorspace, "filter": t.filter}
            for k, t in (textures or {}).items()}


CANDIDATES = (ModelChoice("principled", {}, "no reading: the Principled BSDF, Cycles' most general model"),
              ModelChoice("metallic", {}, "no reading: the Metallic BSDF, a conductor's Fresnel"),
              ModelChoice("diffuse", {}, "no reading: the Diffuse BSDF"))
"""The models a material with no reading is fitted to (`Adapter.candidates`), the most general first."""


class CyclesAdapter(Adapter):
    name = "cycles"
    summary = "Blender Cycles (bpy, CPU) in a persistent worker process"
    install_hint = "pip install 'brdf-remap[cycles]' (bpy 5.0, Python 3.11)"
    models = MODELS
    light_types = frozenset({"point", "environment"})
    # 2: paths through a transmissive sphere (bounces, the mesh probe, no clamping), the subsurface method;
    # 3: a glass fits its IOR (its Specular IOR Level held).
    version = "3"
    calibration = ("diffuse", {"color": 0.8})
    # Principled glass: Base Color tints the transmitted light (white: clear), GGX as Mitsuba's.
    glasses = {kind: ("principled", {"transmission_weight": 1.0, "base_color": 1.0, "ior": 1.5, "distribution": "ggx",
                                     "roughness": r})
               for kind, r in (("smooth", 0.0), ("rough", 0.1 ** 0.5))}
    # The glossy grey dielectric of glTF's metallic-roughness as Blender's Principled BSDF is it (three.js's too).
    dielectrics = {"glossy": ("principled", {"base_color": 0.5, "metallic": 0.0, "roughness": 0.3, "ior": 1.5,
                                             "specular_ior_level": 0.5})}
    metals = {kind: ("metallic", {"distribution": "ggx", "roughness": r, "ior": (1.66, 0.88, 0.52),
                                  "extinction": (9.22, 6.27, 4.84)}) for kind, r in (("smooth", 0.1), ("rough", 0.3))}
    mirror = ("metallic", {"distribution": "ggx", "roughness": 0.0, "ior": 0.0, "extinction": 10.0})  # |r| = 1
    textures = True
    natives = True
    native_lobes = True
    max_cached = 8

    @classmethod
    def unavailable_reason(cls) -> str | None:
        if sys.version_info[:2] != (3, 11):
            return f"bpy 5.0 needs Python 3.11, this is {sys.version_info[0]}.{sys.version_info[1]}"
        if importlib.util.find_spec("bpy") is None:
            return "the bpy package is not installed"
        return None

    @classmethod
    def identity(cls) -> str:
        import importlib.metadata

        return f"{cls.version} bpy-{importlib.metadata.version('bpy')}"

    @classmethod
    def environment(cls) -> dict[str, Any]:
        import importlib.metadata

        return {"renderer": f"Blender {importlib.metadata.version('bpy')} (Cycles, CPU)",
                "worker": f"{sys.executable} -m brdfremap.adapters.cycles.worker"}

    def __init__(self) -> None:
        self.scratch = str(scratch_dir("cycles"))
        self.worker = JsonLinesWorker([sys.executable, "-m", "brdfremap.adapters.cycles.worker"], name="cycles")
        self._passes: OrderedDict[str, dict[str, np.ndarray]] = OrderedDict()
        self.renders = 0
        self._extra: list[JsonLinesWorker] = []
        self.n_workers = _worker_count()

    def describe(self) -> dict[str, Any]:
        if not self.worker.alive():
            self.worker.request({"op": "ping"})
        return {"renderer": f"Blender {self.worker.hello.get('blender', '?')} (Cycles, CPU)",
                "worker_restarts": self.worker.restarts}

    @classmethod
    def _request(cls, model: Model | str, params: dict[str, Value], scene: ProbeScene) -> tuple[str, dict[str, Any]]:
        import json

        model = cls.as_model(model)
        req = {"model": model.name, "params": {k: list(v) if isinstance(v, tuple) else v for k, v in params.items()},
               "scene": scene.document(), "depth": depth(model.transmissive(params))}
        return json.dumps(req, sort_keys=True), req

    def _cached(self, key: str, lobe: str | None) -> dict[str, np.ndarray] | None:
        """A kept render that can serve this request: any for the full image, one with the lobe
        passes for a lobe."""
        passes = self._passes.get(key)
        if passes is None or (lobe is not None and not all(p in passes for p in PASSES)):
            return None
        return passes

    def _render_passes(self, worker: JsonLinesWorker, req: dict[str, Any], n: int,
                       lobes: bool) -> dict[str, np.ndarray]:
        """One render (the worker's `render`, or the ``op`` ``req`` names); its lobe passes only when
        ``lobes`` (they cost about 13 % of a render)."""
        out = os.path.join(self.scratch, f"r{n}.exr")
        try:
            worker.request({"op": "render", "out": out, "passes": lobes, **req})
            return read_passes(out, PASSES if lobes else PASSES[:1])
        finally:
            try:
                os.unlink(out)
            except OSError:
                pass

    def _keep(self, key: str, passes: dict[str, np.ndarray]) -> None:
        self._passes[key] = passes
        if len(self._passes) > self.max_cached:
            self._passes.popitem(last=False)

    def render(self, model: Model | str, params: dict[str, Value], scene: ProbeScene, lobe: str | None = None) -> np.ndarray:
        if self.n_workers > 1 and not self._extra:
            self._start_extras()
        key, req = self._request(model, params, scene)
        passes = self._cached(key, lobe)
        if passes is None:
            # A lobe's render yields every lobe and the full image (passes): asked for after it,
            # they are free. A full image alone is rendered without the passes.
            self.renders += 1
            passes = self._render_passes(self.worker, req, self.renders, lobes=lobe is not None)
            self._keep(key, passes)
        else:
            self._passes.move_to_end(key)
        return lobe_image(passes, lobe)

    def render_batch(self, requests):
        """The uncached renders split over the worker processes, one thread feeding each.

        ``BRDFREMAP_CYCLES_WORKERS`` sets the count (default 1: see `_worker_count`); with one,
        the renders are made one after another."""
        todo: dict[str, dict[str, Any]] = {}
        lobes: set[str] = set()
        for model, params, scene, lobe in requests:
            key, req = self._request(model, params, scene)
            if self._cached(key, lobe) is None:
                todo.setdefault(key, req)
                if lobe is not None:
                    lobes.add(key)
        workers = self._workers(len(todo))
        if len(todo) >= 2 and len(workers) >= 2:
            keys = list(todo)
            shares = [keys[i::len(workers)] for i in range(len(workers))]
            base = self.renders
            self.renders += len(keys)
            results: dict[str, dict[str, np.ndarray]] = {}
            errors: list[BaseException] = []

            def feed(worker, share, offset):
                try:
                    for i, k in enumerate(share):
                        results[k] = self._render_passes(worker, todo[k], base + offset + i * len(workers) + 1,
                                                         lobes=k in lobes)
                except BaseException as exc:  # re-raised below, in the caller's thread
                    errors.append(exc)

            threads = [threading.Thread(target=feed, args=(w, sh, i)) for i, (w, sh) in enumerate(zip(workers, shares))]
            for t in threads:
                t.start()
            for t in threads:
                t.join()
            if errors:
                raise errors[0]
            for k in keys:
                self._keep(k, results[k])
        return [self.render(*r) for r in requests]

    def _start_extras(self) -> None:
        """Start the extra workers in the background at the first render, so that they are
        up by the first Jacobian (a request waits for a worker still starting)."""
        self._extra = [JsonLinesWorker([sys.executable, "-m", "brdfremap.adapters.cycles.worker"],
                                       name=f"cycles[{i + 1}]") for i in range(self.n_workers - 1)]

        def ping(w: JsonLinesWorker) -> None:
            try:
                w.request({"op": "ping"})
            except RenderError:
                pass  # reported, with its stderr, by the batch that uses it

        for w in self._extra:
            threading.Thread(target=ping, args=(w,), daemon=True).start()

    def _workers(self, wanted: int) -> list[JsonLinesWorker]:
        """The primary worker and the extra ones."""
        if wanted >= 2 and not self._extra and self.n_workers > 1:
            self._start_extras()
        return [self.worker, *self._extra]

    def model_for(self, appearance: Appearance) -> ModelChoice:
        return ModelChoice(*_appearance.model_for(appearance))

    def alternatives(self, appearance: Appearance) -> list[ModelChoice]:
        return [ModelChoice(*x) for x in _appearance.alternatives(appearance)]

    def render_textured(self, model: Model | str, params: dict[str, Value], maps: dict[str, TextureMap],
                        scene: ProbeScene) -> np.ndarray:
        """The probe mesh (its UV map) with an Image Texture node per map: the values written as
        float EXRs and read as Non-Color (as they are)."""
        from brdfremap.core.data.imageio import write_exr

        self.renders += 1
        files = []
        try:
            textures = {}
            for name, m in maps.items():
                path = os.path.join(self.scratch, f"t{self.renders}-{name}.exr")
                values = m.values if m.values.ndim == 3 else np.repeat(m.values[..., None], 3, axis=-1)
                write_exr(Path(path), values)
                files.append(path)
                textures[name] = {"file": path, "colorspace": "linear", "filter": m.filter}
            _, req = self._request(model, params, scene)
            out = os.path.join(self.scratch, f"r{self.renders}.exr")
            files.append(out)
            self.worker.request({"op": "render", "out": out, "passes": False, "textures": textures, **req})
            return read_passes(out, PASSES[:1])["Combined"]
        finally:
            for f in files:
                try:
                    os.unlink(f)
                except OSError:
                    pass

    def render_native(self, native: Native, scene: ProbeScene, lobe: str | None = None,
                      transmissive: bool = False) -> np.ndarray:
        """A material of a user's .blend as the file holds it, on the probe mesh; a lobe from the same
        render passes as a model's (any node tree's diffuse and glossy closures fill them)."""
        req = {"op": "render_native", "path": str(Path(native.file).resolve()), "name": native.name,
               "sha256": native.sha256, "scene": scene.document(), "depth": depth(transmissive)}
        key = json.dumps(req, sort_keys=True)
        passes = self._cached(key, lobe)
        if passes is None:
            self.renders += 1
            passes = self._render_passes(self.worker, req, self.renders, lobes=lobe is not None)
            self._keep(key, passes)
        else:
            self._passes.move_to_end(key)
        return lobe_image(passes, lobe)

    def candidates(self) -> list[ModelChoice]:
        return list(CANDIDATES)

    def render_saved(self, path: Path, name: str, scene: ProbeScene, transmissive: bool = False) -> np.ndarray:
        """A material of a .blend file (a library or material.blend this tool wrote), rendered on the
        probe mesh as Blender opens it: its textures read from the files it references."""
        self.renders += 1
        req = {"op": "render_saved", "path": str(Path(path).resolve()), "name": name, "scene": scene.document(),
               "depth": depth(transmissive)}
        return self._render_passes(self.worker, req, self.renders, lobes=False)["Combined"]

    def write_native(self, model: Model | str, params: dict[str, Value], out_dir: Path,
                     textures: dict[str, Texture] | None = None) -> list[Path]:
        out_dir, model = Path(out_dir), self.as_model(model).name
        blend = out_dir / "material.blend"
        tmp = temp_beside(blend)
        try:
            self.worker.request({"op": "save_blend", "model": model, "name": "brdf-remap",
                                 "params": {k: list(v) if isinstance(v, tuple) else v for k, v in params.items()},
                                 "textures": texture_request(out_dir, textures), "path": str(tmp.resolve())})
            os.replace(tmp, blend)
        finally:
            tmp.unlink(missing_ok=True)
        snippet = write_text_atomic(out_dir / "material.py", python_snippet(model, params, textures=textures))
        return [blend, snippet]

    def close(self) -> None:
        self.worker.close()
        for w in self._extra:
            w.close()
        try:
            for f in os.listdir(self.scratch):
                os.unlink(os.path.join(self.scratch, f))
            os.rmdir(self.scratch)
        except OSError:
            pass
