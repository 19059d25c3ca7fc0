"""The remap tables shipped in configs/tables/built/: each is its spec's (a spec changed without a
rebuild would be caught here), reads whole, and answers lookups inside its target's bounds."""

import numpy as np
import pytest

from brdfremap.core.plugins import collect_adapters
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
    for name, v in many.items():
        exact = [tmap.params(values)[0][name] for values in drawn]
        assert np.abs(v - np.array(exact, np.float32)).max() < 1e-3 * (
            target.param(name).upper - target.param(name).lower), name  # the baked map is the map
