"""`remap check` against four adapters that corrupt every fit and passed it before (issue 55): each is the
white Lambertian a correct renderer draws (the box-filtered analytic image), corrupted as a newcomer's
adapter was, and the row that must fail says the cause and the fix; the rows whose cause it is are not
read again as another (a display curve as a units factor and a shift)."""

import numpy as np
import pytest

from brdfremap.core.data.schemas import ModelSpec, ParamSpec
from brdfremap.core.host import check, judge
from brdfremap.core.testing import analytic_lambert, box_filtered_lambert

MODELS = {"lambert": ModelSpec(name="lambert", parameters=(ParamSpec(name="albedo", kind="rgb", default=(0.5,) * 3),))}
WHITE = ("lambert", {"albedo": (0.8, 0.8, 0.8)})


def _srgb(x):
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(np.maximum(x, 0.0031308), 1 / 2.4) - 0.055)


def _eight_bit(x, exposure=1.0):
    """An 8-bit exposure read back and undone: clipped at 1/exposure, 256 levels of it."""
    return np.round(np.clip(x * exposure, 0, 1) * 255) / 255 / exposure


CORRUPT = {
    "correct": lambda scene, a: box_filtered_lambert(scene, a),
    "clipped at 4": lambda scene, a: np.minimum(box_filtered_lambert(scene, a), 4.0),
    "8-bit at 1/64": lambda scene, a: _eight_bit(box_filtered_lambert(scene, a), 1 / 64),
    "8-bit sRGB, not linearised": lambda scene, a: _eight_bit(_srgb(box_filtered_lambert(scene, a))),
    "one ray at each pixel's centre": lambda scene, a: analytic_lambert(scene, a),
}


def _rows(kind: str) -> dict[str, judge.Row]:
    def render(model, params, scene, lobe=None):
        return np.asarray(CORRUPT[kind](scene, np.asarray(params["albedo"], np.float64)), np.float32)
    return {key: row for key, row in zip(check.TITLES, check.run(render, MODELS, WHITE))}


def _failed(rows: dict[str, judge.Row]) -> list[str]:
    return [k for k, r in rows.items() if r.passed is False]


def test_the_correct_renderer_passes_every_row():
    rows = _rows("correct")
    assert _failed(rows) == [] and all(r.passed for r in rows.values()), rows


def test_highlights_clipped_at_4_fail_precision_and_nothing_else():
    """It passed: `brightest 4 (expected 149)`; its gold was then "67.6 %, a model mismatch"."""
    rows = _rows("clipped at 4")
    assert _failed(rows) == ["precision"], rows
    assert "the brightest pixel is 4 where it should be 149" in rows["precision"].detail, rows["precision"]
    assert "(clipped)" in rows["precision"].detail and "float" in rows["precision"].fix


def test_an_8_bit_exposure_at_1_64_is_named_quantised_not_a_units_factor():
    """It passed precision ("brightest 64") and failed units at "1.001x", pointing to precision."""
    rows = _rows("8-bit at 1/64")
    assert "quantisation" in _failed(rows) and "units" not in _failed(rows), rows
    detail = rows["quantisation"].detail
    assert "its lit pixels take 3 values where the analytic gradient has" in detail, detail
    assert "8-bit (3 levels 0.251 apart, scaled after)" in detail, detail
    units = rows["units"]
    assert units.passed is None and "quantisation" in units.detail and "did not pass" in units.detail, units
    assert rows["orientation"].passed is None


def test_srgb_output_is_named_encoded_and_8_bit_not_a_shift_or_a_units_factor():
    """It read "units 1.875x", "shifted one column right", "clipped"; no row said sRGB."""
    rows = _rows("8-bit sRGB, not linearised")
    assert set(_failed(rows)) == {"quantisation", "encoding"}, rows
    power = float(rows["encoding"].detail.split("to the power ")[1].split(",")[0])
    assert 0.4 < power < 0.6 and "gamma- or sRGB-encoded" in rows["encoding"].detail, rows["encoding"]
    assert "(levels k/255, as an 8-bit image reads)" in rows["quantisation"].detail, rows["quantisation"]
    assert all(rows[k].passed is None for k in ("units", "orientation", "precision", "sampling")), rows


def test_one_ray_at_each_pixel_centre_fails_sampling_as_the_adapters_aliasing():
    """Every row passed; under the rim light it is far from a box-filtered image, which the remaps booked as
    the renderers' disagreement."""
    rows = _rows("one ray at each pixel's centre")
    assert _failed(rows) == ["sampling"], rows
    detail = rows["sampling"].detail
    assert detail.startswith("rim light: "), detail
    assert "from the analytic image sampled at each pixel's centre: one sample a pixel" in detail, detail
    far = float(detail.split("(")[1].split("%")[0]) / 100
    assert far > 3 * judge.SAMPLING_TOLERANCE, detail  # far from the threshold, not a hair over it
    assert "integrate each pixel over its area" in rows["sampling"].fix


@pytest.mark.parametrize("kind", ["correct", "clipped at 4"])
def test_the_remap_check_table_has_every_row_in_order(kind):
    assert list(_rows(kind)) == list(check.TITLES)


