"""What the engine asks of the outside world: the problem at one resolution and sampling.

The engine never renders by itself: it asks a `Renders` for a `Level` (the target's render
function there and the source's images), for the source's render noise, and at the end for
the target's noise and what the renderer does to the fitted values. `core.job.renders` builds one
from two adapters; tests build one from a toy adapter the same way."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Protocol

import numpy as np

from ..data.metrics import l2
from ..data.scene import ProbeScene
from ..data.schemas import Value
from .results import Agreement, Validation

RenderFn = Callable[[dict[str, Value], "str | None"], np.ndarray]
ProgressFn = Callable[[str, int, float], None]
"""progress(stage name, target renders so far, best error so far)."""


@dataclass(frozen=True)
class Level:
    """One resolution and sampling of the problem: the target's render function and the source images.

    ``source_lobes`` holds the source's diffuse-only and specular-only images (None where the
    source cannot isolate a lobe; an all-zero image where it has no such lobe)."""

    render: RenderFn
    source: np.ndarray
    source_lobes: dict[str, np.ndarray | None] = field(default_factory=dict)
    spp: int = 0

    @property
    def resolution(self) -> int:
        """The image width (a scene of several views stacks them vertically)."""
        return int(self.source.shape[1])

    @property
    def norm(self) -> float:
        """Residuals of every stage at this level are divided by the full source image's norm."""
        return l2(np.asarray(self.source, dtype=np.float64))

    def image(self, key: str | None) -> np.ndarray:
        """The source image a stage matches: the full one (None) or a lobe's."""
        if key is None:
            return self.source
        lobe = self.source_lobes.get(key)
        if lobe is None:
            raise KeyError(key)
        return lobe


class Renders(Protocol):
    """The renders one remap needs. Implementations cache images and count target renders."""

    scene: ProbeScene

    def level(self, scene: ProbeScene, lobes: bool = True) -> Level:
        """The problem at ``scene``'s resolution and sampling (``lobes``: render the source's lobes too)."""

    def source_noise(self) -> float:
        """Relative RMSE between two renders of the source that differ only in the seed."""

    def target_noise(self, params: dict[str, Value]) -> float:
        """The same for the target with ``params``."""

    def scene_chosen(self) -> bool:
        """Whether the fit's scene was chosen for the source (more samples, the studio) rather than
        being the job's own."""

    def validation(self, params: dict[str, Value]) -> Validation:
        """Source and target with ``params`` under held-out lights the fit never saw."""

    def agreement(self, params: dict[str, Value], validation: Validation, threshold: float, judged) -> Agreement:
        """Whether the two renderers agree on this kind of material (the source's, and the target's with
        ``params``) under the fit scene and the
        held-out conditions ``judged(condition)`` says the verdict judges (`core.job.agreement`)."""

    def held_out(self) -> list[tuple[str, str, ProbeScene]]:
        """Every held-out condition the target renders, judged or not: (name, label, one scene)."""

    def target_at(self, params: dict[str, Value], scene: ProbeScene) -> np.ndarray:
        """The target with ``params`` at ``scene`` (cached)."""

    def notes(self, params: dict[str, Value]) -> list[str]:
        """What the target renderer does to these values that the image cannot show (a trim)."""

    def approximations(self, params: dict[str, Value]) -> list[tuple[str, str]]:
        """(side, what) each side's renderer draws only approximately of its material (the source's,
        the target at these values): a real-time renderer's subsurface or transmission."""

    def target_renders(self) -> int:
        """Target renders made so far (repeats served from a cache not counted)."""
