"""One material model of one renderer, in one place.

A `Model` is the `ModelSpec` it declares (its parameters, bounds, defaults, lobes, what it can
render: smooth, transmissive, texturable) together with the conversions the exporters make for
it: how a material of this model reads in renderer-neutral terms (`appearance`), this model's
parameters for such a reading (`from_appearance`, the fit's informed start), the quantities that
follow from its parameters (`derive`) and what the renderer does to them that the image cannot
show the optimiser (`notes`). An adapter subclasses it once per model and adds the renderer's own
form of the material (Mitsuba's BSDF dictionary, Blender's node); the adapter holds its models by
name (`Adapter.models`) and the protocol passes the object. Reading or changing one model means
reading or changing one class.

The defaults here are a model with no reading: a renderer defined in YAML whose models declare
only their parameters (`adapters/subprocess`), or a model an exporter has no convention for.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from ..data.appearance import Appearance
from ..data.schemas import ModelSpec, ParamSpec, Value
from ..data.kinds import ParamKind


@dataclass(frozen=True)
class Rule:
    """A material's parameters for another model by a fixed rule its own format defines (an importer's
    table), and the rule in words."""

    name: str
    params: dict[str, Value]
    inputs: dict[str, str] = field(default_factory=dict)
    """Each of the other model's parameters that is one of this material's as it is (an image driving it
    drives the other's the same): the other's name, this one's."""


class Model(ModelSpec):
    """A renderer's material model: its declaration and its conversions (see the module)."""

    def appearance(self, params: dict[str, Value]) -> Appearance | None:
        """The material in renderer-neutral terms, as an exporter would read it, or None when this
        model has no such reading. ``params`` is complete. Used as a source: it gives the fit its
        informed start, and a library its choice of target model. Must not render."""
        return None

    def from_appearance(self, appearance: Appearance, base: dict[str, Value]) -> dict[str, Value]:
        """This model's parameters for a neutral description by the exporters' conventions (the
        fit's informed start; the fit corrects them), or {} when there is no such conversion.
        ``base`` is the model's complete parameters as they stand (defaults, --fix), for a
        conversion that depends on one the fit keeps. Only fitted parameters are used; values out
        of bounds are clipped by the caller. Must not render."""
        return {}

    def rule_for(self, target: "Model", params: dict[str, Value]) -> Rule | None:
        """This material's parameters for ``target`` by a fixed rule its format defines (a correspondence
        of its inputs to another renderer's model's: what an importer maps by name), or None. A fit to
        ``target`` starts from it, and its report gives the rule's error beside the fit's. ``params`` is
        complete. Must not render."""
        return None

    def approximations(self, params: dict[str, Value]) -> list[str]:
        """What this model's renderer draws of these parameters only approximately (a real-time
        renderer's subsurface or transmission), each in words: an image of it is the approximation, not
        what the parameters mean, and a result judged on it says so (verdict unchecked)."""
        return []

    def derive(self, params: dict[str, Value]) -> dict[str, Value]:
        """The quantities `derived` names, from complete parameters (a conductor's normal-incidence
        reflectivity from its complex IOR), for reports and experiment plots. Must not render."""
        return {}

    def notes(self, params: dict[str, Value]) -> list[str]:
        """What the renderer does to these parameters that the image cannot show the optimiser,
        e.g. a reflectance it trims to conserve energy. A note makes a fitted result unreliable."""
        return []


AS_WRITTEN = Model(
    name="as written",
    description="A material with no reading: rendered from its own file as written (`Material.native`), its "
                "parameters unknown to the tool. Nothing of it is fitted; it gives no start and chooses no target "
                "model (the target adapter's candidates are fitted, `Adapter.candidates`).",
    parameters=(ParamSpec(name="transmission", kind=ParamKind.SCALAR, default=0.0, fit=False,
                          description="1 where light may pass through it (a glass, a translucent or subsurface node "
                                      "in its graph): rendered with paths through the sphere."),),
    transmits_with="transmission",
)
"""The source model of a material rendered as written with no reading (`Material.native`, its `model` empty)."""
