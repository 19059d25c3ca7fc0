"""Renderer definitions a new user writes (issue 18): a scene language with braces of its own, a
model's text carrying its values, faults named at load time or with what the renderer did write.
Each runs a real renderer process: tests/data/renderers/brace_renderer.py."""

import sys
from pathlib import Path

import numpy as np
import pytest

from brdfremap.adapters.subprocess.adapter import adapter_class
from brdfremap.core.data.errors import ConfigError, RenderError
from brdfremap.core.data.metrics import relative_rmse
from brdfremap.core.data.scene import ProbeScene
from brdfremap.core.testing import analytic_lambert, box_filtered_lambert

DATA = Path(__file__).resolve().parents[1] / "data" / "renderers"
SCENE = ProbeScene(resolution=32, spp=4)

TEMPLATE = """# brace scene: {{ and }} are literal braces, even in a comment like this {{not_a_placeholder}}
scene {{
  size = {width} x {height}
}}
material {{
  {material}
}}
"""


def _definition(tmp_path, *, template=TEMPLATE, material="albedo = {p_albedo}", extra_args=(), output="exr",
                lobes="{diffuse: {}, specular: empty}", params=None, fmt: int | None = 2) -> Path:
    (tmp_path / "scene.brace").write_text(template)
    args = ", ".join(f'"{a}"' for a in ["{python}", str(DATA / "brace_renderer.py"), "{scene_json}", "{scene_file}",
                                         "{output}", *extra_args])
    params = params or "[{name: albedo, kind: rgb, default: [0.5, 0.5, 0.5]}]"
    path = tmp_path / "brace.yaml"
    path.write_text(("" if fmt is None else f"format: {fmt}\n") + f"name: brace\ncommand: [{args}]\nscene_template: scene.brace\noutput_format: {output}\n"
                    f"rgb_format: '{{r}} {{g}} {{b}}'\ntimeout: 30\n"
                    f"models:\n  lambert:\n    parameters: {params}\n    lobes: {lobes}\n"
                    f"    template_vars:\n      material: '{material}'\n")
    return path


def _render(path, albedo=(0.2, 0.4, 0.6)):
    adapter = adapter_class(path)()
    try:
        return adapter.render("lambert", adapter.models["lambert"].complete({"albedo": list(albedo)}), SCENE)
    finally:
        adapter.close()


def test_a_models_text_carries_its_values_into_a_brace_language(tmp_path):
    """New user's item 1 and 2: {p_albedo} inside template_vars is filled (RGB through rgb_format),
    and {{ }} write the scene language's own braces."""
    img = _render(_definition(tmp_path))
    want = box_filtered_lambert(SCENE, np.array([0.2, 0.4, 0.6], np.float32))
    assert relative_rmse(want, img) < 1e-5


@pytest.mark.parametrize("template, line, name", [
    (TEMPLATE.replace("size = {width}", "size = {widht}"), 3, "widht"),
    ("# a comment with {braces}\n" + TEMPLATE, 1, "braces"),
])
def test_an_unknown_placeholder_is_named_with_file_and_line_when_loaded(tmp_path, template, line, name):
    path = _definition(tmp_path, template=template)
    with pytest.raises(ConfigError) as exc:
        adapter_class(path)
    msg = str(exc.value)
    assert f"scene.brace: line {line}: unknown placeholder {{{name}}}" in msg and "{{ or }}" in msg, msg
    assert "\n" not in msg


def test_a_template_var_naming_another_models_parameter_is_refused_when_loaded(tmp_path):
    path = _definition(tmp_path, material="albedo = {p_colour}")
    with pytest.raises(ConfigError) as exc:
        adapter_class(path)
    msg = str(exc.value)
    assert "models.lambert.template_vars.material" in msg and "{p_colour}" in msg and "line 1" not in msg, msg


def test_a_placeholder_in_capitals_is_named_not_sent_as_text(tmp_path):
    """The new-user trial's {P_albedo} reached the renderer literally and crashed it."""
    with pytest.raises(ConfigError) as exc:
        adapter_class(_definition(tmp_path, material="albedo = {P_albedo}"))
    assert "{P_albedo} in models.lambert.template_vars.material is not a placeholder" in str(exc.value)
    assert "write {p_albedo}" in str(exc.value)


