"""Remap tables without renders: the spec and its grid, the candidate maps, the table file and its
lookups, and the checks a spec gets before any render."""

import json
import math

import numpy as np
import pytest
import yaml

from brdfremap.core.data.errors import ConfigError
from brdfremap.core.host.plugins import collect_adapters
from brdfremap.core.data.schemas import Material, Scale
from brdfremap.core.tables import Layout, TableMap, load_table_spec, read_table
from brdfremap.core.tables.build import choose, plan
from brdfremap.core.tables.lookup import axis_values, look_up
from brdfremap.core.tables.maps import Grid, Multilinear, build, choose_hyperparameter, fill
from brdfremap.core.tables.spec import Axis, TableSpec
from brdfremap.core.tables.table import TABLE_SCHEMA_VERSION, Candidate, Table, outside, write_table
from tablekit import SPEC, synthetic_table

def _spec(tmp_path, **changes):
    doc = json.loads(json.dumps(SPEC))
    doc.update(changes)
    path = tmp_path / "spec.yaml"
    path.write_text(yaml.safe_dump(doc))
    return path


def test_grid_spans_the_axes_and_the_draw_stays_inside(tmp_path):
    spec = load_table_spec(_spec(tmp_path))
    layout = Layout(spec.axes, {"alpha": "scalar", "specular_reflectance": "rgb"})
    grid = layout.grid()
    assert len(grid) == 12
    alphas = sorted({v["alpha"] for _, v in grid})
    assert alphas[0] == pytest.approx(0.05) and alphas[-1] == pytest.approx(0.4)
    assert alphas[1] / alphas[0] == pytest.approx(alphas[2] / alphas[1])  # even in the logarithm
    assert all(v["specular_reflectance"][0] == v["specular_reflectance"][2] for _, v in grid)  # grey levels
    drawn = layout.draw(8, seed=3)
    assert drawn == layout.draw(8, seed=3) and drawn != layout.draw(8, seed=4)
    for v in drawn:
        assert 0.05 <= v["alpha"] <= 0.4
        assert all(0.3 <= c <= 1.0 for c in v["specular_reflectance"])
    assert any(len(set(v["specular_reflectance"])) == 3 for v in drawn)  # colours, not grey
    x = layout.features({"alpha": np.array([0.05, 0.4]), "specular_reflectance": np.array([[0.3, 1, 0.65]] * 2)}, 1)
    assert np.allclose(x, [[0.0, 1.0], [1.0, 1.0]])


def test_channels_mode_makes_three_dimensions():
    axes = {"a": Axis(range=(0, 1), steps=2), "c": Axis(range=(0, 1), steps=3, mode="channels")}
    layout = Layout(axes, {"a": "scalar", "c": "rgb"})
    assert [d.label for d in layout.dims] == ["a", "c.r", "c.g", "c.b"] and not layout.separable
    assert len(layout.grid()) == 2 * 27


@pytest.mark.parametrize("scale", ["linear", "log"])
def test_listed_values_are_the_grid_and_the_multilinear_map_interpolates_between_them(scale):
    """An axis's values listed (closer at the dark end): the grid takes them; the maps' coordinate is
    the range's scale as with steps (so draws and the other maps are unchanged), and the multilinear
    map interpolates each cell between its two listed values, evenly in the value or its log."""
    listed = Axis(range=(0.05, 0.9), values=[0.05, 0.15, 0.25, 0.9], scale=scale)
    even = Axis(range=(0.05, 0.9), steps=4, scale=scale)
    assert listed.count == 4 and listed.samples() == [0.05, 0.15, 0.25, 0.9]
    assert np.allclose(listed.knots(), listed.to_unit(np.array([0.05, 0.15, 0.25, 0.9])))
    assert np.allclose(even.knots(), np.linspace(0, 1, 4))
    x = np.linspace(0.04, 0.95, 50)
    assert np.array_equal(listed.to_unit(x), even.to_unit(x))
    assert np.allclose(listed.sample(np.linspace(0, 1, 7)), even.sample(np.linspace(0, 1, 7)))
    layout = Layout({"a": listed}, {"a": "rgb"})
    assert [v["a"] for _, v in layout.grid()] == [[v] * 3 for v in [0.05, 0.15, 0.25, 0.9]]
    grid = Grid(listed.knots()[:, None], np.arange(4)[:, None], np.array([1.0, 2.0, 4.0, 5.0]), np.ones(4, bool),
                (4,), layout.knots())
    mid = np.sqrt(0.15 * 0.25) if scale == "log" else 0.2
    got = Multilinear(grid).predict(listed.to_unit(np.array([[0.05], [mid], [0.25], [0.9], [2.0]])))
    assert got == pytest.approx([1.0, 3.0, 4.0, 5.0, 5.0])