# --- The specular path: a perfect mirror under the studio environment ------------------------------------------

from brdfremap.core.testing import analytic_mirror  # noqa: E402

MIRRORED = {
    "correct": lambda img: img,
    "the environment mirrored in the reflection": lambda img: img[:, ::-1],
    "a factor of 1/π on specular light": lambda img: img / np.pi,
}


@pytest.mark.parametrize("kind, passed, words", [
    ("correct", True, "from the analytic mirror"),
    ("the environment mirrored in the reflection", False, "the reflection is mirrored left-right"),
    ("a factor of 1/π on specular light", False, "(a factor of 1/π)"),
])
def test_a_fault_of_the_specular_path_fails_the_glossy_row_with_its_cause(kind, passed, words):
    """The white Lambertian shows none of these: a mirror's reflection does (a fit would read them as the
    model's highlight)."""
    def render(model, params, scene, lobe=None):
        return np.asarray(MIRRORED[kind](analytic_mirror(scene, 8)), np.float32)
    row = check.glossy(render, ("mirror", {}), environment=True)
    assert row.passed is passed and words in row.detail, row
    assert (row.fix == check.MIRROR_FIX) is (not passed)


def test_the_glossy_row_asks_for_a_mirror_only_of_an_adapter_with_an_environment():
    assert check.glossy(None, None, environment=False).passed is True
    row = check.glossy(None, None, environment=True)
    assert row.passed is None and "Adapter.mirror" in row.fix, row


def test_a_light_without_falloff_is_named_in_units_and_orientation_does_not_read_it_as_a_shift():
    """pygfx's default point light (decay 0): units said "13.4x", orientation "shifted one column right"."""
    from brdfremap.core.testing import sphere_hits

    def render(model, params, scene, lobe=None):
        hits = sphere_hits(scene)
        d2 = ((np.asarray(scene.point_lights[0].position) - hits.position) ** 2).sum(-1)
        return np.asarray(box_filtered_lambert(scene, np.asarray(params["albedo"])) * d2[..., None], np.float32)
    rows = {key: row for key, row in zip(check.TITLES, check.run(render, MODELS, WHITE))}
    assert _failed(rows) == ["units"], rows
    assert "the shape of the analytic image without the light's inverse-square falloff" in rows["units"].detail
    assert rows["orientation"].passed is None, rows["orientation"]


def test_state_left_by_the_render_before_fails_determinism():
    """A newcomer's buffers were not cleared: each render drew over the one before, and units, orientation and
    determinism passed."""
    last = {}

    def render(model, params, scene, lobe=None):
        img = box_filtered_lambert(scene, np.asarray(params["albedo"], np.float64))
        key = scene.resolution
        out = np.maximum(img, last.get(key, 0 * img))
        last[key] = out
        return np.asarray(out, np.float32)
    models = {**MODELS, "grey": ModelSpec(name="grey", parameters=(ParamSpec(name="albedo", kind="rgb",
                                                                             default=(0.9,) * 3),))}
    row = check.determinism(render, models, WHITE)
    assert row.passed is False and "left something behind" in row.detail and "clear the frame" in row.fix, row


def test_an_albedo_read_as_an_srgb_colour_is_named_by_its_factor():
    """pygfx reads material colours as sRGB: units said "0.7544x", with the generic fix."""
    def render(model, params, scene, lobe=None):
        linear = ((np.asarray(params["albedo"], np.float64) + 0.055) / 1.055) ** 2.4
        return np.asarray(box_filtered_lambert(scene, linear), np.float32)
    row = check.calibration(render, WHITE)
    assert row.passed is False and "the albedo 0.8 read as an sRGB colour" in row.detail, row


# --- The second newcomer's misses ------------------------------------------------------------------------------

def test_buffers_never_cleared_give_every_material_one_image_and_fail_determinism():
    """pygfx with clear=False: every render repeated the first one drawn, and determinism passed."""
    first = {}

    def render(model, params, scene, lobe=None):
        img = box_filtered_lambert(scene, np.asarray(params["albedo"], np.float64))
        return np.asarray(first.setdefault(scene.resolution, img), np.float32)
    models = {"grey": ModelSpec(name="grey", parameters=(ParamSpec(name="albedo", kind="rgb", default=(0.3,) * 3),)),
              "lambert": MODELS["lambert"]}
    row = check.determinism(render, models, WHITE)
    assert row.passed is False and "give one image, bit for bit" in row.detail and "clear the frame" in row.fix, row


def test_a_units_error_of_a_few_percent_with_no_factor_lets_sampling_say_more():
    """One sample a pixel in pygfx: units 1.29 % off, 0.98x, and sampling was not judged."""
    def render(model, params, scene, lobe=None):
        return np.asarray(analytic_lambert(scene, np.asarray(params["albedo"]) * 0.98), np.float32)
    rows = {key: row for key, row in zip(check.TITLES, check.run(render, MODELS, WHITE))}
    assert rows["units"].passed is False and "see sampling" in rows["units"].detail, rows["units"]
    assert rows["sampling"].passed is False and "one sample a pixel" in rows["sampling"].detail, rows["sampling"]