def test_no_image_where_asked_lists_what_the_renderer_did_write(tmp_path):
    """Item 5: "wrote no image at image.exr" when it wrote image.exr.png beside it."""
    with pytest.raises(RenderError) as exc:
        _render(_definition(tmp_path, extra_args=["--misname"]))
    assert "wrote no image at image.exr (it wrote: image.exr.png)" in str(exc.value)


def test_radiance_hdr_is_read(tmp_path):
    """Item 6: .hdr was refused as an output format."""
    img = _render(_definition(tmp_path, output="hdr"))
    want = box_filtered_lambert(SCENE, np.array([0.2, 0.4, 0.6], np.float32))
    assert relative_rmse(want, img) < 0.01  # RGBE: an 8-bit mantissa


def test_half_float_pixels_are_noted_once(tmp_path, capsys):
    adapter = adapter_class(_definition(tmp_path, extra_args=["--pixels", "half"]))()
    try:
        params = adapter.models["lambert"].complete({"albedo": [0.2, 0.4, 0.6]})
        adapter.render("lambert", params, SCENE)
        adapter.render("lambert", params, SCENE.with_(seed=1))
    finally:
        adapter.close()
    err = capsys.readouterr().err
    assert err.count("writes half pixels") == 1 and "0.05%" in err and "so they serve" in err, err


def test_an_ambiguous_short_lobe_form_is_refused_showing_the_long_form(tmp_path):
    """Item 7: a colour both lobes share went to the specular stage (57.8 % after the merge)."""
    params = ("[{name: color, kind: rgb, default: [0.5, 0.5, 0.5]}, {name: diffuse, kind: scalar, default: 1}, "
              "{name: specular, kind: scalar, default: 0.5}]")
    path = _definition(tmp_path, params=params, material="albedo = {p_color}",
                       lobes="{diffuse: {specular: 0}, specular: {diffuse: 0}}")
    with pytest.raises(ConfigError) as exc:
        adapter_class(path)
    msg = str(exc.value)
    assert "brace.yaml" in msg and "leaves color to neither lobe" in msg and "or in neither when both lobes share" in msg
    assert "diffuse: {overrides: {specular: 0}, params: [diffuse]}" in msg, msg


def test_a_definition_of_the_first_format_is_read_as_it_was_meant_with_a_note(tmp_path, capsys):
    """Issue 35: a definition the previous version accepted (no `format:`, an ambiguous short lobe
    form) is read as that version read it (what neither lobe switches off: the specular stage's) and
    says once what the current form is; one from a newer version is refused naming both formats."""
    from brdfremap.adapters.subprocess import definition

    params = ("[{name: color, kind: rgb, default: [0.5, 0.5, 0.5]}, {name: diffuse, kind: scalar, default: 1}, "
              "{name: specular, kind: scalar, default: 0.5}]")
    lobes = "{diffuse: {specular: 0}, specular: {diffuse: 0}}"
    path = _definition(tmp_path, params=params, material="albedo = {p_color}", lobes=lobes, fmt=None)
    definition._SAID.clear()
    spec = adapter_class(path).models["lambert"]
    adapter_class(path)
    assert spec.lobes["specular"].params == ("specular", "color") and spec.lobes["diffuse"].params == ("diffuse",)
    err = capsys.readouterr().err
    assert err.count("note:") == 1 and "brace.yaml: format 1: lambert.lobes: the short form leaves color" in err
    assert "add `format: 2` once changed" in err, err
    newer = _definition(tmp_path, fmt=3)
    newer.write_text(newer.read_text() + "shading_language: osl\n")  # a field of that newer format
    with pytest.raises(ConfigError, match=r"brace.yaml.*newer brdf-remap \(definition format 3; this one reads 1 "
                                          r"to 2\)"):
        adapter_class(newer)


def test_the_command_line_has_escapes_too(tmp_path):
    path = _definition(tmp_path, extra_args=["{{literal}}"])
    text = path.read_text()
    assert "{{literal}}" in text
    with pytest.raises(RenderError) as exc:  # the renderer gets "{literal}" and refuses an unknown argument
        _render(path)
    assert "{literal}" in str(exc.value) and "{{literal}}" not in str(exc.value)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(pytest.main([__file__, "-q"]))


