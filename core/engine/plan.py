"""Which stages a scheme runs: the paper's one-, two- and three-stage schemes, and auto."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..data.findings import SchemeChosen
from ..data.schemas import Lobe, ModelSpec
from ..data.settings import Scheme


@dataclass(frozen=True)
class PlannedStage:
    name: str
    lobe: str | None
    """The lobe the target renders alone (None: the full material)."""
    free: list[str]
    source: str | None
    """The source image it matches: a lobe's (its name) or the full image (None)."""


@dataclass(frozen=True)
class Plan:
    scheme: Scheme
    """The scheme actually used: one, two or three."""
    stages: list[PlannedStage]
    findings: list[SchemeChosen]


def lobes_split(target: ModelSpec, free: list[str]) -> bool:
    """Whether the lobes divide the free parameters: each non-empty lobe has one of its own. When
    one lobe's parameters all shape the other too (Principled: Base Color and Metallic are also
    the metal's specular colour), the second stage would only refit the first's parameters on
    the full image: one stage from several starts measured as good, in fewer renders."""
    if not target.has_lobes:
        return False
    shares = [set(target.lobes[lobe].params) & set(free) for lobe in (Lobe.SPECULAR, Lobe.DIFFUSE)
              if not target.lobes[lobe].empty]
    lobes = [s for s in shares if s]  # a lobe with every parameter held divides nothing
    return len(lobes) < 2 or all(a - b for a, b in (lobes, lobes[::-1]))


def plan_stages(scheme: Scheme, target: ModelSpec, free: list[str],
                source_lobes: dict[str, np.ndarray | None]) -> Plan:
    findings = []
    if scheme == Scheme.AUTO:
        scheme = Scheme.TWO if lobes_split(target, free) else Scheme.ONE
        if scheme == Scheme.ONE:
            why = (f"target model {target.name!r} declares no lobes" if not target.has_lobes else
                   f"every {target.name!r} parameter of one lobe also shapes the other")
            findings.append(SchemeChosen(scheme=Scheme.ONE, why=why))
    if scheme == Scheme.ONE:
        return Plan(Scheme.ONE, [PlannedStage("all", None, list(free), None)], findings)
    can_split = target.has_lobes and all(source_lobes.get(lobe) is not None for lobe in Lobe)
    if not can_split:
        why = (f"target model {target.name!r} declares no lobes" if not target.has_lobes
               else "the source model cannot render its lobes separately")
        findings.append(SchemeChosen(scheme=Scheme.ONE, why=f"{scheme}-stage scheme needs lobe isolation: {why}",
                                     fallback=True))
        return Plan(Scheme.ONE, [PlannedStage("all", None, list(free), None)], findings)
    stages = _lobe_stages(target, free)
    if scheme == Scheme.THREE:
        stages.append(PlannedStage("joint", None, list(free), None))
    return Plan(scheme, stages, findings)


def _lobe_stages(target: ModelSpec, free: list[str]) -> list[PlannedStage]:
    stages: list[PlannedStage] = []
    empty = [lobe for lobe in (Lobe.SPECULAR, Lobe.DIFFUSE) if target.lobes[lobe].empty]
    fitted: set[str] = set()
    for lobe in (Lobe.SPECULAR, Lobe.DIFFUSE):
        spec = target.lobes[lobe]
        if spec.empty:
            continue
        params = [p for p in free if p in spec.params]
        # A lobe the target lacks is folded into the other one: fit it against the full image.
        # A parameter the first stage already fitted shapes both lobes (Base Color is also a
        # metal's specular colour): refitting it on one lobe alone would undo the other, so
        # such a stage matches the full image with the first stage's parameters held.
        isolate = not empty and not (fitted & set(params))
        stages.append(PlannedStage(lobe, lobe if isolate else None, params, lobe if isolate else None))
        fitted |= set(params)
    leftover = [p for p in free if p not in fitted]
    if leftover and stages:
        first = stages[0]
        stages[0] = PlannedStage(first.name, first.lobe, first.free + leftover, first.source)
    return stages
