"""Image error metrics over linear RGB images (H x W x 3)."""

from __future__ import annotations

import numpy as np

_709_TO_2020 = np.array(
    [[0.6274040, 0.3292820, 0.0433136], [0.0690970, 0.9195400, 0.0113612], [0.0163916, 0.0880132, 0.8955950]]
)
_2020_TO_LMS = np.array([[1688, 2146, 262], [683, 2951, 462], [99, 309, 3688]]) / 4096.0
_LMS_TO_ITP = np.array([[0.5, 0.5, 0.0], [6610, -13613, 7003], [17933, -17390, -543]]) / np.array([[1], [4096], [4096]])
_LUMA = np.array([0.2126, 0.7152, 0.0722])
REFERENCE_WHITE_NITS = 100.0


def l2(x: np.ndarray) -> float:
    """The Euclidean norm, summed by numpy (pairwise) rather than by BLAS: `np.linalg.norm` of a long
    vector is a BLAS dot whose summation order follows its thread count, so one image gave errors one
    unit in the last place apart in a Dask worker (one BLAS thread) and in the main process."""
    v = np.asarray(x, dtype=np.float64).ravel()
    return float(np.sqrt(np.sum(v * v)))


def relative_rmse(reference: np.ndarray, test: np.ndarray) -> float:
    """The paper's L2 metric: ||test - reference|| / ||reference|| over all pixels and channels."""
    ref = np.asarray(reference, dtype=np.float64)
    diff = np.asarray(test, dtype=np.float64) - ref
    norm = l2(ref)
    if norm == 0.0:
        return l2(diff)
    return l2(diff) / norm


def beyond_noise(error: float, noise_floor: float) -> float:
    """The part of an error the render noise does not explain: sqrt(max(0, e² - floor²)), where
    the floor is the error two renders of one material show (independent noise adds in squares)."""
    return float(np.sqrt(max(0.0, error**2 - noise_floor**2)))


def _pq(y: np.ndarray) -> np.ndarray:
    m1, m2 = 2610 / 16384, 2523 / 4096 * 128
    c1, c2, c3 = 3424 / 4096, 2413 / 4096 * 32, 2392 / 4096 * 32
    yp = np.power(np.clip(y, 0.0, 1.0), m1)
    return np.power((c1 + c2 * yp) / (1 + c3 * yp), m2)


def _itp(rgb709_nits: np.ndarray) -> np.ndarray:
    rgb2020 = rgb709_nits @ _709_TO_2020.T
    lms = _pq(np.clip(rgb2020 @ _2020_TO_LMS.T, 0.0, None) / 10000.0)
    ictcp = lms @ _LMS_TO_ITP.T
    return ictcp * np.array([1.0, 0.5, 1.0])  # ITP: T = 0.5 Ct


def exposure(reference: np.ndarray) -> float:
    """Scale that maps the reference's bright end (99.9th percentile luminance) to 1."""
    lum = np.asarray(reference, dtype=np.float64) @ _LUMA
    top = float(np.percentile(lum, 99.9))
    return 1.0 / top if top > 0 else 1.0


def delta_e_itp_map(reference: np.ndarray, test: np.ndarray) -> np.ndarray:
    """Per-pixel ΔE_ITP (ITU-R BT.2124); 1 is about one just-noticeable difference.

    Scene-referred images have no absolute scale, so both are exposed alike: the reference's
    99.9th-percentile luminance becomes reference white (100 cd/m²)."""
    k = exposure(reference) * REFERENCE_WHITE_NITS
    a = _itp(np.asarray(reference, dtype=np.float64) * k)
    b = _itp(np.asarray(test, dtype=np.float64) * k)
    return 720.0 * np.sqrt(((a - b) ** 2).sum(axis=-1))


def delta_e_itp(reference: np.ndarray, test: np.ndarray) -> float:
    """Mean ΔE_ITP over the object: pixels lit in either image (the black background would
    only dilute the mean)."""
    dmap = delta_e_itp_map(reference, test)
    lit = (np.asarray(reference).max(axis=-1) > 0) | (np.asarray(test).max(axis=-1) > 0)
    return float(dmap[lit].mean()) if lit.any() else 0.0



CLIP_MIN_PIXELS, CLIP_MIN_FRACTION = 8, 0.002
"""A plateau at the image's maximum this large is clipping: float renders of a highlight peak in
one or a few pixels (an analytic sphere's symmetry ties at most four)."""


def clipped_at(img: np.ndarray) -> tuple[float, int] | None:
    """(value, pixels) when the image's largest values sit on one plateau at or below 1: an image
    written with a ceiling (8-bit, or a display transform); else None."""
    a = np.asarray(img, np.float32)
    lit = a.max(axis=-1)
    top = float(lit.max()) if lit.size else 0.0
    if not 0.0 < top <= 1.0 + 1e-6:
        return None
    n = int(np.count_nonzero(lit >= top * (1 - 1e-6)))
    lit_n = int(np.count_nonzero(lit > 0))
    # A clipped image also has lit pixels below its ceiling; one whose every lit pixel is equal (a
    # white sphere under a constant environment) is uniform, not clipped.
    below = lit_n - n
    return (top, n) if n >= max(CLIP_MIN_PIXELS, CLIP_MIN_FRACTION * lit_n) and below >= 0.1 * lit_n else None


def _srgb_decode(x: np.ndarray) -> np.ndarray:
    return np.where(x <= 0.04045, x / 12.92, ((x + 0.055) / 1.055) ** 2.4)


def _srgb_encode(x: np.ndarray) -> np.ndarray:
    return np.where(x <= 0.0031308, x * 12.92, 1.055 * np.power(np.maximum(x, 0), 1 / 2.4) - 0.055)


def eight_bit(img: np.ndarray) -> str:
    """"sRGB" or "linear" when every value is one of 256 levels of that encoding (an 8-bit image),
    else "". Only for an image of more than 256 lit pixels and 32 distinct values."""
    v = np.unique(np.asarray(img, np.float64).ravel())
    if not 32 <= v.size <= 256 or np.count_nonzero(np.asarray(img) > 0) <= 256 or v.max() > 1 + 1e-6:
        return ""  # fewer than 32 distinct values prove nothing (a uniform sphere is one)
    if np.allclose(np.round(v * 255) / 255, v, atol=1e-6):
        return "linear"
    if np.allclose(_srgb_decode(np.round(_srgb_encode(v) * 255) / 255), v, atol=1e-6):
        return "sRGB"
    return ""