def test_a_specular_term_left_on_at_grazing_angles_is_not_called_one_sample_a_pixel():
    """A Phong material with its specular at 0 still reflected at grazing angles: sampling said "one sample a
    pixel" of a renderer taking 64."""
    from brdfremap.core.testing import sphere_hits

    def render(model, params, scene, lobe=None):
        img = box_filtered_lambert(scene, np.asarray(params["albedo"], np.float64))
        hits = sphere_hits(scene)
        grazing = np.clip(1 - (hits.normal * hits.view).sum(-1), 0, 1) ** 5  # a Fresnel-like rim
        return np.asarray(img + 0.3 * grazing[..., None] * (img.max(axis=-1, keepdims=True) > 0), np.float32)
    row = check.sampling(render, WHITE)
    assert row.passed is False and "one sample a pixel" not in row.detail, row
    assert "not the pixel filter alone" in row.detail and "no specular or Fresnel term" in row.fix, row


def test_a_light_without_falloff_clipped_at_1_is_not_called_a_display_curve():
    """Decay 0 with the pixels clipped at 1: encoding said "to the power 0.32: gamma- or sRGB-encoded"."""
    from brdfremap.core.testing import sphere_hits

    def render(model, params, scene, lobe=None):
        hits = sphere_hits(scene)
        d2 = ((np.asarray(scene.point_lights[0].position) - hits.position) ** 2).sum(-1)
        return np.asarray(np.minimum(box_filtered_lambert(scene, np.asarray(params["albedo"])) * d2[..., None], 1.0),
                          np.float32)
    rows = {key: row for key, row in zip(check.TITLES, check.run(render, MODELS, WHITE))}
    assert rows["encoding"].passed is not False, rows["encoding"]
    assert rows["units"].passed is False and "inverse-square falloff" in rows["units"].detail, rows["units"]


def test_the_environment_row_names_a_mirrored_map():
    from brdfremap.core.data.scene import EnvironmentLight  # noqa: F401 (the studio is the row's own scene)

    def render(model, params, scene, lobe=None):
        return np.asarray(box_filtered_lambert(scene, 0.8)[:, ::-1], np.float32)
    row = check.lit_by_environment(render, WHITE, True)
    assert row.passed is False and "the map is mirrored left-right" in row.detail, row
    good = check.lit_by_environment(lambda m, p, s, lobe=None: box_filtered_lambert(s, 0.8), WHITE, True)
    assert good.passed, good


def test_one_sample_a_pixel_off_its_centre_is_named_with_where_it_falls():
    """A rasteriser without its anti-aliasing may take each pixel's one sample off its centre."""
    from brdfremap.core.host.analytic import _directions, _surface, lambert_radiance

    def render(model, params, scene, lobe=None):
        idx = np.arange(scene.resolution, dtype=np.float64)
        xx, yy = np.meshgrid(idx + 0.75, idx + 0.75)
        return np.asarray(lambert_radiance(scene, _surface(scene, *_directions(scene, xx, yy)), 0.8), np.float32)
    row = check.sampling(render, WHITE)
    assert row.passed is False and "sampled at (0.75, 0.75) of each pixel: one sample a pixel, off its centre" \
        in row.detail, row


def test_a_black_mirror_is_said_black_not_a_traceback():
    """The third newcomer's Phong mirror under the studio drew nothing: `math domain error` in the factor."""
    row = check.glossy(lambda m, p, s, lobe=None: np.zeros((s.resolution, s.resolution, 3), np.float32),
                       ("mirror", {}), environment=True)
    assert row.passed is False and "the image is black" in row.detail, row
    assert judge.usual_factor(0.0) == ""


def test_the_studio_rows_wait_for_sampling():
    """One sample a pixel: the environment and glossy rows blamed the map and the specular lookups."""
    def render(model, params, scene, lobe=None):
        return np.asarray(analytic_lambert(scene, np.asarray(params["albedo"])), np.float32)
    rows = {key: row for key, row in zip(check.TITLES, check.run(render, MODELS, WHITE, environment=True,
                                                                   mirror=("lambert", {"albedo": (0.8,) * 3})))}
    assert rows["sampling"].passed is False
    assert rows["environment"].passed is None and rows["glossy"].passed is None, rows


def test_an_underexposed_8_bit_read_back_is_quantised_not_passed():
    """open3d's fixed exposure: the probe in 2 values over 581 lit pixels passed quantisation (and a channel at 0
    made its step 0)."""
    def render(model, params, scene, lobe=None):
        return np.asarray(_eight_bit(box_filtered_lambert(scene, np.asarray(params["albedo"])), 1 / 200), np.float32)
    row = check.quantisation(render, WHITE)
    assert row.passed is False and "8-bit" in row.detail, row
    dark = check.images(lambda m, p, s, lobe=None: np.zeros((s.resolution,) * 2 + (3,), np.float32), MODELS, False)
    assert dark.passed is False and "every pixel is 0" in dark.detail and "8-bit read-back" in dark.fix, dark
