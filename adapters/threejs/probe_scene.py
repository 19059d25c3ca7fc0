"""The probe scene as a glTF 2.0 document (`remap scene export`), for a real-time engine or any glTF
viewer: the sphere (a 256 x 128 UV mesh, normals exact), its camera, each point light as a
`KHR_lights_punctual` light, and the calibration material (a white Lambertian: base colour 0.8,
metallic 0, roughness 1, `KHR_materials_specular` factor 0, no specular lobe). glTF has no environment
light in its core: a scene under one is not written (its shot is rendered from the USD or the XML).

A point light's intensity is the radiant intensity in W/sr written as candela, as three.js reads it
(`adapters/threejs`); an engine that converts candela to watts by 683 lm/W shows the calibration's
units row a factor of 1/683 (`core.host.check.FACTORS`)."""

from __future__ import annotations

import base64
import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from brdfremap.core.data.atomic import write_text_atomic
from brdfremap.core.data.scene import PointLight, ProbeScene
from brdfremap.core.data.sphere import sphere_mesh
from brdfremap.core.host.check import ALBEDO

from . import gltf
from .spheres import _mesh_parts

MATERIAL = "material"
EXTENSIONS = ["KHR_lights_punctual", "KHR_materials_specular"]


def _quaternion(m: np.ndarray) -> list[float]:
    """(x, y, z, w) of a rotation matrix (columns: the rotated axes)."""
    w = math.sqrt(max(0.0, 1.0 + m[0, 0] + m[1, 1] + m[2, 2])) / 2
    x = math.copysign(math.sqrt(max(0.0, 1.0 + m[0, 0] - m[1, 1] - m[2, 2])) / 2, m[2, 1] - m[1, 2])
    y = math.copysign(math.sqrt(max(0.0, 1.0 - m[0, 0] + m[1, 1] - m[2, 2])) / 2, m[0, 2] - m[2, 0])
    z = math.copysign(math.sqrt(max(0.0, 1.0 - m[0, 0] - m[1, 1] + m[2, 2])) / 2, m[1, 0] - m[0, 1])
    return [x, y, z, w]


def _camera_node(scene: ProbeScene) -> dict[str, Any]:
    """The camera's node: a glTF camera looks down its -z with +y up."""
    cam = scene.camera
    eye, target = np.asarray(cam.position, float), np.asarray(cam.target, float)
    back = (eye - target) / np.linalg.norm(eye - target)
    right = np.cross(np.asarray(cam.up, float), back)
    right /= np.linalg.norm(right)
    up = np.cross(back, right)
    return {"name": "camera", "camera": 0, "translation": eye.tolist(),
            "rotation": _quaternion(np.stack([right, up, back], axis=1))}


def document(scene: ProbeScene) -> dict[str, Any]:
    """The glTF document of one single-view scene of point lights."""
    blob, views, accessors, attributes, indices = _mesh_parts(
        {k: v for k, v in sphere_mesh().items() if k in ("POSITION", "NORMAL", "TEXCOORD_0", "indices")})
    s, d = scene.sphere, scene.camera.distance
    lights = [x for x in scene.lights if isinstance(x, PointLight)]
    nodes = [{"name": "sphere", "mesh": 0, "translation": list(s.center), "scale": [s.radius] * 3},
             _camera_node(scene)] + [
        {"name": f"light{i}", "translation": list(x.position), "extensions": {"KHR_lights_punctual": {"light": i}}}
        for i, x in enumerate(lights)]
    return {
        "asset": {"version": "2.0", "generator": gltf.GENERATOR,
                  "extras": {"brdfremap": {"resolution": scene.resolution, "spp": scene.spp, "seed": scene.seed,
                                           "units": "point light intensity: radiant intensity in W/sr, written as "
                                                    "candela; pixels: linear radiance; background black"}}},
        "extensionsUsed": EXTENSIONS, "scene": 0, "scenes": [{"nodes": list(range(len(nodes)))}], "nodes": nodes,
        "cameras": [{"type": "perspective", "perspective": {"yfov": math.radians(scene.camera.fov), "aspectRatio": 1.0,
                                                            "znear": 0.01 * d, "zfar": 100.0 * d}}],
        "meshes": [{"name": "sphere", "primitives": [{"attributes": attributes, "indices": indices, "material": 0}]}],
        "materials": [{"name": MATERIAL, "pbrMetallicRoughness": {"baseColorFactor": [ALBEDO] * 3 + [1.0],
                                                                   "metallicFactor": 0.0, "roughnessFactor": 1.0},
                       "extensions": {"KHR_materials_specular": {"specularFactor": 0.0}}}],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"type": "point", "color": [1.0, 1.0, 1.0], "intensity": x.intensity} for x in lights]}},
        "accessors": accessors, "bufferViews": views,
        "buffers": [{"byteLength": len(blob), "uri": "data:application/octet-stream;base64,"
                     + base64.b64encode(blob).decode()}]}


class GltfSceneWriter:
    name = "gltf"
    suffix = ".gltf"
    swap = ("glTF: the sphere's material is `material` (a white Lambertian: `KHR_materials_specular` factor 0): put "
            "yours in its place. Point lights are `KHR_lights_punctual`, their intensity the radiant intensity in W/sr "
            "written as candela (three.js reads it so); the environment shot has no glTF file (glTF has no "
            "environment light): render it from another format, or leave it out (unchecked).")

    @staticmethod
    def unavailable_reason() -> str | None:
        return None  # JSON: nothing to import

    def close(self) -> None:
        """Nothing held."""

    def write(self, scene: ProbeScene, path: Path, maps: dict[str, Path]) -> list[Path]:
        if scene.environment is not None:
            return []
        return [write_text_atomic(path, json.dumps(document(scene)))]
