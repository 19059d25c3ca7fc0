"""A second choice of model. Where the model the target adapter chose for a material (`model_for`)
comes back a mismatch or unreliable, the adapter's other models that may follow that reading closer
(`Adapter.alternatives`) are fitted too, each in a slot of its own beside the first, and the best
result is kept: by verdict (ok, unchecked, mismatch, unreliable), then by the fit's error. What was
tried and why the kept one won is said in the material's `model_why` (the report, `convert.json`)."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import TYPE_CHECKING

from ..data.appearance import Appearance
from ..data.errors import RemapError
from ..data.schemas import ModelSpec, Need
from ..host.model import Model
from ..host.protocol import ModelChoice
from ..run.runner import Done, Task
from .records import ItemStatus

if TYPE_CHECKING:
    from .convert import Item

RANK = {ItemStatus.OK: 0, ItemStatus.UNCHECKED: 1, ItemStatus.MISMATCH: 2, ItemStatus.UNRELIABLE: 2}
"""A mismatch and an unreliable result rank alike, by their worst error (the fit scene's or a held-out
light's, `Tried.worst`): neither is to be trusted as it stands, a fit 5 % off whose held-out lights are 40 %
off is worse than a mismatch 16 % off everywhere, and a fit 0.1 % off whose rim light parts 18 % from the
source's at a noisy floor is better than a model 50 % off (a node group's Principled BSDF, fitted from no
reading, was kept as a Diffuse BSDF when the verdict ranked first)."""
RETRY = (ItemStatus.MISMATCH, ItemStatus.UNRELIABLE)
"""The verdicts that send a material to the adapter's other models."""


@dataclass(frozen=True)
class Tried:
    """One model fitted for a material, and what it came to."""

    model: str
    why: str
    done: Done

    @classmethod
    def of(cls, choice: ModelChoice, done: Done) -> Tried:
        return cls(choice.model, choice.why, done)

    @property
    def status(self) -> ItemStatus:
        return ItemStatus.FAILED if self.done.report is None else ItemStatus(self.done.report.verdict)

    @property
    def error(self) -> float:
        return math.inf if self.done.report is None else self.done.report.metrics.relative_rmse

    @property
    def worst(self) -> float:
        """The largest of its errors: the fit scene's and each held-out condition's."""
        if self.done.report is None:
            return math.inf
        held = [c.error for c in getattr(self.done.report, "validation", None) or ()]
        return max([self.error, *held])

    def rank(self) -> tuple[int, float, float]:
        return RANK.get(self.status, len(RANK)), self.worst if RANK.get(self.status) == 2 else 0.0, self.error

    def said(self) -> str:
        return f"{self.model} {self.error:.1%} {self.status}" if self.done.report else f"{self.model} failed"


def _tag(choice: ModelChoice) -> str:
    words = [choice.model, *(str(v) for v in choice.fix.values())]
    return re.sub(r"[^A-Za-z0-9._-]+", "_", "-".join(words))


def retries(items: list[Item], adapter, make_task) -> list[tuple[Item, ModelChoice, Task]]:
    """For each material whose chosen model came back a mismatch or unreliable, a task per other model
    ``adapter`` offers for its reading; ``make_task(item, slot, choice, title)`` makes one."""
    out = []
    for item in items:
        if item.status not in RETRY or (item.look is None and not item.candidates):
            continue
        others = adapter.alternatives(item.look) if item.look is not None else item.candidates[1:]
        for choice in others:
            title = f"{item.entry.name} (also {_tag(choice)}: {item.model} came back {item.status})"
            try:
                out.append((item, choice, make_task(item, f"{item.slot}~{_tag(choice)}", choice, title)))
            except RemapError as exc:  # an alternative the job cannot take: said, and the others go on
                item.why = f"{item.why}; {_tag(choice)} not tried: {exc}"
    return out


def lacks(look: Appearance, spec: ModelSpec) -> list[str]:
    """What the source's reading has that this target model cannot render, from its declared
    parameters: a microfacet distribution not among its choices, a need (`Appearance.needs`) no input
    of it is declared for. What would do better: a model (of another renderer) that has them."""
    out = []
    choices = next((p.choices for p in spec.parameters if p.name == "distribution"), ())
    if look.distribution is not None and choices and look.distribution not in choices:
        out.append(f"its {look.distribution} lobe ({spec.name} has {', '.join(choices)} only)")
    served = {need for p in spec.parameters for need in p.fit_for} | (
        {Need.EDGE_TINT} if spec.complex_ior is not None else set())  # a complex IOR has its own edge
    out += [f"{why} (no input of {spec.name} renders it)" for need, why in look.needs().items() if need not in served]
    return out


_FEATURES = (("coat", lambda a: a.coat is not None), ("sheen", lambda a: a.sheen is not None),
             ("anisotropy", lambda a: a.anisotropy > 0.0), ("transmission", lambda a: a.transmission > 0.0))


def dropped(look: Appearance, spec: Model) -> list[str]:
    """What of the reading the model drops, by the adapter's own readings: the reading converted to
    the model's parameters (`from_appearance`) and read back (`appearance`) has no coat, sheen,
    anisotropy or transmission where the source has one, or another diffuse lobe."""
    try:
        back = spec.appearance(spec.complete(spec.from_appearance(look, spec.complete({}))))
    except (RemapError, ValueError):  # a conversion out of the model's bounds: nothing to say from it
        return []
    if back is None:
        return []
    out = [f"its {name} ({spec.name} has none)" for name, has in _FEATURES if has(look) and not has(back)]
    if look.diffuse_model != back.diffuse_model and max(look.diffuse) > 0.0:
        out.append(f"its {look.diffuse_model.value} diffuse ({spec.name}'s is {back.diffuse_model.value})")
    return out


def advise(item: Item, spec: Model, adapter: str) -> None:
    """Say, for a kept result still a mismatch or unreliable, what would do better: what the chosen model
    lacks by the reading (`lacks`, `dropped`), else that no other model of the adapter was offered."""
    if item.look is None or item.status not in RETRY:
        return
    missing = lacks(item.look, spec) + dropped(item.look, spec)
    if missing:
        item.why = f"{item.why}; what {spec.name} lacks for it: {'; '.join(dict.fromkeys(missing))}"
    elif len(item.tried) < 2:
        item.why = f"{item.why}; no other model of {adapter} is offered for it: the closest {spec.name} gets"


def keep_best(item: Item) -> None:
    """Keep the best of the material's fits (its first, then ``item.tried``), and say what was tried."""
    first = Tried(item.model, item.why, item.done)
    tried = [first, *item.tried]
    best = min(tried, key=Tried.rank)
    others = ", ".join(t.said() for t in tried if t is not best)
    if best is first:
        item.why = f"{item.why}; also tried {others}: none closer"
    else:
        item.model, item.slot, item.done = best.model, best.done.task.slot, best.done
        item.why = f"{best.why}: kept over {others}"
    item.tried = tried
