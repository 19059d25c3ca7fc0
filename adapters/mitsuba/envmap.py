"""The scene's environment maps as Mitsuba's `envmap` reads them.

Mitsuba's envmap looks a direction up with its map's first and last rows at the poles (v = 0
and 1 on the rows' centres), where the project's convention (`core.data.environment`, and Cycles)
puts row centres at (i + 0.5) / H: read as it is, every feature of a map lands up to half a
row off, which a mirror shows and a lens (a glass sphere) magnifies (a perfect mirror under
the studio: 2.45 % from the analytic image, 1.07 % with the map resampled, as Cycles' 1.08 %;
docs/measurements/transport.md). Columns agree. So Mitsuba is given the map resampled: 2H + 1 rows at
v = j / 2H, on which its linear interpolation is the convention's exactly (the convention's
rows are linear between its row centres, each of which is one of these rows)."""

from __future__ import annotations

import numpy as np


def mitsuba_rows(px: np.ndarray) -> np.ndarray:
    """An H x W x 3 map in the project's convention as the (2H + 1) x W x 3 map Mitsuba reads alike."""
    h = px.shape[0]
    y = np.clip(np.arange(2 * h + 1) / 2.0 - 0.5, 0.0, h - 1)  # v = j / 2h in the convention's rows
    y0 = np.floor(y).astype(int)
    y1 = np.minimum(y0 + 1, h - 1)
    f = (y - y0)[:, None, None]
    return np.ascontiguousarray(((1 - f) * px[y0] + f * px[y1]).astype(np.float32))
