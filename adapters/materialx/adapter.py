"""The MaterialX adapter: a material rendered by the code MaterialX generates for its nodedef, with
MaterialX's own shader generator and renderer (`PyMaterialXGenGlsl`, `GlslRenderer`, as its viewer
renders), drawing the probe sphere (an OBJ mesh) into a float framebuffer on Mesa's llvmpipe (the CPU)
under a virtual display of the worker's own (`worker.py`, one persistent process).

Where it departs from MaterialX's viewer, it is to put the probe in the same physical units as every
other adapter: point lights are MaterialX's `point_light` falling off with the square of the distance
(`glsl/mx_point_light.glsl`; MaterialX's own divides by (distance + 1)^decay, a real-time convention); an
environment is MaterialX's lat-long lighting with `ENV_SAMPLES` directions a pixel for its filtered
importance sampling (the viewer takes 16) from the map box-averaged to `ENV_WIDTH` columns, its diffuse
from the map's irradiance. Pixels are the mean of `SUPERSAMPLE`² samples (a box filter, as a path
tracer's pixel integrates its footprint; `ENV_SUPERSAMPLE`² under an environment, whose every sample
costs the importance sampling). Deterministic: its noise is nil, and a render depends on neither the
scene's seed nor its samples. Measurements: docs/measurements/materialx.md."""

from __future__ import annotations

import hashlib
import importlib.metadata
import importlib.util
import json
import shutil
import sys
from collections import OrderedDict
from pathlib import Path
from typing import Any

import numpy as np

from brdfremap.core.data.appearance import Appearance, conductor_f0
from brdfremap.core.data.atomic import write_text_atomic
from brdfremap.core.data.environment import pixel_directions, radiance
from brdfremap.core.data.errors import RenderError
from brdfremap.core.data.scene import EnvironmentLight, PointLight, ProbeScene
from brdfremap.core.data.schemas import Native, Value
from brdfremap.core.data.scratch import scratch_dir
from brdfremap.core.data.textures import Texture
from brdfremap.core.host.analytic import environment_irradiance
from brdfremap.core.host.model import Model
from brdfremap.core.host.protocol import Adapter, ModelChoice, check_image
from brdfremap.core.run.workerproc import JsonLinesWorker

from .models import MODELS, TRANSMISSION, MaterialXModel

SUPERSAMPLE = 8
"""Samples a pixel along each axis under point lights."""
BEHIND_SUPERSAMPLE = 16
"""... where every point light is behind the sphere (over 90 degrees from the camera, the rim light and
a fit's back view): the lit part is a crescent along the silhouette, whose pixels 8 × 8 box samples
left 2.8 % from the analytic white Lambertian where Mitsuba and Cycles are 0.66 % apart (16 × 16:
about 1 %; `python bench/materialx_calibration.py`)."""
ENV_SUPERSAMPLE = 4
"""... under an environment."""
ENV_SAMPLES = 256
"""Directions MaterialX's filtered importance sampling takes a pixel under an environment."""
ENV_WIDTH = 256
"""Columns of the map the renderer is given (box-averaged down from the scene's, its light kept): the
sampling's cost grows with the map's size."""
IRRADIANCE_SIZE = (64, 32)
CACHE = 64
"""Images kept by scene and parameters: a render ignores the seed and the samples, so another seed's or
sample count's is the one kept (the same scene's is rendered again, which `remap check` compares bit for
bit)."""
ALUMINIUM = ((1.66, 0.88, 0.52), (9.22, 6.27, 4.84))


def _aluminium(roughness: float) -> tuple[str, dict]:
    look = Appearance(kind="conductor", alpha=roughness ** 2, specular=conductor_f0(*ALUMINIUM), eta=ALUMINIUM[0],
                 k=ALUMINIUM[1])
    return ("open_pbr_surface", {"base_color": look.specular, "base_metalness": 1.0,
                                 "specular_color": look.edge_tint(), "specular_roughness": roughness})


def materialx_version() -> str | None:
    try:
        return importlib.metadata.version("materialx")
    except importlib.metadata.PackageNotFoundError:
        return None


