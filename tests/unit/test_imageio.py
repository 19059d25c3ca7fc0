"""Image files read the right way up, whatever their format stores first."""

import numpy as np

from brdfremap.core.data.imageio import read_image, write_exr


def test_a_pfm_written_bottom_row_first_reads_the_right_way_up(tmp_path):
    """PFM stores its bottom row first; OpenImageIO 3.0 hands the rows back as stored, so a PFM from
    any writer that follows the format (a Node.js renderer: examples/renderer-node) read upside down."""
    img = np.zeros((4, 3, 3), np.float32)
    img[0] = 1.0  # the top row bright
    path = tmp_path / "top.pfm"
    path.write_bytes(b"PF\n3 4\n-1.0\n" + img[::-1].astype("<f4").tobytes())
    assert np.array_equal(read_image(path), img)
    write_exr(tmp_path / "top.exr", img)  # an EXR stores its top row first: read as it is
    assert np.array_equal(read_image(tmp_path / "top.exr"), img)