@pytest.mark.parametrize("listed", [[0.3, 0.3875, 0.475, 1.0], [0.3, 0.399, 0.5, 1.0]])
def test_a_map_over_listed_values_is_looked_up_texel_by_texel_as_one_by_one(tmp_path, listed):
    """Every map over a listed axis follows what it follows over an even one (a rule linear in the
    source, exactly); baked for textures, the multilinear map stays exact where the listed values fall
    on a division of the range (1/8 and 1/4 of it), and elsewhere (99/700) rounds its bend off
    within one node's spacing."""
    from brdfremap.core.tables.build import fit_candidates
    from brdfremap.core.tables.dense import NODES, DenseMap

    axes = {"alpha": SPEC["axes"]["alpha"], "specular_reflectance": {"range": [0.3, 1.0], "values": listed}}
    rng = np.random.default_rng(1)
    values = {"alpha": rng.uniform(0.05, 0.4, 500), "specular_reflectance": rng.uniform(0.3, 1.0, (500, 3))}
    linear = synthetic_table(tmp_path, axes=axes)
    linear = linear.model_copy(update={"points": [pt.model_copy(update={"used": True}) for pt in linear.points]})
    linear = linear.model_copy(update={"candidates": fit_candidates(linear)})
    for method in ("multilinear", "polynomial", "rbf"):
        got = TableMap(linear, method).predict(values)["specular_reflectance"]
        assert got == pytest.approx(0.9 * values["specular_reflectance"], abs=1e-6), method
    bent = [pt.model_copy(update={"params": {**pt.params, "specular_reflectance": [
        c ** 3 for c in pt.values["specular_reflectance"]]}}) for pt in linear.points]
    table = linear.model_copy(update={"points": bent})
    tmap = TableMap(table.model_copy(update={"candidates": fit_candidates(table)}), "multilinear")
    one = tmap.predict(values)["specular_reflectance"]
    dense = DenseMap(tmap)
    many = dense.predict({k: v.astype(np.float32) for k, v in values.items()})["specular_reflectance"]
    aligned = listed[1] == 0.3875
    assert dense.shape[1] == NODES[2] and many == pytest.approx(one, rel=1e-5 if aligned else 0, abs=0 if aligned else 3e-3)
    grey = np.array(listed)[:, None].repeat(3, axis=1)
    at_grid = tmap.predict({"alpha": np.full(4, 0.05), "specular_reflectance": grey})["specular_reflectance"]
    assert at_grid == pytest.approx(grey ** 3, rel=1e-9)


def test_table_show_lists_an_axis_s_listed_values(tmp_path, capsys):
    from brdfremap.core.cli import main
    from brdfremap.core.tables.table import write_table

    table = synthetic_table(tmp_path, axes={"alpha": SPEC["axes"]["alpha"], "specular_reflectance": {
        "range": [0.3, 1.0], "values": [0.3, 0.4, 1.0]}})
    write_table(tmp_path / "table.json", table)
    assert main(["table", "show", str(tmp_path)]) == 0
    assert "grid           alpha 4 x specular_reflectance 3 (0.3, 0.4, 1) = 12 points" in capsys.readouterr().out


@pytest.mark.parametrize("axis, words", [
    ({"range": [0.05, 0.9], "steps": 3, "values": [0.05, 0.5, 0.9]}, "not both"),
    ({"range": [0.05, 0.9]}, "give steps (values evenly spaced over the range) or values (listed)"),
    ({"range": [0.05, 0.9], "values": [0.1, 0.5, 0.9]}, "values: 0.1 to 0.9; they must begin and end at the range"),
    ({"range": [0.05, 0.9], "values": [0.05, 0.5, 0.4, 0.9]}, "values: 0.4 (number 3) is not above 0.5"),
])
def test_listed_values_are_checked_against_the_range(tmp_path, axis, words):
    with pytest.raises(ConfigError) as e:
        load_table_spec(_spec(tmp_path, axes={"alpha": {"range": [0.05, 0.4], "steps": 4},
                                              "specular_reflectance": axis}))
    assert "axes.specular_reflectance" in str(e.value) and words in str(e.value), str(e.value)