class MaterialXAdapter(Adapter):
    name = "materialx"
    summary = "MaterialX's own GLSL (its shader generator and GlslRenderer) on Mesa's llvmpipe, headless"
    install_hint = ("pip install 'brdf-remap[materialx]' and apt-get install xvfb libgl1-mesa-dri "
                    "(`make test` and `make demo` do both)")
    models = MODELS
    light_types = frozenset({"point", "environment"})
    natives = True
    version = "1"
    calibration = ("standard_surface", {"base": 1.0, "base_color": 0.8, "specular": 0.0})
    glasses = {kind: ("open_pbr_surface", {"base_color": 1.0, "transmission_weight": 1.0, "specular_ior": 1.5,
                                           "specular_roughness": r})
               for kind, r in (("smooth", 0.0), ("rough", 0.1 ** 0.5))}
    transmission_limit = TRANSMISSION + ", by design of a real-time renderer"
    dielectrics = {"glossy": ("open_pbr_surface", {"base_color": 0.5, "specular_roughness": 0.3, "specular_ior": 1.5})}
    metals = {"smooth": _aluminium(0.1), "rough": _aluminium(0.3)}
    mirror = ("standard_surface", {"base": 1.0, "base_color": 1.0, "metalness": 1.0, "specular_roughness": 0.0,
                                   "specular": 0.0})

    @classmethod
    def unavailable_reason(cls) -> str | None:
        if importlib.util.find_spec("MaterialX") is None:
            return "the materialx package is not installed (pip install 'materialx==1.39.*')"
        if sys.platform.startswith("linux") and shutil.which("Xvfb") is None:
            return "Xvfb is not installed (apt-get install xvfb libgl1-mesa-dri): MaterialX renders on a virtual display"
        return None

    @classmethod
    def identity(cls) -> str:
        return f"{cls.version} materialx-{materialx_version()} ss{SUPERSAMPLE}/{BEHIND_SUPERSAMPLE}/{ENV_SUPERSAMPLE} fis{ENV_SAMPLES}@{ENV_WIDTH}"

    @classmethod
    def environment(cls) -> dict[str, Any]:
        return {"renderer": f"MaterialX {materialx_version()} GLSL (GlslRenderer) on Mesa llvmpipe under Xvfb",
                "supersample": SUPERSAMPLE, "environment": f"filtered importance sampling, {ENV_SAMPLES} directions "
                                                           f"a pixel, map {ENV_WIDTH} columns wide"}

    def __init__(self) -> None:
        self.worker = JsonLinesWorker([sys.executable, "-m", "brdfremap.adapters.materialx.worker"], name="materialx")
        self.scratch: Path | None = None
        self._maps: dict[str, dict[str, str]] = {}
        self._images: OrderedDict[str, tuple[tuple[int, int], np.ndarray]] = OrderedDict()
        self.renders = 0

    def describe(self) -> dict[str, Any]:
        if not self.worker.alive():
            self.worker.request({"op": "ping"})
        return {"renderer": f"MaterialX {self.worker.hello.get('materialx', '?')} GLSL on Mesa llvmpipe",
                **self.environment()}

    def _dir(self) -> Path:
        if self.scratch is None or not self.scratch.is_dir():
            self.scratch, self._maps = scratch_dir("materialx"), {}
        return self.scratch

    def render(self, model: Model | str, params: dict[str, Value], scene: ProbeScene,
               lobe: str | None = None) -> np.ndarray:
        model = self.as_model(model)
        if lobe is not None:
            raise RenderError(f"materialx: model {model.name!r} has no lobes to render alone")
        assert isinstance(model, MaterialXModel)
        return self.render_document(model.program_document(), model.uniforms(model.complete(params)), scene)

    def render_native(self, native: Native, scene: ProbeScene, lobe: str | None = None,
                      transmissive: bool = False) -> np.ndarray:
        """A material as its document writes it (`Native.element`: its node graphs and images), by the GLSL
        MaterialX generates for it; no lobe of it apart."""
        if lobe is not None:
            raise RenderError(f"materialx: a document rendered as written has no {lobe} lobe of its own to render")
        return self.render_document(native.element, {}, scene, shader=native.name)

    def render_document(self, document: str, values: dict[str, list[str]], scene: ProbeScene,
                        shader: str = "brdfremap_shader") -> np.ndarray:
        """The first material of a MaterialX document on the probe sphere, ``values`` set as its shader
        node's inputs (each [type, value]): every render goes this way."""
        views = [self._view(v, scene.sphere.center) for v in scene.all_views()]
        request = {"document": document, "shader": shader, "values": values, "resolution": scene.resolution,
                   "sphere": {"center": list(scene.sphere.center), "radius": scene.sphere.radius}, "views": views}
        key = hashlib.sha256(json.dumps(request, sort_keys=True).encode()).hexdigest()
        kept = self._images.get(key)
        if kept is not None and kept[0] != (scene.seed, scene.spp):
            # Another seed's or sample count's: the same image (a validation's "more samples" drew every
            # environment again, 498 s of a ketchup's conversion). The same scene again is drawn again:
            # that is how a determinism check asks.
            self._images.move_to_end(key)
            return kept[1].copy()
        out = self._dir() / "render.raw"
        self.worker.request({"op": "render", **request, "out": str(out)})
        self.renders += 1
        img = np.fromfile(out, np.float32).reshape(len(views) * scene.resolution, scene.resolution, 3)
        img = img if scene.views else check_image(img, scene, "materialx")
        self._images[key] = ((scene.seed, scene.spp), img)
        if len(self._images) > CACHE:
            self._images.popitem(last=False)
        return img.copy()

    def _view(self, view, center) -> dict[str, Any]:
        cam = view.camera
        lights = [self._light(x) for x in view.lights]
        env = any(x["type"] == "environment" for x in lights)
        return {"camera": {"position": list(cam.position), "target": list(cam.target), "up": list(cam.up),
                           "fov": cam.fov, "distance": cam.distance},
                "lights": lights, "supersample": ENV_SUPERSAMPLE if env else
                BEHIND_SUPERSAMPLE if _behind(view, center) else SUPERSAMPLE}

    def _light(self, light) -> dict[str, Any]:
        if isinstance(light, PointLight):
            return {"type": "point", "position": list(light.position), "intensity": light.intensity}
        return {"type": "environment", "samples": ENV_SAMPLES, **self._environment(light)}

    def _environment(self, light: EnvironmentLight) -> dict[str, str]:
        """The map's files for the worker (made once): its radiance at `ENV_WIDTH` columns and its
        irradiance over π (what MaterialX's diffuse reads: a white Lambertian's radiance)."""
        key = hashlib.sha256(json.dumps(light.key(), sort_keys=True).encode()).hexdigest()[:16]
        if key not in self._maps or not Path(self._maps[key]["radiance"]).exists():
            px = radiance(light.map, light.scale, light.rotation)
            small = _downsampled(px, ENV_WIDTH)
            w, h = IRRADIANCE_SIZE
            irr = environment_irradiance(px, pixel_directions(w, h)).astype(np.float32) / np.float32(np.pi)
            files = {"key": key, "radiance": str(self._dir() / f"env-{key}.npy"),
                     "irradiance": str(self._dir() / f"irr-{key}.npy")}
            np.save(files["radiance"], small)
            np.save(files["irradiance"], irr)
            self._maps[key] = files
        return self._maps[key]

    def candidates(self) -> list[ModelChoice]:
        return [ModelChoice("open_pbr_surface", {}, "no reading: OpenPBR, MaterialX's most general surface"),
                ModelChoice("standard_surface", {}, "no reading: Autodesk Standard Surface")]

    def model_for(self, appearance: Appearance) -> ModelChoice:
        return ModelChoice("open_pbr_surface", {}, "OpenPBR Surface: MaterialX's physically based surface of today")

    def write_native(self, model: Model | str, params: dict[str, Value], out_dir: Path,
                     textures: dict[str, Texture] | None = None) -> list[Path]:
        """`material.mtlx`: the material as a MaterialX document (its shader node and a material)."""
        model = self.as_model(model)
        assert isinstance(model, MaterialXModel)
        return [write_text_atomic(Path(out_dir) / "material.mtlx", model.document(model.complete(params)))]

    def close(self) -> None:
        self.worker.close()
        if self.scratch is not None:
            shutil.rmtree(self.scratch, ignore_errors=True)
            self.scratch = None


def _behind(view, center) -> bool:
    """Every light of the view a point light on the far side of the sphere from its camera."""
    c, cam = np.asarray(center, float), np.asarray(view.camera.position, float) - np.asarray(center, float)
    return bool(view.lights) and all(isinstance(x, PointLight) and float(np.dot(np.asarray(x.position) - c, cam)) < 0
                                     for x in view.lights)


def _downsampled(px: np.ndarray, width: int) -> np.ndarray:
    """A map box-averaged down to ``width`` columns (and half as many rows), its radiance kept in the mean;
    a map that is narrower already, as it is."""
    h, w = px.shape[:2]
    if w <= width:
        return np.ascontiguousarray(px, np.float32)
    rows = min(h, max(1, width // 2))
    ys = np.linspace(0, h, rows + 1).astype(int)
    xs = np.linspace(0, w, width + 1).astype(int)
    sums = np.add.reduceat(np.add.reduceat(px.astype(np.float64), ys[:-1], axis=0), xs[:-1], axis=1)
    counts = np.outer(np.diff(ys), np.diff(xs))[..., None]
    return (sums / counts).astype(np.float32)
