"""The threejs adapter's one model, `gltf_pbr`: its parameters read from its data file, its
conversions glTF's own (`appearance`). No browser here."""

from __future__ import annotations

from pathlib import Path

from brdfremap.core.data.appearance import Appearance
from brdfremap.core.data.configio import load_yaml_model
from brdfremap.core.data.schemas import Value
from brdfremap.core.host.model import Model

from . import appearance as _gltf


class GltfPbr(Model):
    """glTF's metallic-roughness material with the extensions three.js renders."""

    def appearance(self, params: dict[str, Value]) -> Appearance:
        return _gltf.appearance(params)

    def from_appearance(self, appearance: Appearance, base: dict[str, Value]) -> dict[str, Value]:
        return _gltf.from_appearance(appearance, base)


GLTF_PBR = load_yaml_model(Path(__file__).with_name("gltf_pbr.yaml"), GltfPbr, "a model")
MODELS: dict[str, GltfPbr] = {GLTF_PBR.name: GLTF_PBR}