@pytest.mark.parametrize("change, words", [
    ({"axes": {"alpha": {"range": [0, 0.4], "steps": 4, "scale": "log"}}}, ["axes.alpha", "above 0"]),
    ({"axes": {"alpha": {"range": [0.4, 0.1], "steps": 4}}}, ["axes.alpha", "lower first"]),
    ({"axes": {"eta": {"range": [0.5, 2], "steps": 3}}}, ["axes.eta", "also given in source.params"]),
    ({"kind": "sweep"}, ["kind"]),
])
def test_spec_errors_name_the_field(tmp_path, change, words):
    with pytest.raises(ConfigError) as e:
        load_table_spec(_spec(tmp_path, **change))
    for w in words:
        assert w in str(e.value)


@pytest.mark.parametrize("change, words", [
    ({"axes": {"material": {"range": [0, 1], "steps": 2}}}, ["axes.material", "a choice"]),
    ({"axes": {"alpha": {"range": [0.05, 2.0], "steps": 2}}}, ["axes.alpha.range", "bounds"]),
    ({"axes": {"alpha_u": {"range": [0.05, 0.5], "steps": 2}}}, ["axes.alpha_u", "does nothing"]),
    ({"axes": {"alpha": {"range": [0.05, 0.5], "steps": 2, "mode": "channels"}}}, ["axes.alpha.mode"]),
    ({"axes": {"roughness": {"range": [0.05, 0.5], "steps": 2}}}, ["axes.roughness", "no parameter"]),
    ({"target": {"adapter": "cycles", "model": "principled"}}, ["target.fix", "distribution"]),
])
def test_plan_checks_the_spec_against_the_models_before_any_render(tmp_path, change, words):
    spec = load_table_spec(_spec(tmp_path, **change))
    with pytest.raises(ConfigError) as e:
        plan(spec, "spec.yaml", collect_adapters())
    for w in words:
        assert w in str(e.value), str(e.value)


def _quadratic_grid(shape=(5, 4), holes=()):
    idx = np.array(np.meshgrid(*[np.arange(n) for n in shape], indexing="ij")).reshape(len(shape), -1).T
    x = idx / (np.array(shape) - 1)
    y = 0.3 + 0.2 * x[:, 0] + 0.1 * x[:, 1] ** 2 - 0.05 * x[:, 0] * x[:, 1]
    used = np.ones(len(y), bool)
    used[list(holes)] = False
    return Grid(x, idx, y, used, shape)


def test_each_map_follows_a_smooth_function_and_cv_picks_the_right_degree():
    grid = _quadratic_grid()
    rng = np.random.default_rng(0)
    xs = rng.random((50, 2))
    truth = 0.3 + 0.2 * xs[:, 0] + 0.1 * xs[:, 1] ** 2 - 0.05 * xs[:, 0] * xs[:, 1]
    for method, tol in (("multilinear", 0.01), ("polynomial", 1e-6), ("rbf", 0.01)):
        h, err = choose_hyperparameter(method, grid)
        assert np.abs(build(method, grid, h).predict(xs) - truth).max() < tol, method
        assert math.isfinite(err)
    assert choose_hyperparameter("polynomial", grid)[0] == 2
    # Multilinear interpolation is exact at the nodes, and a hole is filled from its neighbours.
    holed = _quadratic_grid(holes=(7,))
    m = Multilinear(holed)
    assert m.predict(holed.x[[0, 19]]) == pytest.approx(holed.y[[0, 19]])
    assert abs(m.predict(holed.x[[7]])[0] - holed.y[7]) < 0.02
    assert m.predict(np.array([[-1.0, 2.0]]))[0] == pytest.approx(m.predict(np.array([[0.0, 1.0]]))[0])


def test_the_map_applies_per_channel_and_leaves_out_what_it_must(tmp_path):
    table = synthetic_table(tmp_path)
    assert [o.label for o in table.outputs] == ["specular_reflectance", "alpha", "error"]
    tmap = TableMap(table, "polynomial")
    params, expected = tmap.params({"alpha": 0.2, "specular_reflectance": [0.4, 0.7, 0.95]})
    assert params["specular_reflectance"] == pytest.approx([0.36, 0.63, 0.855], abs=0.01)  # each channel its own
    assert params["alpha"] == pytest.approx(0.22, rel=0.02)  # the left-out point's 0.9 is not followed
    assert expected == pytest.approx(0.03, rel=0.1)
    assert params["variant"] == "balanced" and params["diffuse_reflectance"] == (0.0, 0.0, 0.0)
    # Vectorised: every texel of a texture at once.
    many = tmap.predict({"alpha": np.full(1000, 0.2), "specular_reflectance": np.tile([0.4, 0.7, 0.95], (1000, 1))})
    assert many["specular_reflectance"].shape == (1000, 3) and many["alpha"].shape == (1000,)
    assert outside(table, {"alpha": 0.6, "specular_reflectance": [0.5, 0.5, 0.5]}) == [
        "alpha 0.6 above the table's range [0.05, 0.4]"]
    assert outside(table, {"alpha": 0.2, "specular_reflectance": [0.5, 0.5, 0.5]}) == []


