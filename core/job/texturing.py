"""A textured source's job, past its uniform lookup, as the job sees it: the record `result.json`
keeps (the target's maps, the textured check under each condition), what the verdict reads of it,
and the step that makes it (`TexturedStep`), which the job is given by whoever resolved it: the
texel-by-texel remap through a table lives above the job and the tables (`core.textured`).

A target parameter that varies over the texture but that the target renderer takes only as a
number (its model does not list it as `texturable`) is written as its mean, and the record says so."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import numpy as np
from pydantic import Field

from ..data.model import Strict
from ..data.scene import Lighting
from ..data.textures import Texture
from ..host.protocol import Adapter


class MapRecord(Strict):
    param: str
    file: str = Field(description="The map's file beside result.json.")
    colorspace: str = Field(description="srgb (a colour map, 16-bit PNG) or linear (a data map).")
    low: float = Field(description="Its lowest value (any channel).")
    high: float = Field(description="Its highest value.")


class TexturedCheck(Strict):
    """The textured source and the textured result on the probe sphere, each by its own renderer."""

    condition: Lighting = Field(description="scene (the job's lights: where the highlight runs over the texture) or "
                                            "environment (the studio: every texel lit).")
    resolution: int
    spp: int
    error: float = Field(description="Relative RMSE of the textured result against the textured source.")
    perceptual: float = Field(description="Mean ΔE_ITP over the lit pixels.")
    noise_floor: float
    beyond_noise: float


class Textured(Strict):
    """`result.json`'s record of a textured source remapped texel by texel through a table."""

    table: str
    inputs: dict[str, str] = Field(description="Each textured source input and its image file.")
    width: int
    height: int
    maps: list[MapRecord] = Field(description="The target's maps, written beside the native material.")
    constants: dict[str, Any] = Field(default_factory=dict, description="Target parameters uniform over the "
                                                                        "texture (written as numbers).")
    values: dict[str, Any] = Field(default_factory=dict, description="The native material's numbers: the lookup's, "
                                                                    "with the constants and the held means.")
    held: dict[str, str] = Field(default_factory=dict, description="Target parameters that vary over the texture "
                                                                   "but the target takes only as a number: their "
                                                                   "mean is written, and why.")
    outside: list[str] = Field(default_factory=list, description="Texel values outside the table's range (clamped).")
    notes: list[str] = Field(default_factory=list)
    seconds: float = Field(description="The texel-by-texel remap (reading and writing the images aside).")
    checks: list[TexturedCheck] = Field(default_factory=list, description="The textured check under each condition.")
    check_skipped: str = Field("", description="Why the textured check was not rendered.")


@dataclass
class Texturing:
    record: Textured
    files: dict[str, bytes]
    native: dict[str, Texture]
    """Target parameter -> its map (a file name of ``files``), for the native material."""
    params: dict[str, Any]
    """The native material's numbers: the fit's, with the constants and held means."""
    images: tuple[np.ndarray, np.ndarray] | None = None
    """The textured source and result under the studio environment (the check's images)."""


TexturedStep = Callable[[Any, "Adapter | None", Adapter, dict[str, Any]], Texturing]
"""A textured job's remap and check: (the resolved job, the source's adapter or None for no check (`remap
--table --no-render`), the target's adapter, the target's parameters) -> `Texturing`."""


def textured_findings(record: Textured, threshold: float, resolve_limit: float) -> list:
    """What the textured check and the remap say for the verdict: the conditions (resolved by their
    noise) where the textured result is over the threshold beyond the noise; the means written and
    the texels clamped, as a note."""
    from ..data.findings import TexturedAbove, TexturedCondition, TexturedNotes

    above = [TexturedCondition(condition=c.condition, error=c.error, beyond_noise=c.beyond_noise)
             for c in record.checks if c.noise_floor <= resolve_limit and c.beyond_noise > threshold]
    out: list = [TexturedAbove(conditions=above, threshold=threshold)] if above else []
    if record.held or record.outside:
        out.append(TexturedNotes(held=list(record.held.values()), outside=list(record.outside)))
    return out
