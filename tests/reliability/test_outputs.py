"""Nothing lost, nothing wrong: the output folder's rules, with real processes and real filesystems.

Each test is one case of docs/reliability.md. Run them alone with `pytest tests/reliability`."""

import os
import stat
import subprocess
import sys
import time

import pytest
from brdfremap.core.run.store import Store
from helpers import MATERIALS, SmallFilesystem, fill, one_line_error, remap

GOLD = MATERIALS / "gold.yaml"
SMALL = ["--adapter", "mitsuba", "--model", "roughconductor", "--fix", "distribution=ggx", "--resolution", "32"]


def test_two_remaps_into_one_folder_at_once_the_second_is_refused(tmp_path, mitsuba_adapter):
    """Case 1. While one run owns the folder, a second gets one line and exit 2; the first's
    result is whole (every file matches the hash its result.json records)."""
    out = tmp_path / "o"
    cmd = [sys.executable, "-m", "brdfremap.core.cli", "--source", str(GOLD), "--out", str(out),
           *SMALL[:-1], "256", "--spp", "512", "--start", "defaults"]
    first = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.time() + 60
    while not (out / ".lock").exists() or not (out / ".lock").read_text().strip():
        assert first.poll() is None and time.time() < deadline, first.communicate()
        time.sleep(0.02)
    second = remap("--source", GOLD, "--out", out, *SMALL)
    one_line_error(second, "another brdf-remap run is writing this folder")
    assert first.wait(timeout=120) == 0, first.communicate()
    stored = Store(out).inspect("")
    assert stored.report is not None and stored.report.job.scene.resolution == 256, stored.problem


@pytest.mark.parametrize("kind", ["below a file", "dangling link", "looping link", "empty"])
def test_a_bad_out_is_one_line_before_any_render(tmp_path, kind, mitsuba_adapter):
    """Cases 3 and 4, for remap, sweep and render."""
    (tmp_path / "file").write_text("x")
    os.symlink(tmp_path / "nowhere", tmp_path / "dangling")
    os.symlink(tmp_path / "loop-b", tmp_path / "loop-a")
    os.symlink(tmp_path / "loop-a", tmp_path / "loop-b")
    out = {"below a file": tmp_path / "file" / "o", "dangling link": tmp_path / "dangling",
           "looping link": tmp_path / "loop-a", "empty": ""}[kind]
    (tmp_path / "result.json").write_text("{}")  # `--out ""` must not touch the current folder's
    exp = tmp_path / "exp.yaml"
    exp.write_text("kind: sweep\nname: t\nsource: {adapter: mitsuba, model: roughconductor, params: {alpha: 0.1}}\n"
                   "sweep: {param: material, values: [Au, Cu]}\ntarget: {adapter: mitsuba, model: roughconductor}\n"
                   "scene: {resolution: 32}\nplot: {x: source.alpha, y: target.alpha}\n")
    for proc in (remap("--source", GOLD, "--out", out, *SMALL, cwd=tmp_path),
                 remap("sweep", exp, "--out", out, cwd=tmp_path)):
        one_line_error(proc, "--out")
        assert "  [" not in proc.stderr  # no progress line: nothing was rendered
    if kind != "empty":
        image = str(out) + ".exr" if kind == "below a file" else out
        one_line_error(remap("render", GOLD, "--out", image, cwd=tmp_path), "--out")
    assert (tmp_path / "result.json").read_text() == "{}"


def test_a_read_only_filesystem_is_one_line_before_any_render(tmp_path, mitsuba_adapter):
    """Case 3: a read-only filesystem (a tmpfs mounted ro) for remap, sweep and render."""
    with SmallFilesystem(tmp_path / "ro", "1m", "ro") as ro:
        if ro is None:
            pytest.skip("cannot mount a tmpfs here (needs root)")
        for proc in (remap("--source", GOLD, "--out", ro / "o", *SMALL),
                     remap("render", GOLD, "--out", ro / "x.exr", "--resolution", "32")):
            one_line_error(proc, "Read-only file system")


def test_a_full_disk_keeps_the_previous_result_and_says_which_file(tmp_path, mitsuba_adapter):
    """Case 5. The result is written aside first: with the disk full, the remap fails with one
    line naming the file and the reason, and the previous result is still there, whole."""
    with SmallFilesystem(tmp_path / "fs", "2m") as fs:
        if fs is None:
            pytest.skip("cannot mount a tmpfs here (needs root)")
        out = fs / "o"
        assert remap("--source", GOLD, "--out", out, *SMALL, "--quiet").returncode == 0
        before = Store(out).inspect("").report
        fill(fs, leave=20_000)
        proc = remap("--source", GOLD, "--out", out, *SMALL, "--force", "--quiet")
        line = one_line_error(proc, "no space left on the device")
        assert str(out) in line and "the previous result, if any, is kept" in line
        after = Store(out).inspect("")
        assert after.report is not None and after.report.document() == before.document(), after.problem
        assert not [p for p in os.listdir(out) if p.startswith(".staging")]


