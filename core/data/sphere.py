"""The written libraries' sphere as a triangle mesh (glTF's and USD's spheres): geometry only, in
the probe's texture-coordinate convention (`core.data.textures`)."""

from __future__ import annotations

import math

import numpy as np

RINGS, SEGMENTS = 64, 128


def sphere_mesh(rings: int = RINGS, segments: int = SEGMENTS) -> dict[str, np.ndarray]:
    """A UV sphere of radius 1, its pole along +y: positions, normals, the probe's texture coordinates
    (`core.data.textures`: u = φ / 2π from +x, increasing away from a viewer on +z; v = θ / π from the
    top pole), tangents along the latitudes (the probe's: anisotropy turns from them) and triangle
    indices, counter-clockwise seen from outside."""
    theta, phi = np.meshgrid(np.linspace(0.0, math.pi, rings + 1), np.linspace(0.0, 2.0 * math.pi, segments + 1),
                             indexing="ij")
    s, c = np.sin(theta), np.cos(theta)
    pos = np.stack([s * np.cos(phi), c, -s * np.sin(phi)], axis=-1).reshape(-1, 3)
    tangent = np.stack([-np.sin(phi), np.zeros_like(phi), -np.cos(phi)], axis=-1).reshape(-1, 3)  # d(pos)/d(phi)
    uv = np.stack([phi / (2 * math.pi), theta / math.pi], axis=-1).reshape(-1, 2)
    idx = []
    for i in range(rings):
        for j in range(segments):
            a, b = i * (segments + 1) + j, (i + 1) * (segments + 1) + j
            if i > 0:
                idx += [a, b, a + 1]
            if i < rings - 1:
                idx += [a + 1, b, b + 1]
    return {"POSITION": pos.astype(np.float32), "NORMAL": pos.astype(np.float32),
            "TANGENT": np.concatenate([tangent, np.ones((pos.shape[0], 1))], axis=1).astype(np.float32),
            "TEXCOORD_0": uv.astype(np.float32), "indices": np.asarray(idx, np.uint16)}
