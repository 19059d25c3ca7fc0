"""External renderers from YAML: the good path and every fault, with a real misbehaving process."""

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from brdfremap.adapters.subprocess.adapter import adapter_class
from brdfremap.core.data.errors import ConfigError, RenderError
from brdfremap.core.data.metrics import relative_rmse
from brdfremap.core.data.scene import ProbeScene
from brdfremap.core.testing import AdapterContract, box_filtered_lambert

DATA = Path(__file__).resolve().parents[1] / "data" / "renderers"
SCENE = ProbeScene(resolution=32)


@pytest.fixture(scope="module")
def oneshot():
    a = adapter_class(DATA / "fake-oneshot.yaml")()
    yield a
    a.close()


@pytest.fixture(scope="module")
def persistent():
    a = adapter_class(DATA / "fake-persistent.yaml")()
    yield a
    a.close()


def _p(adapter, **kw):
    return adapter.models["lambert"].complete(kw)


def test_good_render_is_the_analytic_image(oneshot):
    img = oneshot.render("lambert", _p(oneshot, albedo=0.8), SCENE)
    assert img.dtype == np.float32 and img.shape == (32, 32, 3)
    assert relative_rmse(box_filtered_lambert(SCENE, 0.8), img) < 1e-6


@pytest.mark.parametrize("fault, words", [
    ("exit", "exit code 3"),
    ("no_output", "wrote no image"),
    ("nan", "NaN or Inf"),
    ("wrong_size", "image is 28x28, expected 32x32"),
    ("truncated", "truncated or corrupt image: "),
    ("garbage", "unreadable image"),
])
def test_faults_are_render_errors_naming_renderer_params_and_stderr(oneshot, fault, words):
    with pytest.raises(RenderError) as e:
        oneshot.render("lambert", _p(oneshot, fault=fault), SCENE)
    msg = str(e.value)
    assert msg.startswith("renderer 'fake-oneshot' (lambert: albedo=[0.5, 0.5, 0.5], fault=" + fault)
    assert words in msg
    if fault in ("exit", "nan"):
        assert f"stderr: fake renderer: fault={fault}" in msg


def test_timeout_kills_the_whole_process_group(oneshot, monkeypatch):
    token = f"brdfremap-hang-test-{os.getpid()}-{time.monotonic_ns()}"  # this run's helper, not another checkout's
    monkeypatch.setitem(oneshot.env, "FAKE_HANG_TOKEN", token)
    t0 = time.monotonic()
    with pytest.raises(RenderError, match="timed out after 5 s \\(process group killed\\)"):
        oneshot.render("lambert", _p(oneshot, fault="hang"), SCENE)
    assert time.monotonic() - t0 < 60  # killed at the 5 s timeout, not after the 120 s hang
    time.sleep(0.5)
    left = subprocess.run(["pgrep", "-f", token], capture_output=True, text=True)
    assert left.stdout.strip() == "", "the renderer's helper process survived"


def test_arguments_cannot_inject(oneshot, tmp_path, monkeypatch):
    log = tmp_path / "argv.json"
    monkeypatch.setitem(oneshot.env, "FAKE_ARGV_LOG", str(log))
    evil = "a b; rm -rf /tmp/x $(id)"
    assert oneshot.render("lambert", _p(oneshot, fault=evil), SCENE).max() > 0  # an unknown fault: renders
    argv = json.loads(log.read_text().splitlines()[-1])
    assert f"fault={evil}" in argv  # one argument, verbatim, no shell


def test_persistent_renderer_is_started_once(persistent):
    a = persistent.render("lambert", _p(persistent, albedo=0.8), SCENE)
    pid = persistent.worker.proc.pid
    b = persistent.render("lambert", _p(persistent, albedo=0.5), SCENE)
    assert persistent.worker.proc.pid == pid
    assert np.allclose(a * 0.5 / 0.8, b, rtol=1e-5, atol=1e-7)


