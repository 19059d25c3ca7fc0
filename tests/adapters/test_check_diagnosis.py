"""`remap check` names what LuxCoreRender's tile engine did to a new user (issue 43): a renderer that
ignores its seed (every noise floor 0), a render that never ends (a sample count not honoured), an
image one row low (read as a units factor). Through the CLI with a real renderer process
(tests/data/renderers/tile_renderer.py), and row by row with images made in numpy."""

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

from brdfremap.core.data.errors import RenderTimeoutError
from brdfremap.core.data.scene import PointLight
from brdfremap.core.data.schemas import ModelSpec, ParamSpec
from brdfremap.core.host import check
from brdfremap.core.testing import analytic_lambert

DATA = Path(__file__).resolve().parents[1] / "data" / "renderers"


def _tile(tmp_path, *flags: str, timeout: float | None = None) -> Path:
    """fake-tile.yaml with its renderer's fault flags (and a shorter time limit) in a copy."""
    doc = yaml.safe_load((DATA / "fake-tile.yaml").read_text())
    doc["command"][1] = str(DATA / "tile_renderer.py")
    doc["command"] += list(flags)
    if timeout is not None:
        doc["timeout"] = timeout
    path = tmp_path / "fake-tile.yaml"
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    return path


def _remap_check(path: Path) -> tuple[subprocess.CompletedProcess, dict[str, tuple[str, str, str]]]:
    """`remap check` as a user runs it; each row by its key in `check.TITLES`: (mark, line, fix line)."""
    proc = subprocess.run([sys.executable, "-m", "brdfremap.core.cli", "check", str(path)], capture_output=True,
                          text=True, timeout=300)
    assert "Traceback" not in proc.stderr, proc.stderr
    lines = proc.stdout.splitlines() + [""]
    rows = {}
    for key, title in check.TITLES.items():
        i = next(i for i, line in enumerate(lines) if title in line)
        follow = lines[i + 1].strip()
        rows[key] = (lines[i].split(title)[0].strip(), lines[i], follow if follow.startswith("fix:") else "")
    return proc, rows


def test_a_renderer_whose_noise_follows_its_seed_passes_every_check(tmp_path):
    proc, rows = _remap_check(_tile(tmp_path))
    assert proc.returncode == 0 and "all checks pass" in proc.stdout, proc.stdout
    assert rows["seed"][0] == "pass" and "apart at 4 spp" in rows["seed"][1], proc.stdout


def test_remap_check_fails_a_renderer_that_ignores_its_seed_with_the_fix(tmp_path):
    """The issue's done-means: every other check passed, and every noise floor was 0."""
    proc, rows = _remap_check(_tile(tmp_path, "--ignore-seed"))
    mark, line, fix = rows["seed"]
    assert proc.returncode == 1 and mark == "FAIL" and "seeds 0 and 1 give the same image" in line, proc.stdout
    assert fix == f"fix: {check.SEED_FIX}", proc.stdout
    assert rows["determinism"][0] == "pass" and [r for r, (m, _, _) in rows.items() if m != "pass"] == ["seed"]


def test_an_image_one_row_low_is_named_a_shift_not_a_units_factor(tmp_path):
    """LuxCoreRender's image sat one row low: units said "10.92 % off; 1.023x"."""
    proc, rows = _remap_check(_tile(tmp_path, "--shift-rows", "1"))
    assert proc.returncode == 1 and rows["units"][0] == "pass" and "x the analytic" not in rows["units"][1]
    mark, line, fix = rows["orientation"]
    assert mark == "FAIL" and "the image is shifted one row down" in line and "(i + 0.5)/H" in fix, proc.stdout


def test_a_render_that_never_ends_is_diagnosed_as_an_unhonoured_sample_count(tmp_path):
    proc, rows = _remap_check(_tile(tmp_path, "--ignore-spp", timeout=2))
    mark, line, fix = rows["images"]
    assert proc.returncode == 1 and mark == "FAIL" and "did not finish in 2 s" in line, proc.stdout
    assert "does not honour the sample count" in fix and "`{spp}`" in fix and "halt condition" in fix, fix
    assert all(m == "not run" for r, (m, _, _) in rows.items() if r != "images"), proc.stdout


