"""The threejs adapter's models, each with the form three.js's own loader reads it in (`page_material`:
what the page is handed) and its native file. `gltf_pbr`: its parameters read from its data file, its
conversions glTF's own (`appearance`), read by GLTFLoader. `usd_preview_surface`: USD's
UsdPreviewSurface (`adapters/usd`), read by three.js's USDLoader from a USD layer. No browser here."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from brdfremap.core.data.appearance import Appearance, Kind, as_rgb
from brdfremap.core.data.atomic import write_text_atomic
from brdfremap.core.data.configio import load_yaml_model
from brdfremap.core.data.errors import RenderError
from brdfremap.core.data.schemas import Value
from brdfremap.core.data.textures import Texture, TextureMap
from brdfremap.core.host.model import Model
from brdfremap.adapters.usd import preview

from . import appearance as _gltf
from . import gltf
from . import textures as _textures


class GltfPbr(Model):
    """glTF's metallic-roughness material with the extensions three.js renders."""

    def appearance(self, params: dict[str, Value]) -> Appearance:
        return _gltf.appearance(params)

    def from_appearance(self, appearance: Appearance, base: dict[str, Value]) -> dict[str, Value]:
        return _gltf.from_appearance(appearance, base)

    def page_material(self, params: dict[str, Value], maps: dict[str, TextureMap] | None = None) -> dict[str, Any]:
        """A one-material glTF document, read by GLTFLoader (maps as embedded textures)."""
        return {"material": gltf.document(params, self, maps=maps)}

    def write_native(self, params: dict[str, Value], out_dir: Path, textures: dict[str, Texture] | None) -> Path:
        """`material.gltf`: the material on a sphere; ``textures`` (files in ``out_dir``) embedded."""
        from .spheres import sphere_document

        maps = _textures.maps_from_files(Path(out_dir), textures, _textures.kinds(self)) if textures else {}
        doc = sphere_document([("brdf-remap", params)], self, [maps])
        return write_text_atomic(Path(out_dir) / "material.gltf", json.dumps(doc, indent=1) + "\n")


class UsdPreview(preview.UsdPreviewSurface):
    """UsdPreviewSurface as three.js renders it: a USD layer parsed by three.js's USDLoader."""

    def appearance(self, params: dict[str, Value]) -> Appearance:
        """As three.js draws it (its USDComposer): useSpecularWorkflow ignored, metallic taken as in the
        metallic workflow, and specularColor tinting the IOR's reflectance (MeshPhysicalMaterial's
        specularColor), not replacing it as the specification's specular workflow does."""
        a = super().appearance({**params, "use_specular_workflow": "metallic"})
        a = a.model_copy(update={"multiscatter": True})  # three.js's energy compensation, as glTF's (appearance.py)
        if params.get("use_specular_workflow") != "specular" or a.kind == Kind.CONDUCTOR:
            return a
        tint = as_rgb(params["specular_color"])
        return a.model_copy(update={"specular": tuple(s * t for s, t in zip(a.specular, tint))})

    def notes(self, params: dict[str, Value]) -> list[str]:
        if params.get("use_specular_workflow") == "specular":
            return ["three.js's USDLoader ignores useSpecularWorkflow: it renders specularColor as a tint of the "
                    "IOR's reflectance, not as the reflectance the specification makes it"]
        return []

    def page_material(self, params: dict[str, Value], maps: dict[str, TextureMap] | None = None) -> dict[str, Any]:
        from brdfremap.adapters.usd.author import probe_layer

        if maps:
            raise RenderError("threejs: usd_preview_surface is rendered untextured here (its maps are read as "
                              "their means)")
        return {"usda": probe_layer(params)}

    def write_native(self, params: dict[str, Value], out_dir: Path, textures: dict[str, Texture] | None) -> Path:
        """`material.usda`: the material on a sphere, as `library.usda` holds it."""
        from brdfremap.adapters.usd.author import sphere_layer

        return write_text_atomic(Path(out_dir) / "material.usda", sphere_layer(params, textures))


GLTF_PBR = load_yaml_model(Path(__file__).with_name("gltf_pbr.yaml"), GltfPbr, "a model")
USD_PREVIEW = preview.load(UsdPreview)
MODELS: dict[str, Model] = {GLTF_PBR.name: GLTF_PBR, USD_PREVIEW.name: USD_PREVIEW}