def test_an_output_the_channels_share_weighs_each_channel_by_its_brightness(tmp_path):
    """A scalar target parameter under a grey `scale` axis: looked up at each channel's grey level
    and averaged with the channels' squared values as weights (the bright channels decide, as in a
    direct fit), by a single lookup and texel by texel alike; black weighs the channels equally."""
    from brdfremap.core.tables.build import fit_candidates
    from brdfremap.core.tables.dense import DenseMap

    table = synthetic_table(tmp_path)
    points = [pt.model_copy(update={"used": True, "params": {
        **pt.params, "alpha": pt.values["alpha"] * (1 + pt.values["specular_reflectance"][0])}}) for pt in table.points]
    table = table.model_copy(update={"points": points})
    tmap = TableMap(table.model_copy(update={"candidates": fit_candidates(table)}), "multilinear")
    colours = np.array([[0.3, 0.65, 1.0], [1.0, 0.3, 0.3]])  # grid levels: multilinear is exact
    got = tmap.predict({"alpha": np.full(2, 0.05), "specular_reflectance": colours})["alpha"]
    weights = colours ** 2 / (colours ** 2).sum(axis=1, keepdims=True)
    assert got == pytest.approx((0.05 * (1 + colours) * weights).sum(axis=1), rel=1e-6)
    assert got[0] > 0.05 * (1 + colours[0].mean())  # not the mean grey level's
    dense = DenseMap(tmap).predict({"alpha": np.full(2, 0.05, np.float32),
                                    "specular_reflectance": colours.astype(np.float32)})["alpha"]
    assert dense == pytest.approx(got, rel=1e-5)
    assert table.layout.channel_weights({"specular_reflectance": np.zeros((1, 3))}) == pytest.approx(
        np.full((1, 3), 1 / 3))  # black: the channels alike


def test_only_a_fit_in_question_with_a_remedy_is_refitted_and_only_with_what_it_changes():
    from brdfremap.core.data.settings import Settings
    from brdfremap.core.tables.refits import _remedy
    from brdfremap.core.tables.table import PointRecord

    def point(findings, used=False):
        return PointRecord(id="g0", values={}, params={}, error=0.05, verdict="unreliable", findings=findings,
                           used=used)

    assert _remedy(point(["held_out_above", "not_at_minimum"]), Settings()) == {"scheme": "three"}
    assert _remedy(point(["not_at_minimum"]), Settings(scheme="three")) == {}  # already in effect
    assert _remedy(point(["cannot_resolve"]), Settings()) == {}  # no remedy to take
    assert _remedy(point(["not_at_minimum"], used=True), Settings()) == {}  # not in question: kept as it is


def test_a_remedy_refit_replaces_the_first_fit_only_where_it_ends_lower(tmp_path):
    """`remedy_points` with a runner that hands back finished fits (the refits' errors given): the
    refit's record replaces the first where it is lower, says so and keeps the first's error; the
    refit runs with scheme three, stored beside its point."""
    from types import SimpleNamespace

    from brdfremap.core.run.runner import Done
    from brdfremap.core.tables.refits import remedy_points
    from brdfremap.core.tables.table import PointRecord

    registry = collect_adapters()
    p = plan(load_table_spec(_spec(tmp_path)), "spec.yaml", registry)
    (i0, v0), (i1, v1), (i2, v2) = p.grid[:3]
    first = [PointRecord(id=f"g{k}", index=list(i), values=v, params={"alpha": 0.1}, error=0.06, verdict="unreliable",
                         findings=f, used=not f) for k, (i, v, f) in enumerate(
        [(i0, v0, ["not_at_minimum"]), (i1, v1, ["not_at_minimum"]), (i2, v2, [])])]
    errors = iter([0.02, 0.09])

    class Handing:
        tasks: list = []

        def run(self, tasks):
            Handing.tasks = tasks
            return [Done(task=t, resumed=False, report=SimpleNamespace(
                findings=[], params={"alpha": 0.2}, metrics=SimpleNamespace(relative_rmse=next(errors), noise_floor=0.01),
                verdict="ok", reliable=True, reason="", renders=60, seconds=1.0, key="k")) for t in tasks]

    out = remedy_points(p, registry, Handing(), p.spec.scene.scene(tmp_path), first)
    assert [t.slot for t in Handing.tasks] == ["points/g0/remedy", "points/g1/remedy"]  # g2 is not in question
    assert all(t.job.settings.scheme == "three" for t in Handing.tasks)
    assert out[0].remedy == "scheme three" and out[0].first_error == 0.06 and out[0].error == 0.02 and out[0].used
    assert out[1] == first[1] and out[2] == first[2]  # the refit ended higher: the first fit stays