def test_a_subprocess_timeout_is_typed_with_its_seconds(tmp_path):
    from brdfremap.adapters.subprocess.adapter import adapter_class

    adapter = adapter_class(_tile(tmp_path, "--ignore-spp", timeout=1))()
    try:
        with pytest.raises(RenderTimeoutError) as exc:
            adapter.render("lambert", adapter.models["lambert"].complete({}), check.NOISY)
    finally:
        adapter.close()
    assert exc.value.seconds == 1 and "rendering until halted" in str(exc.value)


# --- Row by row, images made in numpy --------------------------------------------------------------------------

MODELS = {"lambert": ModelSpec(name="lambert", parameters=(ParamSpec(name="albedo", kind="rgb", default=(0.5,) * 3),))}
WHITE = ("lambert", {"albedo": (0.8, 0.8, 0.8)})


def _renderer(noise: float = 0.04, seeded: bool = True, moved=lambda a: a, hangs: bool = False):
    """The analytic Lambertian with a sampler's noise (4 %/√spp a pixel, drawn from the seed or not)."""
    def render(model, params, scene, lobe=None):
        if hangs:
            raise RenderTimeoutError("timed out after 2 s", seconds=2.0)
        img = analytic_lambert(scene, np.asarray(params["albedo"], np.float32))
        rng = np.random.default_rng([scene.seed if seeded else 0, scene.spp])
        return moved(img * (1 + noise / math.sqrt(scene.spp) * rng.standard_normal(img.shape))).astype(np.float32)
    return render


@pytest.mark.parametrize("noise, seeded, passed, words", [
    (0.04, True, True, "apart at 4 spp"),
    (0.0, False, True, "no sampling noise"),  # an analytic renderer: noise-free by design
    (0.04, False, False, "give the same image"),
    (0.01, False, False, "give the same image"),  # a little noise, still not the seed's
])
def test_the_seed_row_fails_only_a_renderer_with_noise_the_seed_does_not_change(noise, seeded, passed, words):
    row = check.seed(_renderer(noise, seeded), WHITE)
    assert row.passed is passed and words in row.detail, row
    assert (row.fix == check.SEED_FIX) is (not passed)


@pytest.mark.parametrize("rows, columns, name", [(1, 0, "one row down"), (-1, 0, "one row up"),
                                                 (0, 1, "one column right"), (0, -1, "one column left")])
def test_a_shift_by_one_pixel_is_named_in_orientation_and_units_stay_right(rows, columns, name):
    render = _renderer(moved=lambda a: np.roll(a, (rows, columns), axis=(0, 1)))
    row = check.orientation(render, WHITE)
    assert row.passed is False and f"the image is shifted {name} (" in row.detail and "(i + 0.5)/H" in row.fix, row
    units = check.calibration(render, WHITE)
    assert units.passed and f"shifted {name}" in units.detail, units


def test_half_a_pixel_off_is_named_too():
    """Pixel centres at i instead of i + 0.5: the image half a pixel off (rendered here at twice the
    resolution and box-filtered down with the boxes one fine pixel off)."""
    def render(model, params, scene, lobe=None):
        fine = analytic_lambert(scene.with_(resolution=2 * scene.resolution), 0.8)
        fine = np.roll(fine, 1, axis=0)
        n = scene.resolution
        return fine.reshape(n, 2, n, 2, 3).mean(axis=(1, 3)).astype(np.float32)
    row = check.orientation(render, WHITE)
    assert row.passed is False and "the image is shifted half a row down" in row.detail, row


def test_a_correct_image_is_not_taken_for_a_shifted_one():
    for scene_check in (check.orientation, check.calibration):
        row = scene_check(_renderer(), WHITE)
        assert row.passed and "shifted" not in row.detail, row


def test_a_check_whose_render_never_ends_says_why_and_the_rest_do_not_wait():
    rows = check.run(_renderer(hangs=True), MODELS, WHITE)
    assert [r.name for r in rows] == list(check.TITLES.values())
    assert rows[0].passed is False and rows[0].fix == check.HANG_FIX and "2 s" in rows[0].detail
    assert all(r.passed is None and "a render did not finish (see images)" in r.detail for r in rows[1:])
