"""Every value a material gives counts: for every model of both adapters, each parameter given
alone away from its default changes the render, implies the choice it needs (alpha_u: anisotropic),
or is refused in one line; or the model declares it inert there (`ParamSpec.inert_when`: a coat's
roughness with no coat), and then it counts once that condition is lifted."""

import numpy as np
import pytest
from brdfremap.core.data.errors import ConfigError
from brdfremap.core.data.scene import EnvironmentLight, ProbeScene

SCENE = ProbeScene(lights=[EnvironmentLight(type="environment", map="studio")], resolution=32, spp=16)
"""Where every model shows (a mirror as much as a Lambertian): the studio environment."""


def _moved(p):
    """A value of parameter ``p`` well away from its default."""
    if p.kind == "choice":
        return next(c for c in p.choices if c != p.default)
    lo, hi = p.lower, min(p.upper, max(p.lower + 4.0, 1.0))  # unbounded-ish (eta to 8): a visible step
    if p.kind == "rgb":
        d = p.default
        return (hi if d[0] < (lo + hi) / 2 else lo + 0.1 * (hi - lo), *d[1:])
    d = float(p.default)
    if p.scale == "log":
        return min(d * 4, hi) if d * 4 <= hi else d / 4
    return d + 0.4 * (hi - lo) if d < (lo + hi) / 2 else d - 0.4 * (hi - lo)


def _cases(adapter):
    for model, spec in adapter.models.items():
        for p in spec.parameters:
            yield model, spec, p


def _settings(spec, p) -> list[dict]:
    """The other values a parameter is tried with: none (the defaults), and every number moved (a tint
    towards a grey base colour tints nothing; an energy safeguard acts only past a bound); for a
    choice, also the values that count only with its new value (alpha_u once anisotropic)."""
    numbers = {q.name: _moved(q) for q in spec.parameters
               if q.kind != "choice" and not q.active_when and q.name != p.name}
    if p.kind != "choice":
        return [{}, numbers]  # a tint towards a grey base colour tints nothing: every number moved
    new = _moved(p)
    dependents = {q.name: _moved(q) for q in spec.parameters
                  if q.kind != "choice" and new in q.active_when.get(p.name, ())}
    return [{}, dependents, numbers]


def _check(adapter, model, spec, p) -> str | None:
    """None when the value counts (or is refused); else what is wrong."""
    for others in _settings(spec, p):
        try:
            params = spec.complete(spec.settle({**others, p.name: _moved(p)}))
        except ConfigError as exc:  # refused: in one line naming the value
            assert p.name in str(exc) and "\n" not in str(exc), str(exc)
            return None
        if spec.is_inert(p.name, params):  # declared: then it must count once the condition is lifted
            others = {**others, **{k: _moved(spec.param(k)) for k in p.inert_when}}
            params = spec.complete(spec.settle({**others, p.name: _moved(p)}))
        base = {**params, p.name: p.default}  # the choices it implied kept: only the value itself differs
        if not np.array_equal(adapter.render(model, params, SCENE), adapter.render(model, base, SCENE)):
            return None
    return f"{model}.{p.name} = {_moved(p)} renders as the default"


@pytest.mark.parametrize("name", ["mitsuba", "cycles"])
def test_every_parameter_given_changes_the_render_or_is_refused(request, name):
    adapter = request.getfixturevalue(f"{name}_adapter")
    problems = [why for model, spec, p in _cases(adapter) if (why := _check(adapter, model, spec, p))]
    assert not problems, "\n".join(problems)
