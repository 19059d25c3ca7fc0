"""Nothing run that the user did not ask for, and every bad input one clear line (docs/reliability.md)."""

import json

import pytest
from helpers import MATERIALS, one_line_error, remap

GOLD = MATERIALS / "gold.yaml"
SMALL = ["--adapter", "mitsuba", "--model", "roughconductor", "--resolution", "32"]


def _write(path, text):
    path.write_text(text)
    return path


def test_a_material_or_experiment_file_cannot_run_a_program(tmp_path):
    """Case 2: `adapter:` naming a renderer definition beside a downloaded file is refused; the
    definition's command never runs."""
    pwned = tmp_path / "PWNED"
    _write(tmp_path / "r.yaml", f'name: evil\ncommand: ["sh", "-c", "touch {pwned}", "{{output}}"]\n'
                                "models: {m: {parameters: [{name: a, kind: scalar, default: 0.5}]}}\n")
    mat = _write(tmp_path / "material.yaml", "adapter: r.yaml\nmodel: m\n")
    one_line_error(remap("--source", mat, "--out", tmp_path / "o", *SMALL), "material.yaml: adapter:",
                   "'r.yaml' is a file")
    exp = _write(tmp_path / "exp.yaml", "kind: sweep\nname: t\nsource: {adapter: r.yaml, model: m}\n"
                                        "sweep: {param: a, values: [0.1, 0.2]}\ntarget: {adapter: mitsuba, model: "
                                        "diffuse}\nplot: {x: source.a, y: target.reflectance}\n")
    one_line_error(remap("sweep", exp, "--out", tmp_path / "o2"), "exp.yaml: source.adapter:")
    one_line_error(remap("render", mat, "--out", tmp_path / "x.exr"), "material.yaml: adapter:")
    assert not pwned.exists()


@pytest.mark.parametrize("text, words", [
    ("scene: {resolution: 0}", "exp.yaml: scene.resolution: Input should be greater than or equal to 8"),
    ("sweep: {param: alpha, range: {start: 0.1, stop: 0.2, steps: 100000000}}", "sweep.range.steps"),
    ("plot: {x: source.alpha, y: target.alphaa}", "plot.y: model 'roughconductor' has no parameter or derived "
                                                   "quantity 'alphaa'"),
    ("scene: {seed: 4294967296}", "scene.seed: Input should be less than or equal to 2147483646"),
])
def test_experiment_mistakes_are_found_before_the_first_point(tmp_path, text, words):
    """Cases 8 (a scene with resolution 0 gave a traceback), 9 (a range of 1e8 steps validated for
    minutes) and 12 (an unknown plot.y ran every point before plotting nothing)."""
    doc = {"kind": "sweep", "name": "t", "source": "{adapter: mitsuba, model: roughconductor}",
           "sweep": "{param: alpha, values: [0.1, 0.2]}", "target": "{adapter: mitsuba, model: roughconductor}",
           "plot": "{x: source.alpha, y: target.alpha}"}
    key, value = text.split(": ", 1)
    doc[key] = value
    exp = _write(tmp_path / "exp.yaml", "".join(f"{k}: {v}\n" for k, v in doc.items()))
    proc = remap("sweep", exp, "--out", tmp_path / "o", timeout=60)
    one_line_error(proc, words)
    assert not (tmp_path / "o" / "points").exists()


@pytest.mark.parametrize("args, words", [
    (["--precise-spp", "100000"], "--precise-spp: Input should be less than or equal to 64"),
    (["--spp", "65536"], "--precise-spp: 65536 spp x 4 is 262144 samples per pixel"),
    (["--seed", str(2**31)], "--seed: Input should be less than or equal to 2147483646"),
    (["--fix", "alpha=0.1", "--fix", "alpha=0.2"], "--fix alpha: given twice"),
    (["--fix", "eta=1,1,1"], "--fix eta: does nothing with material=Au: it is used only when material is none"),
    (["--resolution", "abc"], "argument --resolution: invalid int value: 'abc' (see `remap --help`)"),
    (["--jobs", "2"], "unrecognized arguments: --jobs 2"),
])
def test_values_beyond_what_renderers_take_are_refused(tmp_path, args, words):
    """Case 9 (values that reach a renderer are bounded by what it takes) and 12 (a repeated
    --fix, one that does nothing); usage errors are one line too."""
    one_line_error(remap("--source", GOLD, "--out", tmp_path / "o", *SMALL, *args), words)
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("text, words", [
    ("adapter: mitsuba\nmodel: roughconductor\nparams: {alpha: 5e-3}\n", None),  # YAML 1.1 made that a string
    ("adapter: mitsuba\nmodel: roughconductor\nparams: {alpha: 0.1}\nparams: {alpha: 0.2}\n",
     "m.yaml: line 4, column 1: malformed YAML: 'params' is given twice (first on line 3): keep one"),
    ("", "m.yaml: is empty: expected a material"),
    ("kind: sweep\nsweep: {param: alpha}\n", "m.yaml: is an experiment file, where a material was expected"),
    ("\x00\x01binary", "m.yaml"),
])
def test_material_files_are_read_as_users_write_them(tmp_path, text, words):
    mat = _write(tmp_path / "m.yaml", text)
    proc = remap("render", mat, "--out", tmp_path / "x.exr", "--resolution", "16", "--quiet")
    if words is None:
        assert proc.returncode == 0, proc.stderr
    else:
        one_line_error(proc, words)


