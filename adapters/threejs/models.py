"""The threejs adapter's one model, `gltf_pbr`, read from its data file (no browser here)."""

from __future__ import annotations

from pathlib import Path

from brdfremap.core.data.configio import load_yaml_model
from brdfremap.core.data.schemas import ModelSpec

GLTF_PBR = load_yaml_model(Path(__file__).with_name("gltf_pbr.yaml"), ModelSpec, "a model")
MODELS = {GLTF_PBR.name: GLTF_PBR}