def test_a_table_file_is_versioned_and_an_edited_one_refused(tmp_path):
    table = synthetic_table(tmp_path)
    path = write_table(tmp_path / "table.json", table)
    again = read_table(tmp_path)
    assert again.digest == table.digest and TableMap(again).params({"alpha": 0.1, "specular_reflectance": [1, 1, 1]})
    doc = json.loads(path.read_text())
    doc["points"][0]["params"]["alpha"] = 0.5
    path.write_text(json.dumps(doc))
    with pytest.raises(ConfigError, match="edited after it was built"):
        read_table(path)
    doc["schema_version"] = TABLE_SCHEMA_VERSION + 1
    path.write_text(json.dumps(doc))
    with pytest.raises(ConfigError, match="upgrade brdf-remap"):
        read_table(path)
    doc["schema_version"] = 1  # its map read otherwise: built again, its fits reused
    path.write_text(json.dumps(doc))
    with pytest.raises(ConfigError, match=r"build it again .*\(its stored fits are reused\)"):
        read_table(path)
    path.write_text(json.dumps({"schema_version": 3, "key": "x"}))
    with pytest.raises(ConfigError, match="not a remap table"):
        read_table(path)


def test_a_lookup_checks_the_material_against_the_table(tmp_path):
    table = synthetic_table(tmp_path)
    from brdfremap.adapters.mitsuba.models import MODELS

    spec = MODELS["roughconductor"]
    good = Material(adapter="mitsuba", model="roughconductor",
                    params={"distribution": "beckmann", "eta": 0, "k": 1, "alpha": 0.1,
                            "specular_reflectance": [0.5, 0.6, 0.7]})
    values = axis_values(table, good, spec, "m.yaml")
    assert values == {"alpha": 0.1, "specular_reflectance": [0.5, 0.6, 0.7]}
    answer = look_up(table, TableMap(table), values)
    assert answer.lookup.digest == table.digest  # its time: bench/tables.py speed
    for params, field in (({**good.params, "distribution": "ggx"}, "params.distribution"),
                          ({**good.params, "material": "Au"}, "params.material"),
                          ({**good.params, "eta": 0.2}, "params.eta")):
        with pytest.raises(ConfigError) as e:
            axis_values(table, good.model_copy(update={"params": params}), spec, "m.yaml")
        assert field in str(e.value) and "was built for" in str(e.value)
    with pytest.raises(ConfigError, match="maps mitsuba:roughconductor"):
        axis_values(table, Material(adapter="mitsuba", model="ward"), MODELS["ward"], "m.yaml")


def test_choice_prefers_the_lookups_closest_to_direct_fits():
    c = {"multilinear": Candidate(method="multilinear", hyper={}, cv_rms={"a": 0.01}, median_ratio=1.02,
                                  p95_ratio=1.3, ratios=[1.0]),
         "polynomial": Candidate(method="polynomial", hyper={}, cv_rms={"a": 0.05}, median_ratio=1.01,
                                 p95_ratio=1.1, ratios=[1.0]),
         "rbf": Candidate(method="rbf", hyper={}, cv_rms={"a": 0.02}, median_ratio=1.2, p95_ratio=1.2, ratios=[1.0])}
    assert choose(c)[0] == "polynomial"
    # Medians within 1 % of the best are alike: the shorter tail decides.
    close = {**c, "rbf": c["rbf"].model_copy(update={"median_ratio": 1.015, "p95_ratio": 1.05})}
    assert choose(close)[0] == "rbf"
    blind = {m: x.model_copy(update={"median_ratio": None, "p95_ratio": None}) for m, x in c.items()}
    assert choose(blind)[0] == "multilinear"


def test_schema_lists_the_table_formats():
    from brdfremap.core.cli.tools import collect_schemas

    known = collect_schemas()
    assert known["table"] is Table and known["table-spec"] is TableSpec


