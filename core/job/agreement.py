"""Whether a job's two renderers agree on its kind of material, under the lights it is judged by.

A remap's error is the model's only where both renderers draw the same thing alike. For opaque
materials the lights' calibration says they do (a white Lambertian within 0.3 % of the analytic
radiance under every light: tests/adapters/test_light_rendering.py). Light through a sphere is
another matter: an adapter without paths deep enough, or a renderer of other habits, draws a glass
otherwise whatever its model. So where either side transmits, each adapter's clear glass
(`Adapter.glasses`) is rendered under each condition the verdict judges: the smooth one where an
environment lights it (under a point light it is black), the rough one under point lights. Their
images are compared in 8 x 8 pixel blocks (light through a rough glass comes in rare bright
samples); beyond the noise and over the threshold, that condition's error is the renderers', not
the model's. Measurements are kept for the process: a library's glasses are rendered once.

Opaque or not, each adapter's white Lambertian (`Adapter.calibration`) is compared the same way
under each held-out condition: how far the two renderers differ on the simplest material there
(Cycles and Mitsuba 3.2 % under the rim light, a command-line renderer more) is a floor that a
material's error there is judged beyond, as it is judged beyond the render noise. A metal's floor
is measured on the two adapters' aluminium of its kind (`Adapter.metals`) where both declare it, a
glossy dielectric's on their glossy grey dielectric (`Adapter.dielectrics`) where both declare one
(adapters of one BRDF: three.js and Cycles' Principled BSDF)."""

from __future__ import annotations

from enum import StrEnum
from typing import Callable

import numpy as np

from ..data.appearance import Appearance, Kind
from ..data.metrics import beyond_noise, relative_rmse
from ..data.scene import EnvironmentLight, Lighting, PointLight, ProbeScene
from ..engine.results import WHITE, Agreement, Disagreement
from ..host.analytic import box_filtered_lambert
from ..host.check import ALBEDO
from ..host.judge import SAMPLING_TOLERANCE
from ..host.protocol import Adapter, check_image

BLOCK = 8
_MEASURED: dict[tuple, tuple] = {}
"""(error, noise floor) of two adapters' glasses at two scenes, kept for the process (a library's
glasses are rendered once); at most `KEEP` entries."""
KEEP = 256
FLOOR_MIN = 0.005
"""Two white Lambertians closer than this beyond their noise (0.5 %, a tenth of the threshold) make no
floor: subtracted in quadrature from a 5 % error it would change it by 0.03 points."""


