"""The CLI contract: instant help, one-line errors with exit code 2, --debug tracebacks."""

import subprocess
import sys
import textwrap

import pytest

from brdfremap.core.cli import main


def test_help_imports_no_renderer():
    code = textwrap.dedent("""
        import sys
        from brdfremap.core.cli import main
        try:
            main(["--help"])
        except SystemExit:
            pass
        heavy = [m for m in ("mitsuba", "drjit", "bpy", "OpenImageIO", "scipy") if m in sys.modules]
        print("HEAVY", heavy)
    """)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert "--adapter" in out and "remap adapters" in out
    assert "HEAVY []" in out


def test_adapters_lists_models_and_variant(capsys):
    assert main(["adapters"]) == 0
    out = capsys.readouterr().out
    assert "mitsuba" in out and "model roughconductor" in out and "model roughplastic" in out
    assert "variant:" in out and "reason:" in out


def _material(tmp_path, text, name="m.yaml"):
    p = tmp_path / name
    p.write_text(textwrap.dedent(text))
    return p


GOOD = """
adapter: mitsuba
model: roughconductor
params: {distribution: beckmann, material: Au, alpha: 0.1}
"""


@pytest.mark.parametrize(
    "material, extra, expect",
    [
        (GOOD, ["--adapter", "cyclez"], "--adapter: unknown adapter 'cyclez'"),
        (GOOD, ["--model", "phongg"], "--model: adapter 'mitsuba' has no model 'phongg'"),
        (GOOD, ["--fix", "alpah=0.1"], "--fix alpah: unknown parameter 'alpah'"),
        (GOOD, ["--fix", "alpha=7"], "--fix alpha: 7 is outside the bounds"),
        (GOOD, ["--fix", "distribution=phong"], "--fix distribution: 'phong' is not one of"),
        (GOOD, ["--resolution", "2"], "--resolution: Input should be greater than or equal to 8"),
        (GOOD, ["--precise-spp", "0"], "--precise-spp: Input should be greater than or equal to 1"),
        ("adapter: mitsuba\nmodel: roughconductor\nparams: {alpha: 3.0}\n", [], "m.yaml: params.alpha: 3 is outside"),
        ("adapter: mitsuba\nmodel: roughconductor\nparams: {roughness: 0.3}\n", [], "m.yaml: params.roughness: unknown parameter"),
        ("adapter: mitsuba\nmodel: glass\n", [], "m.yaml: model: adapter 'mitsuba' has no model 'glass'"),
        ("adapter: arnold\nmodel: x\n", [], "m.yaml: adapter: unknown adapter 'arnold'"),
        ("adapter: mitsuba\nmodel: roughconductor\nparams: {alpha: 0.1\n", [], "m.yaml: line 4, column 1: malformed YAML"),
        ("adapter: mitsuba\nmodle: roughconductor\n", [], "m.yaml: modle: unknown field"),
        ("- just\n- a list\n", [], "m.yaml: expected a mapping"),
    ],
)
def test_bad_input_is_one_line_naming_file_and_field(tmp_path, capsys, material, extra, expect):
    src = _material(tmp_path, material)
    argv = ["--adapter", "mitsuba", "--model", "roughconductor", "--source", str(src), "--out", str(tmp_path / "o")]
    for i in range(0, len(extra), 2):
        if extra[i] in argv:
            argv[argv.index(extra[i]) + 1] = extra[i + 1]
        else:
            argv += extra[i:i + 2]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert expect in err[0], err[0]
    assert not (tmp_path / "o").exists()  # nothing half-written


def test_missing_source_file_and_scene(tmp_path, capsys):
    argv = ["--adapter", "mitsuba", "--model", "roughconductor", "--source", str(tmp_path / "nope.yaml"),
            "--out", str(tmp_path / "o")]
    assert main(argv) == 2
    assert "nope.yaml: file not found" in capsys.readouterr().err
    src = _material(tmp_path, GOOD)
    argv[argv.index("--source") + 1] = str(src)
    assert main(argv + ["--scene", str(tmp_path / "scene.yaml")]) == 2
    assert "scene.yaml: file not found" in capsys.readouterr().err


def test_debug_shows_the_traceback(tmp_path):
    src = _material(tmp_path, GOOD)
    proc = subprocess.run(
        [sys.executable, "-m", "brdfremap.core.cli", "--adapter", "nope", "--model", "x", "--source", str(src),
         "--out", str(tmp_path / "o"), "--debug"], capture_output=True, text=True)
    assert proc.returncode != 0
    assert "Traceback" in proc.stderr and "ConfigError" in proc.stderr


def test_argparse_usage_errors_exit_2(capsys):
    with pytest.raises(SystemExit) as e:
        main(["--model", "x"])
    assert e.value.code == 2


def test_a_swallowed_ctrl_c_is_still_honoured_at_the_next_check():
    import signal

    import pytest

    from brdfremap.core.run import interrupt

    previous = signal.getsignal(signal.SIGINT)
    try:
        interrupt.install()
        interrupt.check()  # nothing pressed: no-op
        try:
            signal.raise_signal(signal.SIGINT)
        except KeyboardInterrupt:
            pass  # as native code might swallow it
        with pytest.raises(KeyboardInterrupt):
            interrupt.check()
    finally:
        interrupt._requested.clear()
        signal.signal(signal.SIGINT, previous)
