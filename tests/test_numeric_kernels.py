"""The numeric building blocks of the kernels keep every rounding of the plain expressions."""

import numpy as np
import pytest

from sigmatau.core import kernels
from sigmatau.core.numeric import WindowSums, _combine, sumsq_combination


@pytest.mark.parametrize("coefs", [(1.0, -1.0), (1.0, 1.0), (1.0, -2.0, 1.0), (-1.0, 3.0, -3.0, 1.0),
                                   (2.0, -1.0), (1.0,), (0.5, 1.0, -1.0)])
def test_combine_is_the_left_to_right_numpy_expression_bit_for_bit(coefs, rng):
    arrays = [rng.standard_normal(1000) * 10.0 ** rng.integers(-3, 4) for _ in coefs]
    terms = list(zip(coefs, arrays))
    expected = coefs[0] * arrays[0] if coefs[0] != 1.0 else arrays[0].copy()
    for c, a in terms[1:]:
        if c == 1.0:
            expected = expected + a
        elif c == -1.0:
            expected = expected - a
        else:
            expected = expected + c * a
    out, tmp = np.empty(1000), np.empty(1000)
    _combine(out, tmp, terms, 0, 1000)
    np.testing.assert_array_equal(out, expected)
    assert sumsq_combination(terms, 1000, chunk=7) == pytest.approx(float(expected @ expected), rel=1e-13)


@pytest.mark.parametrize("ms", [2 ** np.arange(11), np.array([1, 2, 4, 10, 20, 40, 100, 200, 400, 1000]),
                                np.arange(1, 1667), np.array([4, 8, 16]), np.array([3, 6, 12, 24, 48]),
                                np.array([5, 10, 20, 30, 60])])
def test_mvar_with_a_released_is_bit_for_bit_the_same(ms, monkeypatch, rng):
    y = rng.standard_normal(5000)
    y -= y.mean()
    released = kernels._mvar_freq(y, ms, 1.0)
    monkeypatch.setattr(WindowSums, "release_a", lambda self: None)  # keep A: the old path
    kept = kernels._mvar_freq(y, ms, 1.0)
    np.testing.assert_array_equal(released[0], kept[0])
    np.testing.assert_array_equal(released[1], kept[1])


def test_a_step_that_needs_a_after_release_is_refused(rng):
    ws = WindowSums(rng.standard_normal(200), double=True)
    ws.advance(8)
    ws.release_a()
    ws.advance(32)  # doublings only: fine
    with pytest.raises(ValueError, match="needs A_w"):
        ws.advance(33)
    with pytest.raises(AttributeError):
        ws.a