def test_holes_are_filled_along_the_grid_lines_exactly_for_a_linear_map():
    values = np.add.outer(np.linspace(0, 1, 5), 0.5 * np.linspace(0, 1, 4))  # linear in both axes
    holed = values.copy()
    holed[2, 1] = holed[0, 0] = holed[4, 3] = np.nan  # inside, and two corners (extrapolated)
    assert np.allclose(fill(holed), values)
    lone = np.full((3, 3), np.nan)
    lone[1, 1] = 0.7
    assert np.allclose(fill(lone), 0.7)
    grid = _quadratic_grid()
    lin = Grid(grid.x, grid.idx, 0.2 + 0.3 * grid.x[:, 0] - 0.1 * grid.x[:, 1], grid.used, grid.shape)
    assert choose_hyperparameter("multilinear", lin)[1] < 1e-9  # cross-validated as interpolation, not a blur


def test_a_map_that_cannot_be_fitted_says_why_and_is_not_chosen(tmp_path):
    table = synthetic_table(tmp_path)
    few = [p.model_copy(update={"used": i in (0, 11)}) for i, p in enumerate(table.points)]
    from brdfremap.core.tables.build import fit_candidates

    cands = fit_candidates(table.model_copy(update={"points": few}))
    assert cands["rbf"].problem and not cands["rbf"].hyper  # two points: no thin-plate spline in two dimensions
    assert choose(cands)[0] != "rbf"
    json.dumps([c.model_dump(mode="json") for c in cands.values()], allow_nan=False)  # no Infinity in the file


def test_the_digest_covers_the_map_not_the_builds_timing(tmp_path):
    table = synthetic_table(tmp_path)
    slower = table.model_copy(update={"points": [p.model_copy(update={"seconds": 9.0, "renders": 99})
                                                 for p in table.points]})
    assert slower.digest == table.digest
    moved = table.model_copy(update={"points": [table.points[0].model_copy(update={"params": {
        **table.points[0].params, "alpha": 0.3}}), *table.points[1:]]})
    assert moved.digest != table.digest


def test_a_conductors_eta_and_k_are_mapped_as_reflectivity_and_edge_tint():
    from brdfremap.adapters.mitsuba.models import MODELS
    from brdfremap.core.data.appearance import eta_k_from_reflectivity, reflectivity_edge_tint
    from brdfremap.core.tables.outputs import finish, outputs_for, target_value, within_bounds

    outs = outputs_for(MODELS["roughconductor"], ["eta", "k", "alpha"], separable=True)
    assert [o.label for o in outs] == ["alpha", "reflectivity", "edge_tint", "error"]
    eta, k = (0.2, 0.9, 1.4), (3.9, 2.4, 1.6)
    refl = next(o for o in outs if o.param == "reflectivity")
    r, g = reflectivity_edge_tint(eta, k)
    assert target_value({"eta": eta, "k": k}, None, refl) == pytest.approx(float(np.mean(r)) / 0.999)
    back = finish(outs, {"reflectivity": r[None], "edge_tint": g[None], "alpha": np.array([0.1])})
    assert np.allclose(back["eta"][0], eta) and np.allclose(back["k"][0], k) and "reflectivity" not in back
    # Near r = 1 an edge tint can ask for a k beyond its bound: k held there, eta moved, r kept.
    r = np.array([0.95, 0.99])
    e2, k2 = within_bounds(r, *eta_k_from_reflectivity(r, np.array([0.95, 0.95])), 8.0, 10.0)
    assert (k2 <= 10.0).all() and np.allclose(reflectivity_edge_tint(e2, k2)[0], r)


def test_each_output_takes_the_scale_that_predicts_it_better(tmp_path):
    from brdfremap.core.tables.outputs import choose_scales
    from brdfremap.core.tables.table import grid_of

    table = synthetic_table(tmp_path)  # Ward's alpha = 1.1 x the source's, over a log axis: linear in the log
    linear = [o.model_copy(update={"scale": Scale.LINEAR}) if o.param == "alpha" else o for o in table.outputs]
    table = table.model_copy(update={"outputs": linear})
    chosen = {o.param: o.scale for o in choose_scales(table.outputs, lambda o: grid_of(table, o))}
    assert chosen["alpha"] == "log" and chosen["error"] == "log"


def _coupled(values):
    """A target that couples the channels as a rough plastic does: one alpha for the three channels,
    the bright channels' (each channel alone would take 1.1 x alpha x (1 + c / 2); the colour takes
    those averaged with weights c²), and each channel's reflectance making up for the alpha it is
    given instead of its own. On grey: the synthetic table's reflectance, 0.9 x the source's."""
    c = np.asarray(values["specular_reflectance"], float)
    own = 1.1 * values["alpha"] * (1 + c / 2)
    shared = float((own * c ** 2).sum() / (c ** 2).sum())
    return {"variant": "balanced", "ensure_energy_conservation": "true", "diffuse_reflectance": [0, 0, 0],
            "specular_reflectance": list(0.9 * c * (1 + 2 * np.log(shared / own))), "alpha": shared}


