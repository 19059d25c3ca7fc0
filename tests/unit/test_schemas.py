import pytest

from brdfremap.core.data.errors import ConfigError
from brdfremap.core.data.schemas import LobeSpec, ModelSpec, ParamSpec, parse_fix
from brdfremap_example.adapter import TOY


def test_complete_fills_defaults_and_canonicalises_rgb():
    p = TOY.complete({"diffuse": 0.2, "alpha": 0.3})
    assert p["diffuse"] == (0.2, 0.2, 0.2)
    assert p["alpha"] == 0.3 and p["specular"] == 0.5


@pytest.mark.parametrize(
    "given, field, words",
    [
        ({"alhpa": 0.1}, "params.alhpa", "unknown parameter 'alhpa'"),
        ({"alpha": 5.0}, "params.alpha", "outside the bounds [0.01, 1]"),
        ({"alpha": "rough"}, "params.alpha", "expected a number"),
        ({"diffuse": [0.1, 0.2]}, "params.diffuse", "list of 3 numbers"),
        ({"alpha": float("nan")}, "params.alpha", "outside the bounds"),
    ],
)
def test_complete_rejects_bad_values_naming_file_and_field(given, field, words):
    with pytest.raises(ConfigError) as e:
        TOY.complete(given, file="mat.yaml")
    assert str(e.value).startswith(f"mat.yaml: {field}: ")
    assert words in str(e.value)


def test_choice_and_bounds_validation_in_spec():
    with pytest.raises(ValueError):
        ParamSpec(name="d", kind="choice", default="x", choices=("a", "b"))
    with pytest.raises(ValueError):
        ParamSpec(name="a", kind="scalar", lower=0.0, upper=1.0, default=0.5, scale="log")
    with pytest.raises(ValueError):
        ModelSpec(name="m", parameters=(ParamSpec(name="a", kind="scalar", default=0.5),),
                  lobes={"diffuse": LobeSpec(params=("b",))})


def test_parse_fix():
    assert parse_fix("alpha=0.25", TOY) == ("alpha", 0.25)
    assert parse_fix("diffuse=0.1,0.2,0.3", TOY) == ("diffuse", (0.1, 0.2, 0.3))
    with pytest.raises(ConfigError, match="--fix alhpa"):
        parse_fix("alhpa=1", TOY)
    with pytest.raises(ConfigError, match="outside the bounds"):
        parse_fix("alpha=3", TOY)
    with pytest.raises(ConfigError, match="name=value"):
        parse_fix("alpha", TOY)


def test_fittable_respects_fit_flag_fixed_and_activity():
    p = TOY.complete({})
    assert TOY.fittable(p) == ["diffuse", "specular", "alpha"]
    assert TOY.fittable(p, fixed={"alpha"}) == ["diffuse", "specular"]
