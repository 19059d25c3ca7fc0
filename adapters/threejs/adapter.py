"""The three.js adapter: a real-time renderer, driven as a black box. Every render is three.js
itself (pinned from npm, `web/package.json`) in Debian's headless Chromium: the material is a glTF
material read by three.js's GLTFLoader (as an app reads one), point lights are three.js's physical
point lights (candela: W/sr here), an environment goes through three.js's own PMREM, and the
pixels are read back linear from a float render target. Supersampled `SUPERSAMPLE`² per pixel
(a box filter), as a path tracer's pixel integrates its footprint; deterministic, so its own noise
is nil."""

from __future__ import annotations

import base64
import hashlib
import importlib.util
import json
from pathlib import Path
from typing import Any

import numpy as np

from brdfremap.core.data.appearance import Appearance, Kind, conductor_f0
from brdfremap.core.data.environment import radiance
from brdfremap.core.data.errors import ConfigError
from brdfremap.core.data.scene import EnvironmentLight, PointLight, ProbeScene
from brdfremap.core.data.schemas import Native, Value
from brdfremap.core.data.textures import Texture, TextureMap
from brdfremap.core.host.model import Model
from brdfremap.core.host.protocol import Adapter, ModelChoice, RenderError, check_image

from .browser import THREE, WEB, Page, chromium
from .images import kind as image_kind
from .models import MODELS

MAX_TARGET = 8192
"""The largest render target this software WebGL allows, pixels a side (SwiftShader's)."""
SUPERSAMPLE = 8
"""Samples per pixel along each axis (a box filter, as the path tracers' pixels are): a sphere's edge
is covered to 1/64 of a pixel. At 4 the white Lambertian under the rim light (a crescent at the edge)
was 5.4 % from Mitsuba's at 1024 spp, at 8 1.9 %, at 12 1.2 %, at 1.6x and 3.1x the render time of 8
(bench: the module docstring of bench/threejs_cost.py)."""
ALUMINIUM = conductor_f0((1.66, 0.88, 0.52), (9.22, 6.27, 4.84))


def three_version() -> str | None:
    try:
        return json.loads(THREE.read_text())["version"]
    except (OSError, ValueError, KeyError):
        return None