def test_stale_files_of_an_earlier_result_and_a_killed_write_go(tmp_path, mitsuba_adapter):
    """Case 10: a staging folder left by a kill, and files the previous result listed but this
    one has not, are removed; the user's own files stay."""
    out = tmp_path / "o"
    assert remap("--source", GOLD, "--out", out, *SMALL, "--quiet").returncode == 0
    (out / ".staging-killed").mkdir()
    (out / ".staging-killed" / "source.exr").write_bytes(b"half")
    (out / "mine.txt").write_text("the user's")
    assert remap("--source", GOLD, "--out", out, *SMALL[:-1], "48", "--quiet").returncode == 0
    assert not (out / ".staging-killed").exists() and (out / "mine.txt").read_text() == "the user's"


def test_a_killed_writes_staging_folder_goes_when_the_result_there_is_reused(tmp_path, mitsuba_adapter):
    """A kill after a material's result was moved into place and before its staging folder went (a
    sweep's kill -9 left one): the rerun reuses the result and removes the staging folder."""
    out = tmp_path / "o"
    convert = ("convert", GOLD, "--to", "mitsuba:roughconductor", "--out", out, "--resolution", "32", "--validate",
               "none", "--quiet")
    assert remap(*convert).returncode == 0
    (slot,) = (out / "materials").iterdir()
    (slot / ".staging-killed").mkdir()
    (slot / ".staging-killed" / "result.json").write_bytes(b"{}")
    kept = (slot / "result.json").stat().st_mtime_ns
    assert remap(*convert).returncode == 0
    assert (slot / "result.json").stat().st_mtime_ns == kept  # reused, not written again
    assert not (slot / ".staging-killed").exists()


