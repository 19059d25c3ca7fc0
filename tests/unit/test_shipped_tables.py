"""The remap tables shipped in configs/tables/built/: each is its spec's (a spec changed without a
rebuild would be caught here), reads whole, and answers lookups inside its target's bounds."""

import numpy as np
import pytest
from brdfremap.core.data.appearance import reflectivity_edge_tint
from brdfremap.core.host.plugins import collect_adapters
from brdfremap.core.tables import TableMap, load_table_spec, read_table
from brdfremap.core.tables.dense import DenseMap
from helpers import ROOT

SPECS = sorted((ROOT / "configs" / "tables").glob("*.yaml"))


@pytest.mark.parametrize("spec", SPECS, ids=[p.stem for p in SPECS])
def test_each_spec_has_its_built_table_and_it_answers_inside_the_bounds(spec):
    built = ROOT / "configs" / "tables" / "built" / f"{spec.stem}.json"
    assert built.exists(), f"build it: remap table build {spec.relative_to(ROOT)} --out DIR, then copy DIR/table.json"
    table = read_table(built)
    assert table.spec == load_table_spec(spec), "the spec changed since its table was built: build it again"
    target = collect_adapters().get(table.spec.target.adapter).models[table.spec.target.model]
    tmap = TableMap(table)
    drawn = table.layout.draw(16, 99)
    for values in drawn:
        params, expected = tmap.params(values)
        target.complete(params)  # every value within its bounds (a ConfigError otherwise)
        assert 0 < expected < 10
    many = DenseMap(tmap).predict({k: [v[k] for v in drawn] for k in table.spec.axes})
    exact = {name: np.array([tmap.params(values)[0][name] for values in drawn], np.float32) for name in many}
    for name, (baked, truth) in _as_mapped(table, many, exact, target).items():
        assert np.abs(baked - truth).max() < 1e-3, name  # the baked map is the map, to 0.1 % of the range


def _as_mapped(table, many, exact, target) -> dict:
    """Each parameter as the map predicts it, over its range: a conductor's eta and k as their
    reflectivity and edge tint (near a reflectivity of 1, a tiny change in edge tint is a large one in k)."""
    via = next((o.via for o in table.outputs if o.via), ())
    out = {}
    for name in many:
        if name in via:
            continue
        p = target.param(name)
        out[name] = (many[name] / (p.upper - p.lower), exact[name] / (p.upper - p.lower))
    if via:
        for part, baked, truth in zip(("reflectivity", "edge tint"), reflectivity_edge_tint(*(many[n] for n in via)),
                                      reflectivity_edge_tint(*(exact[n] for n in via))):
            out[part] = (np.asarray(baked), np.asarray(truth))
    return out


def test_a_texture_set_looked_up_block_by_block_is_looked_up_whole(monkeypatch):
    from brdfremap.core.tables import dense

    table = read_table(ROOT / "configs" / "tables" / "built" / "cycles-principled-to-mitsuba-principled.json")
    drawn = table.layout.draw(50, 3)
    values = {k: np.array([v[k] for v in drawn], np.float32) for k in table.spec.axes}
    baked = DenseMap(TableMap(table))
    whole = baked.predict(values)
    monkeypatch.setattr(dense, "BLOCK", 7)  # 50 = 7 blocks of 7 and one of 1
    for name, v in baked.predict(values).items():
        assert v.shape == whole[name].shape and np.array_equal(v, whole[name]), name
