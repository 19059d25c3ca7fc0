"""Texture files as the texel-by-texel path reads and writes them: colour spaces, alpha, packed
channels, broken files, and the round trip of a written map."""

import numpy as np
import pytest

from brdfremap.core.data.errors import ConfigError
from brdfremap.core.data.textures import encode, read_values, texture


def _write(path, px, fmt="uint8", straight_alpha=False):
    import OpenImageIO as oiio

    buf = oiio.ImageBuf(np.ascontiguousarray(px, np.float32))
    if straight_alpha:
        buf.specmod().attribute("oiio:UnassociatedAlpha", 1)
    buf.set_write_format(fmt)
    assert buf.write(str(path)), oiio.geterror()
    return path


def test_colour_maps_are_decoded_and_alpha_left_out(tmp_path):
    f = _write(tmp_path / "c.png", np.tile([[[1.0, 0.8, 0.4, 0.5]]], (4, 4, 1)), straight_alpha=True)
    got = read_values(texture(f, "linear"), "rgb")
    assert got.shape == (4, 4, 3) and np.allclose(got[0, 0], [1.0, 0.8, 0.4], atol=2e-3)  # not times the alpha
    srgb = read_values(texture(f, "srgb"), "rgb")[0, 0]
    assert srgb[1] == pytest.approx(((0.8 + 0.055) / 1.055) ** 2.4, abs=3e-3)
    grey = read_values(texture(f, "linear"), "scalar")[0, 0]
    assert grey == pytest.approx(0.2126 + 0.7152 * 0.8 + 0.0722 * 0.4, abs=3e-3)  # luminance
    assert read_values(texture(f, "linear", channel=2), "scalar")[0, 0] == pytest.approx(0.4, abs=3e-3)
    grey = _write(tmp_path / "g.png", np.full((4, 4, 1), 0.6))  # a grey image: its grey in every colour channel
    assert read_values(texture(grey, "linear", channel=2), "scalar")[0, 0] == pytest.approx(0.6, abs=3e-3)
    with pytest.raises(ConfigError, match="has 1 channels, and channel 3"):
        read_values(texture(grey, "linear", channel=3), "scalar")  # its alpha, which it has not: said


def test_a_written_map_reads_back_as_it_was(tmp_path):
    values = np.linspace(0, 1, 48, dtype=np.float32).reshape(4, 4, 3)
    for space in ("srgb", "linear"):
        f = tmp_path / f"{space}.png"
        f.write_bytes(encode(values, ".png", space))
        assert np.abs(read_values(texture(f, space), "rgb") - values).max() < 2e-4
    wide = np.full((2, 2), 3.7, np.float32)
    (tmp_path / "ior.exr").write_bytes(encode(wide, ".exr", "linear"))
    assert read_values(texture(tmp_path / "ior.exr", "linear"), "scalar")[0, 0] == pytest.approx(3.7)


@pytest.mark.parametrize("make, words", [
    (lambda d: _write(d / "nan.exr", np.full((2, 2, 3), np.nan), "float"), "not finite"),
    (lambda d: (d / "cut.png").write_bytes(encode(np.random.rand(64, 64, 3), ".png", "linear")[:300]) and d / "cut.png",
     "cannot read the texture"),
    (lambda d: d, "not an image file"),
])
def test_a_broken_texture_is_one_error_naming_its_file(tmp_path, make, words):
    path = make(tmp_path)
    with pytest.raises(ConfigError) as e:
        read_values(texture(path, "linear"), "rgb")
    assert words in str(e.value) and str(path) in str(e.value) and "\n" not in str(e.value)