def test_an_empty_scene_file_is_an_error_not_the_default_scene(tmp_path):
    """Case 12: an empty scene file silently meant the built-in probe."""
    one_line_error(remap("render", GOLD, "--scene", _write(tmp_path / "s.yaml", ""), "--out", tmp_path / "x.exr"),
                   "s.yaml: is empty: expected a scene")
    one_line_error(remap("render", GOLD, "--scene", _write(tmp_path / "c.yaml", "camera: {distance: 1.5}\n"),
                         "--out", tmp_path / "x.exr"), "c.yaml: camera.distance: puts it 1.5 from the sphere's "
                                                      "centre, inside the sphere")


def test_a_corrupt_probe_cache_is_ignored_and_rebuilt(tmp_path, mitsuba_adapter):
    """Case 8: a corrupt ~/.cache/brdfremap file broke every Mitsuba remap until deleted."""
    cache = tmp_path / "cache" / "brdfremap" / "mitsuba-llvm-probe.json"
    cache.parent.mkdir(parents=True)
    for junk in ("[]", '{"x": 1}', "\x00garbage"):
        cache.write_text(junk)
        proc = remap("render", GOLD, "--out", tmp_path / "x.exr", "--resolution", "16", "--quiet",
                     env={"XDG_CACHE_HOME": str(tmp_path / "cache")})
        assert proc.returncode == 0, proc.stderr
        assert isinstance(json.loads(cache.read_text()), dict)


def test_a_stored_point_that_is_valid_json_but_no_report_is_redone(tmp_path, mitsuba_adapter):
    """Case 8: a point's result.json without `metrics` gave a traceback; now it is redone, saying why."""
    exp = _write(tmp_path / "exp.yaml", "kind: sweep\nname: t\nsource: {adapter: mitsuba, model: roughconductor}\n"
                                        "sweep: {param: alpha, values: [0.1, 0.2]}\ntarget: {adapter: mitsuba, "
                                        "model: roughconductor}\nscene: {resolution: 32}\n"
                                        "plot: {x: source.alpha, y: target.alpha}\n")
    assert remap("sweep", exp, "--out", tmp_path / "o", "--quiet").returncode == 0
    point = tmp_path / "o/points/00-001/result.json"
    doc = json.loads(point.read_text())
    point.write_text(json.dumps({k: v for k, v in doc.items() if k != "metrics"}))
    proc = remap("sweep", exp, "--out", tmp_path / "o")
    assert proc.returncode == 0 and "(1 remaps resumed" in proc.stdout, proc.stderr
    assert "00-001" in proc.stderr and "redone: " in proc.stderr and "metrics: Field required" in proc.stderr


def test_a_report_written_by_a_newer_version_is_not_overwritten(tmp_path, mitsuba_adapter):
    out = tmp_path / "o"
    assert remap("--source", GOLD, "--out", out, *SMALL, "--quiet").returncode == 0
    doc = json.loads((out / "result.json").read_text())
    (out / "result.json").write_text(json.dumps({**doc, "schema_version": 99}))
    one_line_error(remap("--source", GOLD, "--out", out, *SMALL), "written by a newer brdf-remap",
                   "nothing was overwritten")
    assert json.loads((out / "result.json").read_text())["schema_version"] == 99


