"""glint.halton against the radical inverses written out by hand."""
import numpy as np
import pytest

import glint


def test_first_points_are_radical_inverses():
    h = glint.halton(9, 3)
    assert h.shape == (9, 3) and h.dtype == np.float64
    np.testing.assert_array_equal(h[:, 0], [0, 1 / 2, 1 / 4, 3 / 4, 1 / 8, 5 / 8, 3 / 8, 7 / 8, 1 / 16])
    np.testing.assert_allclose(h[:, 1], [0, 1 / 3, 2 / 3, 1 / 9, 4 / 9, 7 / 9, 2 / 9, 5 / 9, 8 / 9], rtol=4e-15)
    np.testing.assert_allclose(h[:, 2], [0, 1 / 5, 2 / 5, 3 / 5, 4 / 5, 1 / 25, 6 / 25, 11 / 25, 16 / 25], rtol=4e-15)
    np.testing.assert_array_equal(glint.halton(3, 2, start=5), glint.halton(8, 2)[5:])


def test_randomized_points_are_uniform():
    h = glint.halton(4096, 4, seed=3, randomization="owen")
    assert np.all((h >= 0) & (h < 1))
    assert not np.array_equal(h, glint.halton(4096, 4, seed=4, randomization="owen"))
    # Each coordinate of 4096 stratified points: the mean is 1/2 to far better than random.
    np.testing.assert_allclose(h.mean(0), 0.5, atol=2e-3)


def test_bad_arguments():
    with pytest.raises(glint.Error, match="unknown randomization 'sobol'"):
        glint.halton(4, 2, randomization="sobol")
    with pytest.raises(glint.Error, match=r"dims = 1025 is outside \[1, 1024\]"):
        glint.halton(4, 1025)