def _blocks(img: np.ndarray) -> np.ndarray:
    n = img.shape[0] // BLOCK * BLOCK
    if n == 0:
        return img.astype(np.float64)
    return img[:n, :n].astype(np.float64).reshape(n // BLOCK, BLOCK, n // BLOCK, BLOCK, 3).mean(axis=(1, 3))


def _pair(adapter: Adapter, kind: str, scenes: tuple[ProbeScene, ProbeScene]) -> tuple[np.ndarray, np.ndarray]:
    name, given = adapter.glasses[kind]
    model = adapter.models[name]
    params = model.complete(given)
    return tuple(_blocks(check_image(adapter.render(model, params, sc), sc, f"adapter {adapter.name!r} {kind} glass"))
                 for sc in scenes)  # type: ignore[return-value]


def compare(one: Adapter, other: Adapter, condition: Lighting, label: str, scenes: tuple[ProbeScene, ProbeScene],
            threshold: float) -> Disagreement | None:
    """The two adapters' clear glasses under one condition (two renders each, at these two scenes'
    seeds): a Disagreement when they differ beyond the noise by more than ``threshold``."""
    kind = "smooth" if any(isinstance(x, EnvironmentLight) for x in scenes[0].lights) else "rough"
    key = (one.name, one.identity(), other.name, other.identity(), kind, scenes[0].cache_key(), scenes[1].cache_key())
    if key not in _MEASURED:
        a, b = _pair(one, kind, scenes), _pair(other, kind, scenes)
        if len(_MEASURED) >= KEEP:
            _MEASURED.pop(next(iter(_MEASURED)))
        if a[0].any() or b[0].any():
            _MEASURED[key] = (relative_rmse((a[0] + a[1]) / 2, (b[0] + b[1]) / 2),
                              float(np.hypot(relative_rmse(*a), relative_rmse(*b)) / 2))
        else:
            _MEASURED[key] = (0.0, 0.0)  # black in both: nothing drawn, nothing to disagree on
    err, floor = _MEASURED[key]
    far = beyond_noise(err, floor)
    if far <= threshold:
        return None
    return Disagreement(condition=condition, label=label, kind=f"{kind} glass", error=err, noise_floor=floor,
                        beyond_noise=far)


SMOOTH_METAL = 0.03
"""A metal of microfacet α below this is judged against the adapters' smooth aluminium (α 0.01),
from it on against their rough one (α 0.09): 0.03 lies between the two."""


class Reference(StrEnum):
    """The material a pair's floor is measured on, past the white Lambertian: a metal of each kind
    (`Adapter.metals`), a glossy dielectric (`Adapter.dielectrics`)."""

    SMOOTH_METAL = "smooth"
    ROUGH_METAL = "rough"
    GLOSSY_DIELECTRIC = "glossy"

    def declared(self, adapter: Adapter) -> dict[str, tuple[str, dict]]:
        return adapter.dielectrics if self == Reference.GLOSSY_DIELECTRIC else adapter.metals

    @property
    def words(self) -> str:
        return "glossy dielectric" if self == Reference.GLOSSY_DIELECTRIC else f"{self.value} metal"


def reference_kind(look: Appearance | None) -> Reference | None:
    """Which reference a material read as this is judged against: a smooth or rough metal, a glossy
    dielectric (a dielectric with a specular lobe no sharper than the smooth metal's, opaque), or None
    (the white Lambertian; or no reading)."""
    if look is None:
        return None
    sharp = (look.alpha or 0.0) < SMOOTH_METAL
    if look.kind == Kind.CONDUCTOR:
        return Reference.SMOOTH_METAL if sharp else Reference.ROUGH_METAL
    glossy = look.alpha is not None and max(look.specular) > 0.0 and look.transmission == 0.0
    return Reference.GLOSSY_DIELECTRIC if glossy and not sharp else None


def reference(adapter: Adapter, kind: Reference | None) -> tuple[str, dict] | None:
    """The material an adapter's floor is measured on: its reference of this kind where it declares
    one, else its white Lambertian."""
    return kind.declared(adapter)[kind.value] if kind is not None and kind.value in kind.declared(adapter) \
        else adapter.calibration


def _calibration_pair(adapter: Adapter, kind: Reference | None,
                      scenes: tuple[ProbeScene, ProbeScene]) -> tuple[np.ndarray, np.ndarray]:
    name, given = reference(adapter, kind)  # type: ignore[misc]
    model = adapter.models[name]
    params = model.complete(given)
    return tuple(check_image(adapter.render(model, params, sc), sc, f"adapter {adapter.name!r} calibration material")
                 .astype(np.float64) for sc in scenes)  # type: ignore[return-value]


def _kind(one: Adapter, other: Adapter, kind: Reference | str | None) -> Reference | None:
    """The reference of this kind both adapters declare, or None (their white Lambertians)."""
    kind = None if kind is None else Reference(kind)
    both = kind is not None and all(kind.value in kind.declared(a) for a in (one, other))
    return kind if both else None


def calibration_floor(one: Adapter, other: Adapter, condition: Lighting, label: str,
                      scenes: tuple[ProbeScene, ProbeScene], kind: Reference | str | None = None) -> Disagreement | None:
    """The two adapters' white Lambertians (or their references of this kind, where both declare one) under one
    condition (two renders each, at these two scenes' seeds), compared pixel by pixel: a Disagreement when they
    differ beyond the noise by `FLOOR_MIN` or more, naming the adapter whose white Lambertian is itself off its
    analytic image there (`_off_analytic`: its fault, not a floor)."""
    kind = _kind(one, other, kind)
    key = ("calibration", one.name, one.identity(), other.name, other.identity(), kind, scenes[0].cache_key(),
           scenes[1].cache_key())
    if key not in _MEASURED:
        a, b = _calibration_pair(one, kind, scenes), _calibration_pair(other, kind, scenes)
        if len(_MEASURED) >= KEEP:
            _MEASURED.pop(next(iter(_MEASURED)))
        err, floor = (relative_rmse((a[0] + a[1]) / 2, (b[0] + b[1]) / 2),
                      float(np.hypot(relative_rmse(*a), relative_rmse(*b)) / 2)) if a[0].any() else (0.0, 0.0)
        own = _off_analytic({one.name: a, other.name: b}, scenes[0]) \
            if kind is None and beyond_noise(err, floor) >= FLOOR_MIN else None
        _MEASURED[key] = (err, floor, own)
    err, floor, own = _MEASURED[key]
    far = beyond_noise(err, floor)
    if far < FLOOR_MIN:
        return None
    return Disagreement(condition=condition, label=label, kind=WHITE if kind is None else kind.words,
                        error=err, noise_floor=floor, beyond_noise=far, own=own[0] if own else "",
                        own_error=own[1] if own else 0.0)


def _off_analytic(pairs: dict[str, tuple[np.ndarray, np.ndarray]], scene: ProbeScene) -> tuple[str, float] | None:
    """(adapter, error beyond its noise) of the adapter whose white Lambertian (two seeds' renders) is furthest
    from its box-filtered analytic image, where that is beyond `judge.SAMPLING_TOLERANCE` (`remap check`'s
    sampling row would fail); None where both are within it or the scene has no analytic image (several views,
    a backdrop)."""
    if scene.views or any(not isinstance(x, (PointLight, EnvironmentLight)) for x in scene.lights):
        return None
    want = box_filtered_lambert(scene, ALBEDO).astype(np.float64)
    found = {name: beyond_noise(relative_rmse(want, (a + b) / 2), relative_rmse(a, b) / 2)
             for name, (a, b) in pairs.items()}
    worst = max(found, key=found.get)
    return (worst, found[worst]) if found[worst] > SAMPLING_TOLERANCE else None


def calibration_floors(source: Adapter, target: Adapter,
                       conditions: list[tuple[str, str, tuple[ProbeScene, ProbeScene]]],
                       kind: Reference | str | None = None) -> dict[str, Disagreement]:
    """How far the two renderers differ on a white Lambertian (or their references of this kind)
    under each held-out condition (not the fit scene, whose differences the fit absorbs): measured once
    a process for each pair, reference and scene. None where an adapter declares no such material, or
    both sides are one renderer."""
    both = _kind(source, target, kind)
    if getattr(source, "unmetered", source) is getattr(target, "unmetered", target) or \
            reference(source, both) is None or reference(target, both) is None:
        return {}
    found = (calibration_floor(source, target, name, label, scenes, kind)
             for name, label, scenes in conditions if name != Lighting.SCENE)
    return {d.condition: d for d in found if d is not None}


def agreement(source: Adapter, target: Adapter, transmissive: bool,
              conditions: list[tuple[str, str, tuple[ProbeScene, ProbeScene]]], threshold: float,
              judged: Callable[[str], bool] = lambda c: True, kind: Reference | str | None = None) -> Agreement:
    """Whether the two adapters agree under these conditions (name, label, two scenes of other seeds)
    on a material of this kind; ``judged(name)``: whether the verdict judges that condition; ``kind``:
    the reference the source is judged against (`reference_kind`), None for the white Lambertian."""
    floors = calibration_floors(source, target, [c for c in conditions if judged(c[0])], kind)
    if not transmissive or getattr(source, "unmetered", source) is getattr(target, "unmetered", target):
        return Agreement(floors=floors)
    lacking = [a.name for a in (source, target) if not {"smooth", "rough"} <= set(a.glasses)]
    if lacking:
        return Agreement(unchecked=f"adapter {' and '.join(repr(n) for n in lacking)} declares no clear glasses "
                                   "(Adapter.glasses), so their light through a sphere is not compared", floors=floors)
    found = [compare(source, target, name, label, scenes, threshold)
             for name, label, scenes in conditions if judged(name)]
    return Agreement(checked=True, disagree=[d for d in found if d is not None], floors=floors)
