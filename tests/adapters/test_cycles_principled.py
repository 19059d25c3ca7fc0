"""Cycles' Principled BSDF, every reflection input (issue 20, first part): each reaches Blender,
and a material that uses them converts with a verdict instead of being refused."""

import numpy as np
import pytest

from brdfremap.core.data.metrics import relative_rmse
from brdfremap.core.data.scene import ProbeScene

SCENE = ProbeScene(resolution=32, spp=16)
COPPER = {"base_color": [0.955, 0.638, 0.538], "metallic": 1.0, "roughness": 0.35}
# Each held input with a value away from its default, over a base where it can show.
CHANGES = [
    ({"coat_weight": 1.0}, {"coat_ior": 2.2}), ({"coat_weight": 1.0}, {"coat_tint": [0.9, 0.5, 0.3]}),
    ({"coat_weight": 1.0}, {"coat_roughness": 0.4}),
    ({}, {"sheen_weight": 1.0}), ({"sheen_weight": 1.0}, {"sheen_tint": [1.0, 0.2, 0.2]}),
    ({"sheen_weight": 1.0}, {"sheen_roughness": 0.1}),
    ({"metallic": 0.0}, {"diffuse_roughness": 1.0}),
    ({"metallic": 0.0}, {"subsurface_weight": 1.0, "subsurface_scale": 1.0}),
    ({"metallic": 0.0, "subsurface_weight": 1.0, "subsurface_scale": 1.0}, {"subsurface_radius": [0.1, 1.0, 1.0]}),
    ({"metallic": 0.0}, {"transmission_weight": 1.0}),
    ({}, {"thin_film_thickness": 400.0}), ({"thin_film_thickness": 400.0}, {"thin_film_ior": 2.0}),
    ({}, {"alpha": 0.5}),
    ({}, {"anisotropic": 0.9}), ({"anisotropic": 0.9}, {"anisotropic_rotation": 0.125}),
]


@pytest.mark.parametrize("base, change", CHANGES, ids=[next(iter(c)) for _, c in CHANGES])
def test_each_principled_input_reaches_blender(cycles_adapter, base, change):
    spec = cycles_adapter.models["principled"]
    before = spec.complete({**COPPER, **base})
    after = spec.complete({**COPPER, **base, **change})
    a = cycles_adapter.render("principled", before, SCENE)
    b = cycles_adapter.render("principled", after, SCENE)
    assert relative_rmse(a, b) > 0.02, (change, relative_rmse(a, b))


def test_a_copper_with_a_tinted_coat_converts_with_a_verdict(tmp_path, root, cycles_adapter, mitsuba_adapter):
    """The issue's first refusal: "unknown parameter 'coat_tint' for model 'principled'"."""
    from brdfremap.core.cli import main
    from reports import read_result

    src = tmp_path / "coat.yaml"
    src.write_text("adapter: cycles\nmodel: principled\nparams: {base_color: [0.955, 0.638, 0.538], metallic: 1.0, "
                   "roughness: 0.35, coat_weight: 1.0, coat_ior: 1.6, coat_tint: [0.9, 0.55, 0.3]}\n")
    out = tmp_path / "out"
    assert main(["--source", str(src), "--adapter", "mitsuba", "--model", "principled", "--out", str(out), "--quiet",
                 "--resolution", "64", "--validate", "none"]) == 0
    r = read_result(out / "result.json")
    assert r["source"]["params"]["coat_tint"] == [0.9, 0.55, 0.3]
    assert r["verdict"] in ("mismatch", "unreliable") and r["metrics"]["relative_rmse"] > 0.05  # no coat tint there


def test_held_inputs_are_listed_with_their_bounds(cycles_adapter):
    spec = cycles_adapter.models["principled"]
    names = set(spec.names)
    assert {"coat_ior", "coat_tint", "sheen_weight", "sheen_roughness", "sheen_tint", "diffuse_roughness",
            "subsurface_weight", "subsurface_radius", "subsurface_scale", "subsurface_ior", "subsurface_anisotropy",
            "transmission_weight", "thin_film_thickness", "thin_film_ior", "alpha"} <= names
    assert spec.param("thin_film_thickness").upper == 100000.0 and not spec.param("coat_tint").fit
    assert not np.isnan(spec.param("subsurface_ior").lower)