def test_coloured_points_correct_a_map_where_the_target_couples_the_channels(tmp_path, monkeypatch):
    """A grey grid cannot show how a target couples a colour's channels; coloured points fitted beside
    it correct the map (a lookup and texel by texel alike), where a channel is given a shared
    parameter off its own; a table without them keeps its digest."""
    from brdfremap.core.tables.build import fit_candidates
    from brdfremap.core.tables.dense import DenseMap
    from brdfremap.core.tables.table import PointRecord

    table = synthetic_table(tmp_path)
    points = [pt.model_copy(update={"used": True, "params": _coupled(pt.values)}) for pt in table.points]
    drawn = table.layout.draw(64, 5)
    colours = [PointRecord(id=f"c{i}", values=v, params=_coupled(v), error=0.02, verdict="ok", used=True)
               for i, v in enumerate(drawn)]
    colours[3] = colours[3].model_copy(update={"params": {**colours[3].params, "specular_reflectance": [
        0.05, 0.05, 0.05]}})  # another optimum
    plain = table.model_copy(update={"points": points})
    table = plain.model_copy(update={"colours": colours})
    table = table.model_copy(update={"candidates": fit_candidates(table)})
    assert "multilinear+colours" in table.candidates and "rbf-mean+colours" in table.candidates
    c = table.candidates["multilinear+colours"]
    before, after = c.correction_cv["specular_reflectance"]
    assert after < 0.2 * before  # cross-validated, at the channels a shared alpha moves
    tests = table.layout.draw(40, 99)
    want = np.array([_coupled(v)["specular_reflectance"] for v in tests])
    values = {"alpha": np.array([v["alpha"] for v in tests]),
              "specular_reflectance": np.array([v["specular_reflectance"] for v in tests])}
    texels = {k: v.astype(np.float32) for k, v in values.items()}
    plain_map, fixed_map = TableMap(table, "multilinear"), TableMap(table, "multilinear+colours")
    before = np.abs(plain_map.predict(values)["specular_reflectance"] - want).max()
    got = fixed_map.predict(values)["specular_reflectance"]
    assert np.abs(got - want).max() < 0.2 * before
    monkeypatch.setattr("brdfremap.core.tables.dense.BLOCK", 7)  # texels in blocks, each corrected
    dense = DenseMap(fixed_map).predict(texels)["specular_reflectance"]
    assert np.abs(dense - got).max() < 1e-3  # texel by texel: the same correction
    assert all(c.correction is None for c in fit_candidates(plain).values())  # no coloured points, no correction
    reread = read_table(write_table(tmp_path / "coloured.json", table))
    assert reread.digest == table.digest and reread.colours == table.colours
    # Nothing the channels share: nothing moves a channel off its own lookup, and no correction.
    unshared = table.model_copy(update={"outputs": [o for o in table.outputs if o.param != "alpha"]})
    assert not any(c.correction for c in fit_candidates(unshared).values())


@pytest.mark.parametrize("version", [2, 3, 4])
def test_a_table_of_an_earlier_format_is_read_as_it_is(tmp_path, version):
    """Format 3 added coloured points, 4 path following, 5 listed values: a file of 2, 3 or 4 has
    none of the later fields, and keeps its digest."""
    table = synthetic_table(tmp_path).model_copy(update={"schema_version": version})
    doc = json.loads(write_table(tmp_path / "t.json", table).read_text())
    for ax in doc["spec"]["axes"].values():  # what formats 2 to 4 wrote
        del ax["values"]
    if version < 4:
        del doc["spec"]["follow"]
    if version == 2:
        del doc["colours"], doc["spec"]["colours"]
        for c in doc["candidates"].values():
            del c["correction"], c["correction_cv"]
    (tmp_path / "old.json").write_text(json.dumps(doc))
    again = read_table(tmp_path / "old.json")
    assert again.schema_version == version and again.digest == doc["digest"] and not again.colours
    assert again.spec.follow == []


@pytest.mark.parametrize("change, words", [
    ({"axes": {"alpha": {"range": [0.05, 0.4], "steps": 4},
               "specular_reflectance": {"range": [0.3, 1.0], "steps": 3, "mode": "channels"}}},
     "colours: coloured points correct a map over one RGB axis sampled as grey levels"),
    ({"holdout": 0}, "colours: coloured points need held-out materials"),
])
def test_coloured_points_need_one_grey_axis_and_held_out_materials(tmp_path, change, words):
    path = _spec(tmp_path, colours=8, **change)
    with pytest.raises(ConfigError, match=words):
        plan(load_table_spec(path), str(path), collect_adapters())


