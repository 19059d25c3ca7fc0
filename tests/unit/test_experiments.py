"""Experiments without renders: cliff detection, the file format, its errors, the round-trip fit."""

import math

import numpy as np
import pytest

from brdfremap.core.cli import main
from brdfremap.core.data.errors import ConfigError
from brdfremap.core.experiments import Experiment, find_cliffs, load_experiment, points_of

K, W, FLOOR = 4.0, 3, 1e-3


def test_a_smooth_curve_has_no_cliff():
    x = np.linspace(1.1, 2.0, 46)
    assert find_cliffs(list(x), list(0.04 * (x - 1) ** 2 + 0.001 * np.sin(9 * x)), K, W, FLOOR) == []


def test_a_step_is_one_cliff_at_the_point_after_it():
    x = list(range(20))
    y = [0.1 + 0.01 * i for i in range(10)] + [0.6 + 0.01 * i for i in range(10)]
    ((before, after, ratio),) = find_cliffs(x, y, K, W, FLOOR)
    assert (before, after) == (9, 10) and ratio > 10


def test_a_lone_outlier_is_one_cliff_naming_the_outlier():
    x = list(range(12))
    y = [0.1 * i for i in range(12)]
    y[5] = 3.0
    ((before, after, _),) = find_cliffs(x, y, K, W, FLOOR)
    assert (before, after) == (4, 5)


def test_points_are_ordered_by_x_not_by_index():
    x = [3, 0, 2, 1, 4, 5, 6]
    y = [0.3, 0.0, 0.2, 0.1, 2.0, 2.1, 2.2]  # jump between x=3 (index 0) and x=4 (index 4)
    ((before, after, _),) = find_cliffs(x, y, K, W, FLOOR)
    assert (before, after) == (0, 4)


def test_steps_below_the_floor_never_count():
    x = list(range(10))
    y = [0.5] * 5 + [0.5005] + [0.5] * 4  # flat with one wiggle below the floor
    assert find_cliffs(x, y, K, W, FLOOR) == []


def _exp(**over):
    doc = {
        "kind": "sweep", "name": "t",
        "source": {"adapter": "mitsuba", "model": "ashikhmin_shirley_plastic", "params": {"alpha": 0.1}},
        "sweep": {"param": "int_ior", "range": {"start": 1.1, "stop": 1.5, "steps": 5}},
        "groups": {"param": "alpha", "values": [0.1, 0.2]},
        "target": {"adapter": "mitsuba", "model": "ward"},
        "plot": {"x": "source.int_ior", "y": "target.specular_reflectance"},
    }
    doc.update(over)
    return doc


def test_points_cover_groups_times_values():
    pts = points_of(Experiment.model_validate(_exp()))
    assert len(pts) == 10 and pts[0].id == "00-000" and pts[-1].id == "01-004"
    assert pts[-1].params == {"alpha": 0.2, "int_ior": 1.5}
    assert math.isclose(pts[1].params["int_ior"], 1.2)


def _write(tmp_path, doc):
    import yaml

    path = tmp_path / "exp.yaml"
    path.write_text(yaml.safe_dump(doc))
    return path


@pytest.mark.parametrize("change, field", [
    ({"sweep": {"param": "int_ior", "values": [1.2], "range": {"start": 1, "stop": 2, "steps": 3}}}, "sweep"),
    ({"plot": {"x": "int_ior", "y": "target.alpha"}}, "plot"),
    ({"kind": "sweeep"}, "kind"),
    ({"colour": 1}, "colour"),
])
def test_a_malformed_file_names_its_field(tmp_path, change, field):
    path = _write(tmp_path, _exp(**change))
    with pytest.raises(ConfigError) as err:
        load_experiment(path)
    assert str(path) in str(err.value) and field in str(err.value)


@pytest.mark.parametrize("change, needle", [
    ({"sweep": {"param": "ior", "values": [1.2]}}, "sweep.param"),
    ({"sweep": {"param": "int_ior", "values": [1.2, 7.0]}}, "point 00-001 (int_ior=7).int_ior"),
    ({"target": {"adapter": "mitsuba", "model": "ward", "fix": {"alpha": -1}}}, "target.fix.alpha"),
    ({"target": {"adapter": "mitsuba", "model": "wardd"}}, "target.model"),
])
def test_bad_points_fail_before_any_render(tmp_path, capsys, change, needle):
    path = _write(tmp_path, _exp(**change))
    assert main(["sweep", str(path), "--out", str(tmp_path / "o"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert needle in err and str(path) in err and "Traceback" not in err
    assert not (tmp_path / "o" / "points").exists()


def test_the_command_must_match_the_kind(tmp_path, capsys):
    path = _write(tmp_path, _exp())
    assert main(["roundtrip", str(path), "--out", str(tmp_path / "o")]) == 2
    assert "run it with `remap sweep`" in capsys.readouterr().err


def test_shipped_experiments_load(root):
    files = sorted((root / "configs/experiments").glob("*.yaml"))
    assert len(files) >= 5
    for f in files:
        exp = load_experiment(f)
        assert exp.figure and points_of(exp)


def test_three_points_are_too_few_to_call_a_cliff():
    assert find_cliffs([0, 1, 2], [0.0, 0.01, 0.5], K, W, FLOOR) == []


def test_a_side_param_is_parsed_once_and_written_as_it_was_given():
    from brdfremap.core.experiments.spec import Side, SideParam

    exp = Experiment.model_validate(_exp(plot={"x": "source.int_ior", "y": "back.alpha"}))
    assert exp.plot.x == SideParam(Side.SOURCE, "int_ior") and exp.plot.y.side is Side.BACK
    assert exp.compared() == "int_ior" and str(exp.plot.y) == "back.alpha"
    assert exp.model_dump()["plot"]["x"] == "source.int_ior" and '"y":"back.alpha"' in exp.model_dump_json()
    assert Experiment.model_validate_json(exp.model_dump_json()) == exp
    for bad in ("int_ior", "front.alpha", "source.", ".alpha"):
        with pytest.raises(ValueError, match=f"plot.y: must look like source.<name>, target.<name> or "
                                             f"back.<name>, not '{bad}'"):
            SideParam.parse(bad, "plot.y")
