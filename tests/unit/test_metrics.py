import numpy as np

from brdfremap.core.data.metrics import delta_e_itp, relative_rmse


def _img(seed=0):
    rng = np.random.default_rng(seed)
    return rng.random((16, 16, 3)).astype(np.float32)


def test_relative_rmse_is_the_papers_l2():
    a = _img()
    assert relative_rmse(a, a) == 0.0
    assert np.isclose(relative_rmse(a, 1.1 * a), 0.1, rtol=1e-6)
    b = _img(1)
    assert np.isclose(relative_rmse(a, b), np.linalg.norm(b - a) / np.linalg.norm(a))


def test_delta_e_itp_zero_for_identical_and_grows_with_difference():
    a = _img()
    assert delta_e_itp(a, a) == 0.0
    small, big = delta_e_itp(a, 1.01 * a), delta_e_itp(a, 1.2 * a)
    assert 0 < small < big


def test_delta_e_itp_ignores_black_background():
    a = np.zeros((32, 32, 3), np.float32)
    a[8:24, 8:24] = 0.5
    b = a * 1.05
    padded_a = np.pad(a, ((32, 32), (32, 32), (0, 0)))
    padded_b = np.pad(b, ((32, 32), (32, 32), (0, 0)))
    assert np.isclose(delta_e_itp(a, b), delta_e_itp(padded_a, padded_b))


def test_delta_e_itp_just_noticeable_scale():
    # A 1% luminance change on mid grey is about one just-noticeable difference or less.
    a = np.full((4, 4, 3), 0.18, np.float32)
    assert 0.1 < delta_e_itp(a, a * 1.01) < 3.0