def _check(path, *args):
    import subprocess

    return subprocess.run([sys.executable, "-m", "brdfremap.core.cli", "check", str(path), *args],
                          capture_output=True, text=True, timeout=300)


def _checked(tmp_path, *extra):
    path = _definition(tmp_path, extra_args=list(extra))
    path.write_text(path.read_text() + "calibration: {model: lambert, params: {albedo: [0.8, 0.8, 0.8]}}\n")
    return _check(path)


def test_remap_check_passes_a_correct_renderer(tmp_path):
    proc = _checked(tmp_path)
    assert proc.returncode == 0 and "all checks pass" in proc.stdout and "FAIL" not in proc.stdout, proc.stdout


@pytest.mark.parametrize("fault, row, words", [
    (["--scale", "3.14159265"], "units", "a factor of π"),
    (["--scale", "0.0795774715"], "units", "a factor of 1/(4π)"),
    (["--mirror"], "orientation", "the image is mirrored left-right"),
    (["--mirror", "--scale", "3.14159265"], "units", "a factor of π"),
    (["--clip"], "precision", "clipped"),
])
def test_remap_check_names_each_fault(tmp_path, fault, row, words):
    """Item 3: wrong units (and the factor), a mirrored image, clipping, half floats: each a failed
    row with its fix; exit 1."""
    proc = _checked(tmp_path, *fault)
    failing = [line for line in proc.stdout.splitlines() if line.strip().startswith("FAIL")]
    assert proc.returncode == 1 and any(row in line and words in line for line in failing), proc.stdout
    assert "fix:" in proc.stdout and "Traceback" not in proc.stderr


def test_half_floats_pass_with_a_note(tmp_path):
    """Issue 35: POV-Ray writes only half-float EXR. Half floats round at 0.05 %, far below the render
    noise and the fit's steps: the precision row passes and says so, and the lobes may round apart."""
    proc = _checked(tmp_path, "--pixels", "half")
    row = next(line for line in proc.stdout.splitlines() if "precision" in line)
    assert proc.returncode == 0 and row.strip().startswith("pass") and "half float" in row, proc.stdout


def test_a_held_parameter_needs_no_lobe_in_the_short_form(tmp_path):
    """Issue 35: a definition the previous version accepted was refused for parameters held at their
    value (fit: false) that neither short-form lobe switches off; only fitted ones need a lobe."""
    from brdfremap.adapters.subprocess.definition import load_definition

    params = ("[{name: albedo, kind: rgb, default: [0.5, 0.5, 0.5]}, {name: gloss, kind: scalar, default: 0.3}, "
              "{name: ambient, kind: scalar, default: 0.0, fit: false}]")
    held = _definition(tmp_path, params=params, lobes="{diffuse: {gloss: 0.0}, specular: {albedo: [0, 0, 0]}}")
    specs = load_definition(held).model_specs()
    assert set(specs["lambert"].lobes) == {"diffuse", "specular"}
    fitted = held.read_text().replace("{name: ambient, kind: scalar, default: 0.0, fit: false}",
                                      "{name: ambient, kind: scalar, default: 0.0}")
    held.write_text(fitted)
    with pytest.raises(ConfigError, match="leaves ambient to neither lobe"):
        load_definition(held)