@pytest.mark.parametrize("text, words", [
    ("adapter: mitsuba\nmodel: roughconductor\nparams: {alpha: 0.1, alpha: 0.2}\n", "'alpha' is given twice"),
    ("adapter: mitsuba\nmodel: roughconductor\nb: &b {alpha: 0.1}\nparams: {<<: *b}\n",
     "aliases (*name) and merge keys (<<) are not supported"),
    ("adapter: mitsuba\nmodel: roughconductor\nparams: {alpha: " + "[" * 5000 + "]" * 5000 + "}\n",
     "nested too deeply"),
    ("adapter: mitsuba\nmodel: roughconductor\nparams: {alpha: " + "x" * 100000 + "}\n", "expected a number"),
])
def test_hostile_yaml_is_one_short_line(tmp_path, text, words):
    """A flow mapping's duplicate, anchors and merge keys (a "billion laughs" file expands to
    gigabytes), deep nesting, a huge value: one short line each."""
    mat = _write(tmp_path / "m.yaml", text)
    line = one_line_error(remap("render", mat, "--out", tmp_path / "x.exr", timeout=60), words)
    assert len(line) < 400


@pytest.mark.parametrize("scene, words", [
    ("camera: {target: [0, 100, 0]}", "camera.target: the sphere is 86 degrees off the view axis"),
    ("sphere: {center: [0, 0, 10]}", "camera.target: the sphere is 180 degrees off the view axis"),
    ("camera: {up: [0, 0, 0]}", "camera: up: must not be zero nor along the view axis"),
    ("camera: {up: [0, 0, 1]}", "camera: up: must not be zero nor along the view axis"),
    ("light: {intensity: .inf}", "lights.0.intensity: Input should be a finite number"),
])
def test_a_scene_that_would_render_black_is_refused_naming_the_field(tmp_path, scene, words):
    one_line_error(remap("render", GOLD, "--scene", _write(tmp_path / "s.yaml", scene + "\n"),
                         "--out", tmp_path / "x.exr"), "s.yaml", words)


@pytest.mark.parametrize("args, words", [
    (["rendr", str(GOLD), "--out", "x.exr"], "unknown command 'rendr' (commands: convert, table, render"),
    (["render", "RESULT", "--out", "x.exr"], "is a result (result.json) file, where a material was expected"),
    (["--adapter", "cycles", "--model", "principled", "--source", str(GOLD), "--out", "o", "--fix",
      "coat_roughness=0.1"], "--fix coat_roughness: does nothing with coat_weight=0"),
])
def test_a_mistaken_command_file_or_fix_is_named(tmp_path, args, words, mitsuba_adapter):
    out = tmp_path / "r"
    assert remap("--source", GOLD, "--out", out, *SMALL, "--quiet").returncode == 0
    args = [str(out / "result.json") if a == "RESULT" else a for a in args]
    one_line_error(remap(*args, cwd=tmp_path), words)


def test_a_sweep_on_an_empty_scheduler_address_is_refused(tmp_path):
    exp = _write(tmp_path / "e.yaml", "kind: sweep\nname: t\nsource: {adapter: mitsuba, model: roughconductor}\n"
                                      "sweep: {param: alpha, values: [0.1]}\ntarget: {adapter: mitsuba, model: "
                                      "roughconductor}\nplot: {x: source.alpha, y: target.alpha}\n")
    one_line_error(remap("sweep", exp, "--out", tmp_path / "o", "--scheduler", ""), "--scheduler: is empty")


@pytest.mark.parametrize("models, words", [
    ("{m: {parameters: [{name: a, kind: scalar, default: 0.5}, {name: a, kind: scalar, default: 0.5}]}}",
     "models: model 'm' has duplicate parameter names"),
    ("{m: {parameters: [{name: a, kind: scalar, upper: 1, default: 5}]}}", "parameter 'a': default 5.0 is outside [0, 1]"),
])
def test_a_definitions_model_mistakes_are_one_line_when_it_is_loaded(tmp_path, models, words):
    d = _write(tmp_path / "d.yaml", f'name: d\ncommand: ["x", "{{output}}"]\nmodels: {models}\n')
    line = one_line_error(remap("--adapter", d, "--model", "m", "--source", GOLD, "--out", tmp_path / "o"), "d.yaml")
    assert words in line and "errors.pydantic.dev" not in line


def test_more_cycles_workers_than_cores_is_refused_naming_the_variable(tmp_path):
    """Third trial N8: BRDFREMAP_CYCLES_WORKERS=100000 started Blenders without bound (275 MB each)."""
    proc = remap("render", MATERIALS / "cycles-red-plastic.yaml", "--out", tmp_path / "x.exr",
                 env={"BRDFREMAP_CYCLES_WORKERS": "100000"})
    one_line_error(proc, "BRDFREMAP_CYCLES_WORKERS", "100000", "cores")
