"""The selection-aware limits of the IMU fit's kept terms (sigmatau.imu.fitting).

A kept term's interval is the Neyman interval of its unconstrained estimate ĉ given that the
selection kept it: ĉ ~ N(c, s(c)²) truncated below at the edge where the selection would drop the
term. Checked here on the truncated normal itself (exact cases, and coverage over draws from it),
independently of the fit.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.special import ndtri

from sigmatau.imu.fitting import _truncated_below_limits

LEVEL = 0.683


def test_without_truncation_and_with_a_constant_spread_the_limits_are_c_hat_plus_minus_z_s():
    z = ndtri(0.5 + LEVEL / 2)
    lo, hi = _truncated_below_limits(2.0, lambda c: 0.5, -math.inf, LEVEL)
    # The root is found to 1e-6 of the spread.
    assert lo == pytest.approx(2.0 - z * 0.5, abs=1e-6)
    assert hi == pytest.approx(2.0 + z * 0.5, abs=1e-6)
    mid = _truncated_below_limits(2.0, lambda c: 0.5, -math.inf, 0.0)
    assert mid[0] == pytest.approx(2.0, abs=1e-6) and mid[1] == pytest.approx(2.0, abs=1e-6)


def test_the_limits_solve_the_truncated_normal_equations():
    """S(c) = P_c(ĉ' ≥ ĉ | ĉ' > edge) is (1 − p)/2 at the lower limit and (1 + p)/2 at the upper."""
    from scipy.stats import truncnorm

    def spread(c):
        return 0.3 + 0.2 * abs(c)

    c_hat, edge = 1.1, 0.8
    lo, hi = _truncated_below_limits(c_hat, spread, edge, LEVEL)

    def survival(c):
        s = spread(c)
        return truncnorm.sf(c_hat, (edge - c) / s, np.inf, loc=c, scale=s)

    assert survival(lo) == pytest.approx(0.5 - LEVEL / 2, abs=1e-6)
    assert survival(hi) == pytest.approx(0.5 + LEVEL / 2, abs=1e-6)
    # Near the edge the truncated normal holds low true values too: the interval reaches lower than
    # the one that ignores the truncation, ĉ − z·s(ĉ) = 0.58.
    z = ndtri(0.5 + LEVEL / 2)
    assert lo < c_hat - z * spread(c_hat) - 0.2, lo


@pytest.mark.parametrize("truth, edge", [(1.0, 0.6), (1.0, 1.2), (0.2, 0.5), (3.0, -math.inf)])
def test_the_limits_cover_at_their_level_given_the_truncation(rng, truth, edge):
    """Draws of ĉ from N(c, s(c)²) kept only above the edge (the selection): the interval covers c
    in a share p of them. Binomial count over 1500 kept draws; accepted within 3.29 sd (two-sided
    0.1 %). The spread grows with the level, as an AVAR point's does."""
    def spread(c):
        return 0.25 + 0.25 * abs(c)

    s = spread(truth)
    draws = truth + s * rng.standard_normal(20_000)
    kept = draws[draws > edge][:1500]
    assert kept.size == 1500
    held = 0
    for c_hat in kept:
        lo, hi = _truncated_below_limits(float(c_hat), spread, edge, LEVEL)
        held += lo <= truth <= hi
    sd = math.sqrt(LEVEL * (1 - LEVEL) / kept.size)
    assert abs(held / kept.size - LEVEL) <= 3.29 * sd, (held, kept.size)
