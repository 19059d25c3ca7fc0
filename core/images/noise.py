"""The render noise of one image, estimated from the image itself, for a shot given with one seed (the
difference of two seeds is the measure; this is the fallback, and a result says which it used).

Immerkær's estimator (1996): the image convolved with a kernel that cancels every plane and smooth ramp
leaves the noise, whose mean absolute value gives its standard deviation; over the sphere's interior (two
pixels in from its edge, which the kernel would read as noise). On the exported scenes rendered by
Mitsuba and by Blender it is a quarter to seven times two seeds' difference (`bench/images_noise.py`: a
rim light's thin crescent reads as noise, a smooth shading hides some): a rough estimate, said as one."""

from __future__ import annotations

import numpy as np
from scipy.ndimage import binary_erosion, convolve

KERNEL = np.array([[1, -2, 1], [-2, 4, -2], [1, -2, 1]], np.float64)


def estimated_noise(img: np.ndarray) -> float:
    """The relative RMSE two renders like this one would differ by (as `relative_rmse` of two seeds)."""
    px = np.asarray(img, np.float64)
    inside = binary_erosion(px.sum(axis=2) > 0, iterations=2)
    norm = float(np.linalg.norm(px))
    if not inside.any() or norm == 0:
        return 0.0
    variance = 0.0
    for c in range(px.shape[2]):
        sigma = np.sqrt(np.pi / 2) * float(np.abs(convolve(px[..., c], KERNEL, mode="constant"))[inside].mean()) / 6
        variance += float(inside.sum()) * sigma ** 2
    return float(np.sqrt(2 * variance) / norm)
