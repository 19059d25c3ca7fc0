"""A second choice of model (issue 43): where the model an adapter chose comes back a mismatch or
unreliable, its other models for that reading are fitted too and the best kept, every try said; and
what the kept model lacks by the reading is said."""

from types import SimpleNamespace

from brdfremap.core.data.appearance import Appearance, Kind
from brdfremap.core.host.plugins import collect_adapters
from brdfremap.core.host.protocol import ModelChoice
from brdfremap.core.library.alternatives import Tried, keep_best, lacks, retries
from brdfremap.core.library.convert import Item
from brdfremap.core.library.formats import Entry
from brdfremap.core.run.runner import Done, Task

PLASTIC = Appearance(kind=Kind.DIELECTRIC, alpha=0.2, distribution="beckmann", specular=(0.04,) * 3,
                     diffuse=(0.5, 0.1, 0.1), ior=1.5)
SCHLICK_METAL = Appearance(kind=Kind.CONDUCTOR, alpha=0.1, distribution="ggx", specular=(0.9, 0.7, 0.3))


def _done(slot, verdict, error, held=()):
    report = SimpleNamespace(verdict=verdict, metrics=SimpleNamespace(relative_rmse=error),
                             validation=[SimpleNamespace(error=e) for e in held])
    return Done(Task(slot, None, slot), report, resumed=False)


def _item(status, error, held=()):
    item = Item(Entry(name="m", file="f.mtlx"), slot="m-1", model="roughconductor", why="a metal", look=SCHLICK_METAL)
    item.done = _done("m-1", status, error, held)
    return item


def test_the_best_verdict_then_the_least_error_is_kept_and_every_try_said():
    item = _item("mismatch", 0.42)
    item.tried = [Tried("principled", "Schlick's Fresnel", _done("m-1~principled", "mismatch", 0.16, held=[0.2])),
                  Tried("roughconductor", "Beckmann", _done("m-1~roughconductor-beckmann", "unreliable", 0.05,
                                                            held=[0.4]))]
    keep_best(item)
    assert item.model == "principled" and item.slot == "m-1~principled"
    assert "kept over roughconductor 42.0% mismatch, roughconductor 5.0% unreliable" in item.why
    assert len(item.tried) == 3
    item = _item("ok", 0.04)
    item.tried = [Tried("principled", "Schlick's Fresnel", _done("m-1~principled", "mismatch", 0.01))]
    keep_best(item)
    assert item.model == "roughconductor"  # ok first, whatever the errors


def test_a_mismatch_and_an_unreliable_result_rank_by_their_worst_error():
    item = _item("mismatch", 0.496, held=[0.99])  # a Diffuse BSDF for a node group's Principled BSDF
    item.tried = [Tried("principled", "no reading", _done("m-1~principled", "unreliable", 0.001, held=[0.18]))]
    keep_best(item)
    assert item.model == "principled"


def test_the_first_choice_stays_where_nothing_does_better_and_says_so():
    item = _item("unreliable", 0.03)
    item.tried = [Tried("principled", "Schlick's Fresnel", _done("m-1~principled", "unreliable", 0.09))]
    keep_best(item)
    assert item.model == "roughconductor" and item.slot == "m-1" and "none closer" in item.why


def test_only_a_mismatch_or_an_unreliable_result_is_tried_again():
    adapter = SimpleNamespace(alternatives=lambda look: [ModelChoice("principled", {}, "why")])
    made = []
    tasks = retries([_item("ok", 0.01), _item("mismatch", 0.3)], adapter,
                    lambda item, slot, choice, title: made.append(slot) or Task(slot, None, title))
    assert made == ["m-1~principled"] and len(tasks) == 1


def test_the_adapters_offer_other_models_only_where_the_reading_says_the_first_may_not_follow():
    reg = collect_adapters()
    from brdfremap.adapters.cycles import appearance as cycles
    from brdfremap.adapters.mitsuba import appearance as mitsuba

    assert [m for m, _, _ in cycles.alternatives(SCHLICK_METAL)] == ["principled"]  # Schlick: Principled's own
    aluminium = SCHLICK_METAL.model_copy(update={"eta": (1.66, 0.88, 0.52), "k": (9.22, 6.27, 4.84)})
    assert cycles.alternatives(aluminium) == []  # a complex IOR: the Metallic BSDF's own Fresnel
    assert "principled" in [m for m, _, _ in mitsuba.alternatives(PLASTIC.model_copy(update={"distribution": "ggx"}))]
    assert reg.get("cycles").models["principled"]  # the registry lists models without starting a renderer


def test_what_the_chosen_model_lacks_is_read_from_its_declared_parameters():
    models = collect_adapters().get("cycles").models
    assert lacks(PLASTIC, models["principled"]) == ["its beckmann lobe (principled has multi_ggx, ggx only)"]
    assert lacks(PLASTIC, models["glossy"]) == []  # Beckmann among its choices
    aluminium = SCHLICK_METAL.model_copy(update={"eta": (1.66, 0.88, 0.52), "k": (9.22, 6.27, 4.84)})
    assert lacks(aluminium, models["metallic"]) == []  # its complex IOR renders the edge itself
    assert lacks(aluminium, models["glossy"]) and "Schlick" in lacks(aluminium, models["glossy"])[0]


def test_what_a_model_drops_of_the_reading_is_read_back_through_the_adapter(mitsuba_adapter):
    from brdfremap.core.data.appearance import Coat, Sheen
    from brdfremap.core.library.alternatives import dropped

    coated = PLASTIC.model_copy(update={"distribution": "ggx", "coat": Coat(weight=1.0, alpha=0.01),
                                        "sheen": Sheen(weight=0.5)})
    models = mitsuba_adapter.models
    assert dropped(coated, models["roughplastic"]) == [
        "its coat (roughplastic has none)", "its sheen (roughplastic has none)"]
    assert not [d for d in dropped(coated, models["principled"]) if "coat" in d]