def environment_rows(px: np.ndarray) -> np.ndarray:
    """A map in the project's convention (`core.data.environment`: row 0 straight up, u = atan2(x, -z)
    / 2π) as three.js samples an equirectangular texture (u = atan2(z, x) / 2π + 1/2, v = asin(y) / π
    + 1/2, the first row at v = 0): rows bottom first, turned a quarter of the way round."""
    return np.ascontiguousarray(np.roll(px[::-1], px.shape[1] // 4, axis=1), dtype=np.float32)


def embedded(image: dict[str, Any], native: Native) -> dict[str, Any]:
    """An image of a material rendered as written (its file's absolute path: `library._alone`) as the data URI the
    page reads; a PNG or JPEG only."""
    where = f"threejs: material {native.name!r} of {native.file}: image {image.get('uri')!r}"
    try:
        data = Path(str(image.get("uri", ""))).read_bytes()
    except OSError as exc:
        raise RenderError(f"{where} cannot be read ({exc.strerror or exc})") from None
    try:
        mime = MIME[image_kind(data, where)]
    except ConfigError as exc:
        raise RenderError(str(exc)) from None
    return {**image, "uri": f"data:{mime};base64,{base64.b64encode(data).decode()}"}


MIME = {".png": "image/png", ".jpg": "image/jpeg"}


class ThreeJsAdapter(Adapter):
    name = "threejs"
    summary = "three.js (WebGL 2) in headless Chromium: a real-time renderer, glTF materials"
    install_hint = ("apt-get install chromium nodejs npm, then `npm ci` in adapters/threejs/web "
                    "(`make test` and `make demo` do both)")
    models = MODELS
    light_types = frozenset({"point", "environment"})
    version = "2"  # 2: the probe sphere has tangents (anisotropy turned from a frame three.js made from screen derivatives)
    textures = True
    natives = True
    calibration = ("gltf_pbr", {"base_color": 0.8, "metallic": 0.0, "roughness": 1.0, "specular": 0.0})
    transmission_limit = ("three.js's transmission is screen-space, by design: a glass shows a blurred copy of what "
                          "was rendered behind it (the black background), not the environment refracted through the "
                          "sphere; no setting of it is light transport")
    glasses = {kind: ("gltf_pbr", {"base_color": 1.0, "metallic": 0.0, "roughness": r, "ior": 1.5, "transmission": 1.0})
               for kind, r in (("smooth", 0.0), ("rough", 0.1 ** 0.5))}
    dielectrics = {"glossy": ("gltf_pbr", {"base_color": 0.5, "metallic": 0.0, "roughness": 0.3, "ior": 1.5})}
    metals = {kind: ("gltf_pbr", {"base_color": ALUMINIUM, "metallic": 1.0, "roughness": r})
              for kind, r in (("smooth", 0.1), ("rough", 0.3))}
    mirror = ("gltf_pbr", {"base_color": 1.0, "metallic": 1.0, "roughness": 0.0})

    @classmethod
    def scene_problem(cls, scene: ProbeScene) -> str | None:
        if scene.resolution * SUPERSAMPLE > MAX_TARGET:
            return (f"renders at most {MAX_TARGET // SUPERSAMPLE} px a side ({SUPERSAMPLE} x {SUPERSAMPLE} samples a "
                    f"pixel in WebGL render targets of at most {MAX_TARGET} px), and the scene asks for "
                    f"{scene.resolution}")
        return super().scene_problem(scene)

    @classmethod
    def unavailable_reason(cls) -> str | None:
        if chromium() is None:
            return "Chromium is not installed (apt-get install chromium)"
        if importlib.util.find_spec("playwright") is None:
            return "the playwright package is not installed"
        if three_version() is None:
            return f"three.js is not installed in {WEB} (run `npm ci` there)"
        return None

    @classmethod
    def identity(cls) -> str:
        return f"{cls.version} three-{three_version()} ss{SUPERSAMPLE}"

    @classmethod
    def environment(cls) -> dict[str, Any]:
        return {"renderer": f"three.js {three_version()} (WebGL 2, SwiftShader) in {chromium()}"}

    def __init__(self) -> None:
        self.page = Page()
        self.renders = 0

    def describe(self) -> dict[str, Any]:
        return {"renderer": f"three.js r{self.page.info.get('three', '?')} in headless Chromium",
                "gl": self.page.info.get("renderer", "?"), "startup_seconds": round(self.page.startup_seconds, 2)}

    def render(self, model: Model | str, params: dict[str, Value], scene: ProbeScene,
               lobe: str | None = None) -> np.ndarray:
        model = self.as_model(model)
        if lobe is not None:
            raise ValueError(f"threejs: model {model.name!r} has no lobes to render alone")
        return self.render_request(model.page_material(params), scene)

    def render_textured(self, model: Model | str, params: dict[str, Value], maps: dict[str, TextureMap],
                        scene: ProbeScene) -> np.ndarray:
        """The maps as the glTF textures `write_native` writes (8-bit PNGs in the document), read by
        GLTFLoader, on a sphere of the probe's texture coordinates."""
        model = self.as_model(model)
        return self.render_request(model.page_material(model.complete(params), maps), scene)

    def render_document(self, doc: dict[str, Any], scene: ProbeScene) -> np.ndarray:
        """The first material of a glTF document, as three.js's GLTFLoader reads it, on the probe
        sphere (a `.gltf` this tool writes renders as its fit did)."""
        return self.render_request({"material": doc}, scene)

    def render_native(self, native: Native, scene: ProbeScene, lobe: str | None = None,
                      transmissive: bool = False) -> np.ndarray:
        """A glTF material as its file holds it (`Native.element`: the material alone in a document, its
        images embedded: every texture, texture transform and extension GLTFLoader reads), on the probe
        sphere with its texture coordinates; no lobe of it apart."""
        if lobe is not None:
            raise RenderError(f"threejs: a material rendered as written has no {lobe} lobe of its own to render")
        try:
            doc = json.loads(native.element)
        except ValueError:
            raise RenderError(f"threejs: material {native.name!r} of {native.file} is not a glTF document") from None
        return self.render_document({**doc, "images": [embedded(x, native) for x in doc.get("images", [])]}, scene)

    def candidates(self) -> list[ModelChoice]:
        return [ModelChoice("gltf_pbr", {}, "glTF's metallic-roughness, the one model three.js reads")]

    def render_layer(self, usda: str, scene: ProbeScene) -> np.ndarray:
        """The first mesh's material of a USD layer (text), as three.js's USDLoader reads it, on the
        probe sphere."""
        return self.render_request({"usda": usda}, scene)

    def render_request(self, material: dict[str, Any], scene: ProbeScene) -> np.ndarray:
        """A material in the form its model's loader reads (`page_material`: a glTF document or a USD
        layer) on the probe sphere: every render goes this way. A textured material's sphere has the
        probe's texture coordinates (`core.data.textures`)."""
        views = [{"camera": self._camera(view.camera), "lights": [self._light(x) for x in view.lights]}
                 for view in scene.all_views()]
        request = {"resolution": scene.resolution, "supersample": SUPERSAMPLE,
                   "sphere": {"center": list(scene.sphere.center), "radius": scene.sphere.radius,
                              "textured": bool(material.get("material", {}).get("textures"))},
                   "views": views, **material}
        self.renders += 1
        img = self.page.render(request, len(views))
        return img if scene.views else check_image(img, scene, "threejs")

    @staticmethod
    def _camera(c) -> dict[str, Any]:
        return {"position": list(c.position), "target": list(c.target), "up": list(c.up), "fov": c.fov,
                "distance": c.distance}

    def _light(self, light) -> dict[str, Any]:
        if isinstance(light, PointLight):
            return {"type": "point", "position": list(light.position), "intensity": light.intensity}
        return {"type": "environment", "key": self._environment(light)}

    def _environment(self, light: EnvironmentLight) -> str:
        """The key of this environment in the page, handed over the first time."""
        key = hashlib.sha256(json.dumps(light.key(), sort_keys=True).encode()).hexdigest()[:16]
        self.page.environment(key, environment_rows(radiance(light.map, light.scale, light.rotation)))
        return key

    def model_for(self, appearance: Appearance) -> ModelChoice:
        kind = "a metal" if appearance.kind == Kind.CONDUCTOR else "a dielectric"
        return ModelChoice("gltf_pbr", {}, f"{kind}: glTF's metallic-roughness, the one model three.js reads")

    def write_native(self, model: Model | str, params: dict[str, Value], out_dir: Path,
                     textures: dict[str, Texture] | None = None) -> list[Path]:
        """The model's native file (`material.gltf`, `material.usda`): the material on a sphere;
        ``textures`` (files in ``out_dir``) with it."""
        return [self.as_model(model).write_native(params, Path(out_dir), textures)]

    def close(self) -> None:
        self.page.shutdown()