def test_results_are_readable_by_others_under_the_usual_umask(tmp_path, mitsuba_adapter):
    """Case 11: files get what the umask gives (0644 under 022), not mkstemp's 0600."""
    out = tmp_path / "o"
    proc = subprocess.run(["sh", "-c", f"umask 022 && {sys.executable} -m brdfremap.core.cli --source {GOLD} "
                          f"--out {out} {' '.join(SMALL)} --quiet && {sys.executable} -m brdfremap.core.cli "
                          f"render {GOLD} --out {tmp_path / 'r.exr'} --resolution 32 --quiet"],
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    for f in [*out.iterdir(), tmp_path / "r.exr"]:
        if f.name.startswith("."):
            continue
        assert stat.S_IMODE(f.stat().st_mode) == 0o644, (f.name, oct(f.stat().st_mode))


def test_render_writes_through_a_link_and_keeps_it(tmp_path, mitsuba_adapter):
    real = tmp_path / "real.exr"
    real.write_bytes(b"old")
    os.symlink(real, tmp_path / "link.exr")
    assert remap("render", GOLD, "--out", tmp_path / "link.exr", "--resolution", "32").returncode == 0
    assert (tmp_path / "link.exr").is_symlink() and real.stat().st_size > 100
    one_line_error(remap("render", GOLD, "--out", tmp_path / "nope" / ".." / "file.txt"), ".exr")


def test_a_remap_into_a_running_sweeps_point_is_refused(tmp_path, mitsuba_adapter):
    from brdfremap.core.run.store import owned

    with owned(tmp_path / "sweep"):
        proc = remap("--source", GOLD, "--out", tmp_path / "sweep" / "points" / "00-003", *SMALL)
    one_line_error(proc, "which another brdf-remap run is writing")


def test_a_folder_holding_another_programs_result_json_is_not_written_and_nothing_is_deleted(tmp_path,
                                                                                              mitsuba_adapter):
    """A result.json brdf-remap did not write names files of the user's: they are not removed."""
    out = tmp_path / "proj"
    out.mkdir()
    (out / "thesis.tex").write_text("chapter 1")
    (out / "result.json").write_text('{"tool": "other", "files": ["thesis.tex", {"name": "thesis.tex"}]}')
    one_line_error(remap("--source", GOLD, "--out", out, *SMALL, "--quiet"), "that brdf-remap did not write")
    assert (out / "thesis.tex").read_text() == "chapter 1" and '"other"' in (out / "result.json").read_text()


@pytest.mark.parametrize("files", [["thesis.tex"], [{"name": "thesis.tex", "sha256": "0" * 64, "bytes": 9}]])
def test_a_result_json_claiming_to_be_ours_cannot_get_a_users_file_deleted(tmp_path, mitsuba_adapter, files):
    """Third trial N1: `{"tool": "brdf-remap 0.1.0", "files": ["thesis.tex"]}` made the next remap
    delete thesis.tex. A listed file goes only while it is byte for byte what brdf-remap wrote."""
    import json

    out = tmp_path / "proj"
    out.mkdir()
    (out / "thesis.tex").write_text("chapter 1")
    (out / "result.json").write_text(json.dumps({"tool": "brdf-remap 0.1.0", "files": files}))
    remap("--source", GOLD, "--out", out, *SMALL, "--quiet", "--validate", "none")
    assert (out / "thesis.tex").read_text() == "chapter 1"


def test_a_folder_where_an_image_goes_is_named_before_any_render(tmp_path):
    """Third trial N2: a folder named target.exr failed after the fit, naming neither."""
    (tmp_path / "o" / "target.exr").mkdir(parents=True)
    proc = remap("--source", GOLD, "--out", tmp_path / "o", *SMALL)
    one_line_error(proc, "target.exr", "move it")
    assert "renders" not in proc.stdout


def test_an_edited_report_is_not_taken_for_the_result(tmp_path, mitsuba_adapter):
    import json

    out = tmp_path / "o"
    assert remap("--source", GOLD, "--out", out, *SMALL, "--quiet").returncode == 0
    doc = json.loads((out / "result.json").read_text())
    doc["metrics"]["relative_rmse"] = 0.001
    (out / "result.json").write_text(json.dumps(doc))
    stored = Store(out).inspect("")
    assert stored.report is None and "edited after it was written" in stored.problem
    rerun = remap("--source", GOLD, "--out", out, *SMALL)
    assert rerun.returncode == 0 and "was replaced: " in rerun.stderr and "edited" in rerun.stderr


def test_an_interrupted_swap_leaves_the_previous_result_or_the_new_one(tmp_path, mitsuba_adapter):
    """Case 5's other half: killed while the new result is moved in (its files half there, no
    result.json yet), the folder gets its previous result back at the next look."""
    out = tmp_path / "o"
    assert remap("--source", GOLD, "--out", out, *SMALL, "--quiet").returncode == 0
    before = (out / "result.json").read_bytes()
    backup = out / ".previous-killed"
    backup.mkdir()
    for name in ("result.json", "target.exr", "source.png"):
        os.replace(out / name, backup / name)  # as the swap does, just before the kill
    (out / "target.exr").write_bytes(b"half of the new result")
    stored = Store(out).inspect("")
    assert stored.report is not None and (out / "result.json").read_bytes() == before and not backup.exists()


def test_render_into_a_running_sweeps_folder_and_a_disk_that_fills_are_refused(tmp_path, mitsuba_adapter):
    from brdfremap.core.run.store import owned

    with owned(tmp_path / "sweep"):
        one_line_error(remap("render", GOLD, "--out", tmp_path / "sweep" / "points" / "p" / "t.exr"),
                       "which another brdf-remap run is writing")
    with SmallFilesystem(tmp_path / "fs", "1m") as fs:
        if fs is None:
            pytest.skip("cannot mount a tmpfs here (needs root)")
        image = fs / "r.exr"
        assert remap("render", GOLD, "--out", image, "--resolution", "32", "--quiet").returncode == 0
        size = image.stat().st_size
        fill(fs, leave=0)
        one_line_error(remap("render", GOLD, "--out", image, "--resolution", "64", "--quiet"),
                       "no space left on the device", "the previous file, if any, is kept")
        assert image.stat().st_size == size and not [p for p in os.listdir(fs) if p.startswith(".r.")]


@pytest.mark.parametrize("obstacle", ["lock is a folder", "result.json is a folder", "name too long"])
def test_an_obstructed_out_is_one_line_before_any_render(tmp_path, obstacle, mitsuba_adapter):
    out = tmp_path / ("x" * 300 if obstacle == "name too long" else "o")
    if obstacle != "name too long":
        (out / (".lock" if obstacle.startswith("lock") else "result.json")).mkdir(parents=True)
    proc = remap("--source", GOLD, "--out", out, *SMALL)
    one_line_error(proc, "--out")
    assert "  [" not in proc.stderr
    if obstacle == "name too long":
        one_line_error(remap("render", GOLD, "--out", str(out) + ".exr"), "too long")


def test_a_sweep_keeps_the_users_files_and_refuses_an_obstructed_folder(tmp_path, mitsuba_adapter):
    exp = tmp_path / "exp.yaml"
    exp.write_text("kind: sweep\nname: t\nsource: {adapter: mitsuba, model: roughconductor}\n"
                   "sweep: {param: alpha, values: [0.1, 0.2]}\ntarget: {adapter: mitsuba, model: roughconductor}\n"
                   "scene: {resolution: 32}\nplot: {x: source.alpha, y: target.alpha}\n")
    out = tmp_path / "o"
    out.mkdir()
    (out / "cliff-edge-holiday.png").write_bytes(b"a photo")
    assert remap("sweep", exp, "--out", out, "--quiet").returncode == 0
    assert (out / "cliff-edge-holiday.png").read_bytes() == b"a photo"
    (tmp_path / "o2" / "results.csv").mkdir(parents=True)
    proc = remap("sweep", exp, "--out", tmp_path / "o2")
    one_line_error(proc, "holds a folder named results.csv")
    assert not (tmp_path / "o2" / "points").exists()