def _white_through(tmp_path, definition: Path, model: str) -> dict:
    """Mitsuba's white Lambertian (albedo 0.8) remapped to ``model`` of a renderer definition, as a user
    runs it; its result.json."""
    import json
    import subprocess

    (tmp_path / "white.yaml").write_text("adapter: mitsuba\nmodel: diffuse\nparams: {reflectance: 0.8}\n")
    run = subprocess.run([sys.executable, "-m", "brdfremap.core.cli", "--adapter", str(definition), "--model", model,
                          "--source", str(tmp_path / "white.yaml"), "--out", str(tmp_path / "out"), "--quiet"],
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr
    return json.loads((tmp_path / "out" / "result.json").read_text())


NODE = Path(__file__).resolve().parents[2] / "examples" / "renderer-node" / "renderer.yaml"


@pytest.mark.skipif(__import__("shutil").which("node") is None, reason="needs Node.js: apt-get install nodejs")
def test_a_persistent_renderer_in_javascript_passes_check_and_remaps(tmp_path, mitsuba_adapter):
    """Issue 35: the JSON-lines mode with a renderer that is not Python (examples/renderer-node): every
    check passes, and a white Lambertian comes back as itself."""
    proc = _check(NODE)
    assert proc.returncode == 0 and "all checks pass" in proc.stdout, proc.stdout + proc.stderr
    r = _white_through(tmp_path, NODE, "phong")
    assert r["verdict"] == "ok" and abs(r["params"]["diffuse"][0] / 0.8 - 1) < 0.01, r["reason"]

POVRAY = Path(__file__).resolve().parents[2] / "examples" / "renderer-povray" / "povray.yaml"


@pytest.mark.skipif(__import__("shutil").which("povray") is None, reason="needs POV-Ray: apt-get install povray")
def test_the_newcomers_povray_definition_passes_check_and_remaps(tmp_path, mitsuba_adapter):
    """Issue 35: POV-Ray 3.7 from Debian, defined from the README alone (half-float EXR, its sample grid
    capped at 9): every check passes, and a white Lambertian comes back as itself, ok."""
    proc = _check(POVRAY)
    assert proc.returncode == 0 and "all checks pass" in proc.stdout and "half float" in proc.stdout, proc.stdout
    r = _white_through(tmp_path, POVRAY, "diffuse")
    assert r["verdict"] == "ok" and abs(r["params"]["reflectance"][0] / 0.8 - 1) < 0.01, r["reason"]

def test_remap_check_without_a_calibration_material_says_what_is_missing(tmp_path):
    proc = _check(_definition(tmp_path))
    assert proc.returncode == 1 and "not run" in proc.stdout and "calibration: {model: ..." in proc.stdout, proc.stdout


SHIPPED = Path(__file__).resolve().parents[2] / "configs" / "renderers"


@pytest.mark.parametrize("adapter, needs", [("mitsuba", "mitsuba"), ("cycles", "bpy"),
                                            (str(SHIPPED / "mitsuba-cli.yaml"), "mitsuba"),
                                            (str(SHIPPED / "cycles-subprocess.yaml"), "bpy"),
                                            (str(SHIPPED.parents[1] / "examples" / "renderer" / "my-renderer.yaml"),
                                             "mitsuba")])
def test_remap_check_passes_the_built_in_and_shipped_adapters(adapter, needs):
    pytest.importorskip(needs)
    proc = _check(adapter)
    assert proc.returncode == 0 and "all checks pass" in proc.stdout, proc.stdout + proc.stderr


def _remap_through(tmp_path, path):
    import json
    import subprocess

    (tmp_path / "white.yaml").write_text("adapter: mitsuba\nmodel: diffuse\nparams: {reflectance: 0.8}\n")
    (tmp_path / "bright.yaml").write_text("lights: [{type: point, intensity: 300.0}]\nresolution: 32\nspp: 4\n")
    proc = subprocess.run([sys.executable, "-m", "brdfremap.core.cli", "--adapter", str(path), "--model", "lambert",
                           "--source", str(tmp_path / "white.yaml"), "--scene", str(tmp_path / "bright.yaml"),
                           "--out", str(tmp_path / "out"), "--validate", "none", "--quiet"],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    return json.loads((tmp_path / "out" / "result.json").read_text())


@pytest.mark.parametrize("extra, output, words", [(["--clip"], "exr", "clips at 1"),
                                                  ([], "png", "has 256 sRGB levels")])
def test_a_clipped_or_8_bit_image_is_named_not_called_a_model_mismatch(tmp_path, mitsuba_adapter, extra, output,
                                                                       words):
    """Item 4: an 8-bit PNG clips highlights at 1 and the fit reported 90 % as "the closest this
    target model gets"."""
    r = _remap_through(tmp_path, _definition(tmp_path, extra_args=extra, output=output))
    kinds = [f["kind"] for f in r["findings"] if f["severity"] == "unreliable"]
    assert r["verdict"] == "unreliable" and "image_precision" in kinds and "model_mismatch" not in kinds, kinds
    msg = next(f["message"] for f in r["findings"] if f["kind"] == "image_precision")
    assert "target renderer's image" in msg and words in msg and "float EXR" in msg, msg


def test_samples_can_be_written_as_a_grid_side_or_a_power_of_two(tmp_path):
    """Item 8: a renderer taking √spp (a stratified grid) or a depth got the same image at 4x samples."""
    copy = tmp_path / "filled.brace"
    path = _definition(tmp_path, template=TEMPLATE + "samples = {spp} grid = {spp_sqrt} depth = {spp_log2}\n",
                       extra_args=["--copy-scene", str(copy)])
    adapter = adapter_class(path)()
    try:
        params = adapter.models["lambert"].complete({})
        for spp, grid, depth in ((16, 4, 4), (17, 5, 5), (64, 8, 6)):
            adapter.render("lambert", params, SCENE.with_(spp=spp))
            assert f"samples = {spp} grid = {grid} depth = {depth}" in copy.read_text()
    finally:
        adapter.close()


def test_one_shot_renders_of_a_batch_run_at_once(tmp_path):
    """Item 9: a Jacobian's renders ran one after the other while the renderer waited. With
    `jobs: 4`, four renders of a renderer that waits overlap (their logged intervals)."""
    log = tmp_path / "times.log"
    path = _definition(tmp_path, extra_args=["--sleep", "0.5", "--log", str(log)])
    path.write_text(path.read_text() + "jobs: 4\n")
    adapter = adapter_class(path)()
    try:
        p = adapter.models["lambert"].complete({})
        images = adapter.render_batch([("lambert", {**p, "albedo": (a, a, a)}, SCENE, None) for a in (0.2, 0.4, 0.6, 0.8)])
    finally:
        adapter.close()
    assert [float(img.max()) for img in images] == sorted(float(img.max()) for img in images)  # in request order
    spans = [tuple(map(float, line.split())) for line in log.read_text().splitlines()]
    assert len(spans) == 4 and max(s for s, _ in spans) < min(e for _, e in spans)  # all four under way at once


def test_a_native_template_writes_the_fitted_material_beside_the_result(tmp_path, mitsuba_adapter):
    """Item 10: Mitsuba gets material.xml, Cycles material.blend; a YAML renderer got only numbers."""
    path = _definition(tmp_path)
    path.write_text(path.read_text() + "    native: {file: material.brace, text: 'material {{ albedo = {p_albedo} }} "
                                       "# {model}'}\n")
    r = _remap_through(tmp_path, path)
    text = (tmp_path / "out" / "material.brace").read_text()
    fitted = r["params"]["albedo"]
    assert text == f"material {{ albedo = {fitted[0]:.9g} {fitted[1]:.9g} {fitted[2]:.9g} }} # lambert", text
    assert "material.brace" in [f["name"] for f in r["files"]]


@pytest.mark.parametrize("native, words", [("{file: ../x, text: a}", "plain file name"),
                                           ("{file: result.json, text: a}", "plain file name"),
                                           ("{file: m.txt, text: '{p_colour}'}", "models.lambert.native.text")])
def test_a_bad_native_template_is_refused_when_loaded(tmp_path, native, words):
    path = _definition(tmp_path)
    path.write_text(path.read_text() + f"    native: {native}\n")
    with pytest.raises(ConfigError) as exc:
        adapter_class(path)
    assert words in str(exc.value) and "brace.yaml" in str(exc.value)


def test_remap_adapters_shows_a_definition_given_by_path_with_bounds(tmp_path):
    """Item 11."""
    import subprocess

    path = _definition(tmp_path)
    proc = subprocess.run([sys.executable, "-m", "brdfremap.core.cli", "adapters", str(path)], capture_output=True,
                          text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.startswith("brace  [file ") and "albedo (rgb [0, 1]; default [0.5, 0.5, 0.5])" in proc.stdout
    assert "cycles" not in proc.stdout


def test_convert_to_a_definition_file_gathers_each_materials_native_file(tmp_path, mitsuba_adapter):
    """Item 10's library: a target no library writer knows gets each material's native file."""
    import subprocess

    path = _definition(tmp_path)
    path.write_text(path.read_text() + "    native: {file: material.brace, text: 'material {{ albedo = {p_albedo} }}'}\n")
    lib = tmp_path / "lib"
    lib.mkdir()
    (lib / "white.yaml").write_text("adapter: mitsuba\nmodel: diffuse\nparams: {reflectance: 0.8}\n")
    proc = subprocess.run([sys.executable, "-m", "brdfremap.core.cli", "convert", str(lib), "--to", f"{path}:lambert",
                           "--out", str(tmp_path / "out"), "--resolution", "32", "--spp", "4", "--validate", "none"],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert f"libraries   {tmp_path / 'out'}/native" in proc.stdout
    (written,) = (tmp_path / "out" / "native").glob("*/material.brace")
    text = written.read_text()
    values = [float(v) for v in text.split("=")[1].split("}")[0].split()]
    assert text.startswith("material { albedo = ") and all(abs(v / 0.8 - 1) < 0.05 for v in values), text


@pytest.mark.parametrize("yaml_text, words", [
    ("    native: {file: Result.JSON, text: a}\n", "plain file name"),
    ("    template_vars: {width: '1'}\n", "cannot be a template_vars name"),
])
def test_names_that_would_overwrite_a_result_file_or_a_placeholder_are_refused(tmp_path, yaml_text, words):
    path = _definition(tmp_path)
    text = path.read_text()
    if "template_vars" in yaml_text:
        text = text.replace("    template_vars:\n      material: 'albedo = {p_albedo}'\n",
                            "    template_vars: {material: 'albedo = {p_albedo}', width: '1'}\n")
    else:
        text += yaml_text
    path.write_text(text)
    with pytest.raises(ConfigError) as exc:
        adapter_class(path)
    assert words in str(exc.value)


def test_an_escaped_output_placeholder_is_not_taken_for_one(tmp_path):
    path = _definition(tmp_path)
    path.write_text(path.read_text().replace('"{output}"', '"{{output}}"'))
    with pytest.raises(ConfigError) as exc:
        adapter_class(path)
    assert "use {output}" in str(exc.value)


# -- a declared start and reading (issue 46): the exporters' conversions as data -----------------

PLASTIC = ("[{name: distribution, kind: choice, choices: [beckmann, ggx], default: ggx}, "
           "{name: albedo, kind: rgb, default: [0.5, 0.5, 0.5]}, {name: roughness, kind: scalar, default: 0.5}, "
           "{name: gloss, kind: scalar, default: 0.5, fit: false}, "
           "{name: ior, kind: scalar, lower: 1.0, upper: 3.0, default: 1.5}, "
           "{name: level, kind: scalar, default: 0.5, fit: false}]")
DECLARED = """    start:
      distribution: distribution
      albedo: base_color
      roughness: {from: alpha, as: sqrt}
      gloss: {from: alpha, as: [sqrt, one_minus]}
      ior: ior
      level: {from: specular, as: mean, scale: 12.5}
    reading:
      kind: dielectric
      alpha: {from: roughness, as: square}
      distribution: distribution
      diffuse: albedo
      ior: ior
"""


def _declared(tmp_path, declared: str = DECLARED) -> Path:
    path = _definition(tmp_path, params=PLASTIC)
    path.write_text(path.read_text() + declared)
    return path


def _start(src, adapter: str, model: str) -> dict:
    from brdfremap.core.data.settings import Settings
    from brdfremap.core.host.plugins import collect_adapters
    from brdfremap.core.job.execute import informed_start
    from brdfremap.core.job.job import Job, Target, resolve

    registry = collect_adapters()
    names = {a: registry.resolve(a) if a.endswith(".yaml") else a for a in (src.adapter, adapter)}
    src = src.model_copy(update={"adapter": names[src.adapter]})
    job = Job(source=src, target=Target(adapter=names[adapter], model=model), scene=ProbeScene(), settings=Settings(),
              label="m.yaml")
    return informed_start(resolve(job, registry))


def test_a_declared_start_is_the_informed_start_leaving_out_what_the_reading_lacks(tmp_path):
    from brdfremap.core.data.schemas import Material

    path = str(_declared(tmp_path))
    plastic = Material(adapter="mitsuba", model="roughplastic", params={
        "distribution": "beckmann", "alpha": 0.09, "int_ior": 1.6, "diffuse_reflectance": [0.6, 0.2, 0.1]})
    start = _start(plastic, path, "lambert")
    assert start["distribution"] == "beckmann" and start["albedo"] == pytest.approx((0.6, 0.2, 0.1))
    assert start["roughness"] == pytest.approx(0.3) and start["gloss"] == pytest.approx(0.7)  # held, set all the same
    assert start["ior"] == pytest.approx(1.6 / 1.000277)
    assert start["level"] == pytest.approx(((start["ior"] - 1) / (start["ior"] + 1)) ** 2 * 12.5)
    # A Lambertian source has no specular lobe (no α) and names no distribution: neither is started.
    white = Material(adapter="mitsuba", model="diffuse", params={"reflectance": [0.8, 0.8, 0.8]})
    start = _start(white, path, "lambert")
    assert start["albedo"] == (0.8, 0.8, 0.8) and not {"roughness", "gloss", "distribution"} & set(start)


def test_a_declared_reading_starts_a_remap_from_the_renderer(tmp_path):
    from brdfremap.core.data.schemas import Material

    mine = Material(adapter=str(_declared(tmp_path)), model="lambert", params={
        "distribution": "beckmann", "albedo": [0.6, 0.2, 0.1], "roughness": 0.4, "ior": 1.6})
    start = _start(mine, "mitsuba", "roughplastic")
    assert start["distribution"] == "beckmann" and start["alpha"] == pytest.approx(0.16)
    assert start["diffuse_reflectance"] == pytest.approx((0.6, 0.2, 0.1))
    assert start["int_ior"] == pytest.approx(1.6 * 1.000277)


def test_the_worked_examples_start_converts_each_model():
    """examples/renderer/my-renderer.yaml: a conductor's complex IOR as it is; Disney's roughness √α and
    specular F0 / 0.08 for its principled model."""
    from brdfremap.core.data.schemas import Material

    example = str(SHIPPED.parents[1] / "examples" / "renderer" / "my-renderer.yaml")
    gold = Material(adapter="mitsuba", model="roughconductor", params={
        "distribution": "beckmann", "eta": [0.14, 0.37, 1.44], "k": [3.98, 2.38, 1.6], "alpha": 0.1})
    assert _start(gold, example, "conductor") == {"distribution": "beckmann", "eta": (0.14, 0.37, 1.44),
                                                  "k": (3.98, 2.38, 1.6), "alpha": 0.1}
    plastic = Material(adapter="mitsuba", model="roughplastic", params={
        "alpha": 0.09, "int_ior": 1.5 * 1.000277, "diffuse_reflectance": [0.6, 0.2, 0.1]})
    start = _start(plastic, example, "principled")
    assert start["base_color"] == pytest.approx((0.6, 0.2, 0.1)) and start["metallic"] == 0.0
    assert start["roughness"] == pytest.approx(0.3) and start["specular"] == pytest.approx(0.04 / 0.08)


@pytest.mark.parametrize("change, words", [
    (("as: sqrt}", "as: sqr}"), "models.lambert.start.roughness.as: unknown conversion 'sqr' (known: identity, sqrt,"),
    (("albedo: base_color", "albedo: base_colour"),
     "models.lambert.start.albedo: 'base_colour' is not a quantity of the neutral reading (known: kind,"),
    (("      ior: ior\n      level", "      iorr: ior\n      level"),
     "models.lambert.start.iorr: not a parameter of lambert (its parameters: distribution, albedo,"),
    (("level: {from: specular, as: mean,", "level: {from: specular,"),
     "models.lambert.start.level: specular gives a colour, and level takes a number: add `as: mean`"),
    (("diffuse: albedo", "diffuse: colour"), "models.lambert.reading.diffuse: 'colour' is not a parameter of lambert"),
    (("kind: dielectric", "kind: metal"), "models.lambert.reading.kind: Input should be 'conductor' or 'dielectric'"),
    (("{from: roughness, as: square}", "{from: roughness, as: square, eval: 'x*x'}"),
     "models.lambert.reading.alpha.eval: unknown field"),
])
def test_a_bad_start_or_reading_is_one_line_naming_the_file_and_field(tmp_path, change, words):
    old, new = change
    assert old in DECLARED
    with pytest.raises(ConfigError) as exc:
        adapter_class(_declared(tmp_path, DECLARED.replace(old, new)))
    msg = str(exc.value)
    assert msg.startswith(f"{tmp_path / 'brace.yaml'}: ") and words in msg and "\n" not in msg, msg
