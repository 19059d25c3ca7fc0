"""Scenes of several lights and views, environment maps, and what a scene an adapter cannot render
does (numpy and the analytic toy only; the renderers' calibration is in tests/adapters/test_lights.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from brdfremap.core.data import environment
from brdfremap.core.data.errors import ConfigError
from brdfremap.core.data.imageio import write_exr
from brdfremap.core.job.renders import CachedRenderer
from brdfremap.core.data.scene import EnvironmentLight, PointLight, ProbeScene, load_scene
from brdfremap.core.testing import analytic_lambert, box_filtered_lambert, environment_irradiance, sphere_hits
from brdfremap_example.adapter import ToyAdapter

from tests.helpers import ROOT, one_line_error, remap


def _scene(tmp_path, text: str, name: str = "scene.yaml"):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_one_light_written_the_old_way_is_a_list_of_one(tmp_path):
    old = load_scene(_scene(tmp_path, "light: {r: 5.2, theta: 60, phi: 125, intensity: 30}\n"))
    assert old.lights == [PointLight(theta=60.0)]
    assert old.cache_key() == ProbeScene(lights=[PointLight(theta=60.0)]).cache_key()
    with pytest.raises(ConfigError, match="either `light`"):
        load_scene(_scene(tmp_path, "light: {theta: 60}\nlights: [{theta: 30}]\n"))


def test_lights_without_a_type_are_point_lights_and_environments_say_so(tmp_path):
    s = load_scene(_scene(tmp_path, "lights:\n  - {theta: 30}\n  - {type: environment, map: studio, scale: 2}\n"))
    assert isinstance(s.lights[0], PointLight) and isinstance(s.lights[1], EnvironmentLight)
    assert s.light_types() == {"point", "environment"} and s.environment.scale == 2


def test_a_map_file_is_found_beside_the_scene_and_keyed_by_its_content(tmp_path):
    write_exr(tmp_path / "sky.exr", np.full((16, 32, 3), 0.5, np.float32))
    s = load_scene(_scene(tmp_path, "lights: [{type: environment, map: sky.exr}]\n"))
    assert s.environment.map == str((tmp_path / "sky.exr").resolve())
    key = s.cache_key()
    write_exr(tmp_path / "sky.exr", np.full((16, 32, 3), 0.25, np.float32))
    assert load_scene(tmp_path / "scene.yaml").cache_key() != key  # new pixels, new renders


@pytest.mark.parametrize("text, words", [
    ("lights: [{type: environment, map: missing.exr}]", ["lights.0.map", "file not found"]),
    ("lights: [{type: environment, map: flat.exr}]", ["lights.0.map", "twice as wide"]),
    ("lights: [{type: environment}, {type: environment, map: constant}]", ["lights", "more than one environment"]),
    ("lights: [{type: sun}]", ["lights.0"]),
    ("lights: []", ["lights"]),
    ("views: [{lights: [{r: 1}]}]", ["views.0.lights.0.r", "inside the sphere"]),
])
def test_bad_lights_are_one_line_naming_the_field(tmp_path, text, words):
    write_exr(tmp_path / "flat.exr", np.ones((16, 16, 3), np.float32))
    (tmp_path / "m.yaml").write_text("adapter: mitsuba\nmodel: diffuse\nparams: {reflectance: 0.5}\n")
    p = _scene(tmp_path, text + "\n")
    proc = remap("render", tmp_path / "m.yaml", "--scene", p, "--out", tmp_path / "x.exr")
    one_line_error(proc, str(p), *words)


def test_the_convention_maps_pixel_centres_back_to_their_uv():
    d = environment.pixel_directions(64, 32)
    uv = environment.direction_to_uv(d)
    u, v = np.meshgrid((np.arange(64) + 0.5) / 64, (np.arange(32) + 0.5) / 32)
    assert np.allclose(uv[..., 0], u) and np.allclose(uv[..., 1], v)
    assert np.allclose(environment.direction_to_uv(np.array([0.0, 1.0, 0.0]))[1], 0.0)  # top row: straight up
    assert np.isclose(environment.direction_to_uv(np.array([0.0, 0.0, 1.0]))[0], 0.5)  # centre: towards the camera


def test_rotation_moves_features_in_azimuth():
    px = np.zeros((8, 16, 3), np.float32)
    px[:, 3] = 1.0
    assert np.argmax(environment.rotated(px, 90.0)[0, :, 0]) == 7
    assert np.allclose(environment.rotated(px, 360.0), px)


def test_the_studio_is_asymmetric_and_the_constant_map_integrates_to_pi():
    s = environment.studio(128)
    assert not np.allclose(s, s[:, ::-1]) and not np.allclose(s, s[::-1])
    n = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])
    e = environment_irradiance(environment.constant(), n)
    assert np.allclose(e, math.pi, rtol=2e-3)  # a constant radiance of 1 on any surface: pi
    left, right = environment_irradiance(s, np.array([[-1.0, 0, 0], [1.0, 0, 0]]))
    assert left.sum() > 1.1 * right.sum()  # the key is on the left, warm; the fill on the right, cool
    assert left[0] > left[2] and right[2] > right[0]


def test_an_adapter_without_environments_refuses_them_before_any_render(tmp_path):
    env = ProbeScene(lights=[EnvironmentLight(type="environment")])
    assert "no environment light" in ToyAdapter.scene_problem(env)
    assert ToyAdapter.scene_problem(ProbeScene()) is None
    mat = tmp_path / "m.yaml"
    mat.write_text("adapter: mitsuba\nmodel: diffuse\nparams: {reflectance: 0.5}\n")
    p = _scene(tmp_path, "lights: [{type: environment}]\n")
    fake = ROOT / "tests" / "data" / "renderers" / "fake-oneshot.yaml"
    proc = remap("--adapter", fake, "--model", "lambert", "--source", mat, "--scene", p, "--out", tmp_path / "o")
    one_line_error(proc, "--scene", "'fake-oneshot'", "no environment light")
    assert not (tmp_path / "o" / "result.json").exists()


def test_views_render_one_below_the_other_and_point_lights_add_up():
    toy = ToyAdapter()
    spec = toy.models["toy"]
    p = spec.complete({"diffuse": 0.8, "specular": 0.0})
    a, b = PointLight(theta=30.0), PointLight(theta=100.0, phi=0.0, intensity=10.0)
    both = ProbeScene(lights=[a, b], resolution=32)
    views = ProbeScene(lights=[a], views=[{"lights": [b]}], resolution=32)
    r = CachedRenderer(toy, "toy", toy.models["toy"], views)
    img = r(p)
    assert img.shape == (64, 32, 3)
    one = [toy.render("toy", p, ProbeScene(lights=[x], resolution=32)) for x in (a, b)]
    assert np.allclose(img, np.concatenate(one)) and np.allclose(toy.render("toy", p, both), one[0] + one[1])
    assert np.allclose(toy.render("toy", p, both), box_filtered_lambert(both, 0.8), rtol=1e-5, atol=1e-7)