def test_persistent_renderer_that_dies_is_restarted_once_then_reported(persistent):
    with pytest.raises(RenderError) as e:
        persistent.render("lambert", _p(persistent, fault="die"), SCENE)
    msg = str(e.value)
    assert "renderer 'fake-persistent' (lambert:" in msg and "exited (code 11)" in msg
    assert "segfault-like death" in msg
    assert persistent.render("lambert", _p(persistent), SCENE).max() > 0  # usable again


def test_persistent_bad_image_is_reported(persistent):
    with pytest.raises(RenderError, match="NaN or Inf"):
        persistent.render("lambert", _p(persistent, fault="nan"), SCENE)


def test_bad_definitions_name_the_file_and_field(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text('name: x\ncommand: ["r", "{scene}", "{output}"]\nmodels: {}\n')
    with pytest.raises(ConfigError, match="bad.yaml: command: .*unknown placeholder \\{scene\\}"):
        adapter_class(bad)
    bad.write_text('name: x\ncommand: ["r"]\nmodels: {}\n')
    with pytest.raises(ConfigError, match="use \\{output\\}"):
        adapter_class(bad)
    # Found when the definition is loaded, not at the first render (they were tracebacks there).
    for line, words in (('rgb_format: "{r} {q}"', "rgb_format: '\\{r\\} \\{q\\}' cannot be filled"),
                        ('define: ["-D", "{vlaue}"]', "define: unknown placeholder \\{vlaue\\}"),
                        ('command: ["r", "{scene_file}", "{output}"]', "give scene_template")):
        key = line.split(":")[0]
        base = {"name": "name: x", "command": 'command: ["r", "{output}"]', "models": "models: {}"}
        base[key] = line
        bad.write_text("\n".join(base.values()) + "\n")
        with pytest.raises(ConfigError, match=words):
            adapter_class(bad)


class TestFakeRendererContract(AdapterContract):
    factory = adapter_class(DATA / "fake-oneshot.yaml")
    calibration = ("lambert", {"albedo": 0.8})


def _remap_with_fake(tmp_path, root, reflectance, *extra):
    """`remap` in a subprocess: a Mitsuba diffuse source to the fake external renderer."""
    mat = tmp_path / "m.yaml"
    mat.write_text(f"adapter: mitsuba\nmodel: diffuse\nparams: {{reflectance: {reflectance}}}\n")
    out = tmp_path / "out"
    proc = subprocess.run(
        [sys.executable, "-m", "brdfremap.core.cli", "--adapter", str(DATA / "fake-oneshot.yaml"), "--model",
         "lambert", "--source", str(mat), "--out", str(out), "--quiet", "--resolution", "32", *extra],
        capture_output=True, text=True, cwd=root)
    return proc, out


def test_cli_failure_is_exit_2_without_traceback_and_no_result(tmp_path, root):
    proc, out = _remap_with_fake(tmp_path, root, 0.8, "--fix", "fault=exit")
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr
    assert proc.stderr.startswith("remap: error: renderer 'fake-oneshot' (lambert: albedo=")
    assert not (out / "result.json").exists()


def test_cli_remap_through_an_external_renderer_file(tmp_path, root):
    proc, out = _remap_with_fake(tmp_path, root, [0.7, 0.4, 0.2], "--coarse", "0")
    assert proc.returncode == 0, proc.stderr
    r = json.loads((out / "result.json").read_text())
    assert np.allclose(r["params"]["albedo"], [0.7, 0.4, 0.2], atol=0.01)


def test_an_invalid_definition_in_a_renderer_folder_is_listed_with_its_error(tmp_path, monkeypatch, capsys):
    from brdfremap.core.cli import main

    (tmp_path / "typo.yaml").write_text('name: typo\ncomand: ["x"]\nmodels: {}\n')
    monkeypatch.setenv("BRDFREMAP_RENDERERS", str(tmp_path))
    assert main(["adapters"]) == 0
    out = capsys.readouterr().out
    assert "typo" in out and "invalid definition" in out and "comand: unknown field" in out