@pytest.mark.parametrize("axis", ["alpha", "specular_reflectance"])
def test_path_following_refits_each_step_from_its_predecessor_as_it_now_stands(tmp_path, axis):
    """`follow_points` along each axis (alpha: 4 steps; the grey levels: 3) with a runner that hands
    back finished fits (up: lower, down: higher): up the axis each point starts from the fit before it
    as it now stands, so the refits add up; a refit in question does not replace a used fit; a
    failed fit starts nobody and takes any refit; down, every refit is higher and none is kept."""
    from types import SimpleNamespace

    from brdfremap.core.run.runner import Done
    from brdfremap.core.data.findings import NotAtMinimum
    from brdfremap.core.tables.refits import follow_points
    from brdfremap.core.tables.table import PointRecord

    registry = collect_adapters()
    p = plan(load_table_spec(_spec(tmp_path, follow=[axis])), "spec.yaml", registry)
    d = [dim.axis for dim in p.layout.dims].index(axis)
    n, lines = p.spec.axes[axis].count, len(p.grid) // p.spec.axes[axis].count
    first = [PointRecord(id=f"g{k}", index=list(i), values=v, params={"alpha": 0.1}, error=0.06, verdict="ok",
                         used=True) for k, (i, v) in enumerate(p.grid)]
    line = [tuple(pt.index[:d] + pt.index[d + 1:]) for pt in first]
    bottoms = [k for k, pt in enumerate(first) if pt.index[d] == 0]
    failed_line, questioned_line = line[bottoms[0]], line[bottoms[1]]
    first[bottoms[0]] = first[bottoms[0]].model_copy(update={"params": None, "error": None, "used": False})
    questioned = next(k for k, pt in enumerate(first) if line[k] == questioned_line and pt.index[d] == 1)
    waves = []

    class Handing:
        def run(self, tasks):
            waves.append(tasks)
            return [Done(task=t, resumed=False, report=SimpleNamespace(
                findings=[NotAtMinimum(predicted=0.04)]
                if t.slot == f"points/g{questioned}/{axis}-up" else [],
                params={"alpha": t.job.start["alpha"] + 0.01},
                metrics=SimpleNamespace(relative_rmse=0.09 if t.slot.endswith("-down") else 0.05, noise_floor=0.01),
                verdict="ok", reliable=True, reason="", renders=60, seconds=1.0, key="k")) for t in tasks]

    out = follow_points(p, registry, Handing(), p.spec.scene.scene(tmp_path), first, axis)
    assert [len(w) for w in waves] == [lines - 1] + [lines] * (2 * n - 3)  # the failed bottom starts nobody
    assert all(t.job.settings.starts == 1 for w in waves for t in w)
    assert all(t.slot.endswith(f"/{axis}-up") for w in waves[:n - 1] for t in w)
    assert all(t.slot.endswith(f"/{axis}-down") for w in waves[n - 1:] for t in w)
    for k, pt in enumerate(out):
        i = pt.index[d]
        held = {failed_line: 1, questioned_line: 1}.get(line[k])  # the step whose fit stays the first
        if i == held or (i == 0 and line[k] != failed_line):
            assert pt == first[k], pt.id
        elif i == 0:  # failed: the down sweep's refit, from the first fit above it
            assert pt.params["alpha"] == pytest.approx(0.11) and pt.error == 0.09 and pt.continued
            assert pt.first_error is None
        else:
            steps = i - 1 if held else i
            assert pt.params["alpha"] == pytest.approx(0.1 + 0.01 * steps), pt.id
            assert pt.continued and pt.error == 0.05 and pt.first_error == 0.06


def test_follow_names_an_axis_of_the_grid_once(tmp_path):
    with pytest.raises(ConfigError, match="follow: 'roughness' is not a scalar or grey axis"):
        load_table_spec(_spec(tmp_path, follow=["roughness"]))
    with pytest.raises(ConfigError, match="an axis named twice"):
        load_table_spec(_spec(tmp_path, follow=["alpha", "alpha"]))
    channels = {**SPEC["axes"], "specular_reflectance": {**SPEC["axes"]["specular_reflectance"], "mode": "channels"}}
    with pytest.raises(ConfigError, match="follow: 'specular_reflectance' is not a scalar or grey axis"):
        load_table_spec(_spec(tmp_path, axes=channels, follow=["specular_reflectance"]))
