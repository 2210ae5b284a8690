"""The exact EDF of the Allan variance of white PM + white FM (sigmatau.uncertainty.mixture_edf).

Checked against a dense oracle (the quadratic form's variance ``2 tr(AΣAΣ)`` with the matrices
written out) and against Monte Carlo; the Greenhall–Riley values it departs from are shown to be
outside the Monte Carlo's band.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from sigmatau.confidence import edf, white_mixture_edf
from sigmatau.errors import ParameterError


def _dense_nu(statistic: str, m: int, N: int, w: float) -> float:
    """ν = 2(E σ̂²)²/var σ̂² with σ̂² = yᵀAy over the n = N − 1 frequency samples, written out:
    A from the estimator's definition, Σ the covariance of white PM (unit phase variance,
    differenced) scaled to the share w plus white FM scaled to 1 − w; var = 2 tr(AΣAΣ)."""
    n = N - 1
    starts = range(n - 2 * m + 1) if statistic == "oadev" else range(0, n - 2 * m + 1, m)
    rows = []
    for k in starts:
        h = np.zeros(n)
        h[k:k + m] = -1.0 / m
        h[k + m:k + 2 * m] = 1.0 / m
        rows.append(h)
    D = np.array(rows)
    A = D.T @ D / (2 * len(rows))
    diff = np.zeros((n, n + 1))           # y = diff(x) for white PM
    diff[np.arange(n), np.arange(n)] = -1.0
    diff[np.arange(n), np.arange(1, n + 1)] = 1.0
    s_pm = diff @ diff.T
    s_fm = np.eye(n)
    s_pm *= w / np.trace(A @ s_pm) if w > 0 else 0.0
    s_fm *= (1 - w) / np.trace(A @ s_fm) if w < 1 else 0.0
    S = s_pm + s_fm
    mean = np.trace(A @ S)
    return float(2 * mean**2 / (2 * np.trace(A @ S @ A @ S)))


@pytest.mark.parametrize("statistic", ["oadev", "adev"])
@pytest.mark.parametrize("m", [1, 2, 3, 5])
@pytest.mark.parametrize("w", [0.0, 0.3, 0.8, 1.0])
def test_exact_against_the_dense_quadratic_form(statistic, m, w):
    """The lag-sum formula equals the written-out quadratic form to rounding (N = 41 phase points)."""
    got = float(white_mixture_edf(statistic, m, 41, w))
    assert got == pytest.approx(_dense_nu(statistic, m, 41, w), rel=1e-10)


def _lag_sum_nu(statistic: str, m: int, N: int, w: float) -> float:
    """ν = M²R(0)²/Σ(M − |i|)R(iL)², the lags summed one by one (O(m))."""
    n = N - 1
    terms, spacing = (n - 2 * m + 1, 1) if statistic == "oadev" else (n // m - 1, m)
    if terms < 1:
        return math.nan
    lags = np.arange(0, min(2 * m, (terms - 1) * spacing) + 1, spacing)
    a = lags.astype(float)
    r_fm = np.where(a <= m, (2 * m - 3 * a) / m**2, (a - 2 * m) / m**2) * m
    r_pm = np.zeros(a.size)
    for lag, value in ((0, 6.0), (m, -4.0), (2 * m, 1.0)):
        r_pm[lags == lag] = value / 3.0
    r = (1 - w) * r_fm + w * r_pm
    weight = terms - lags // spacing
    return float(terms**2 * r[0] ** 2 / (weight[0] * r[0] ** 2 + 2 * np.sum(weight[1:] * r[1:] ** 2)))


def test_closed_form_against_the_lag_sum(rng):
    """The O(1) closed form equals the lag-by-lag sum to 1e-12 over 600 random (m, N, share),
    including records too short for 2m lags, and at a day at 1 kHz with m = 10⁶."""
    for _ in range(300):
        m, N = int(rng.integers(1, 300)), int(rng.integers(2, 2000))
        w = float(rng.choice([0.0, 1.0, rng.random()]))
        for statistic in ("oadev", "adev"):
            want, got = _lag_sum_nu(statistic, m, N, w), float(white_mixture_edf(statistic, m, N, w))
            assert (math.isnan(want) and math.isnan(got)) or got == pytest.approx(want, rel=1e-12)
    assert float(white_mixture_edf("oadev", 10**6, 86_400_001, 0.3)) == pytest.approx(
        _lag_sum_nu("oadev", 10**6, 86_400_001, 0.3), rel=1e-12)


def test_pure_noises_match_greenhall_where_it_is_exact():
    """White PM alone, and white FM alone at m ≥ 64, agree with the Greenhall–Riley EDF (ratios
    within 1 % at N = 4097); white FM at m = 1, 2, 8 does not (the module docstring's figures)."""
    for m in (1, 8, 64):
        assert float(white_mixture_edf("oadev", m, 4097, 1.0)) == pytest.approx(edf("oadev", 2, m, 4097), rel=0.01)
    assert float(white_mixture_edf("oadev", 64, 4097, 0.0)) == pytest.approx(edf("oadev", 0, 64, 4097), rel=0.01)
    got = white_mixture_edf("oadev", [1, 2, 8], 4097, 0.0)
    assert [round(float(v)) for v in got] == [2730, 2339, 751]
    # Greenhall–Riley's values are also allantools 2024.6's edf_greenhall (alpha=0, d=2, overlapping)
    # to the last digit; the exact ones are those of the dense and lag-sum oracles above and are
    # within the Monte Carlo's error below (2779 ± 62, 2362 ± 53 and 783 ± 20 in the module docstring).
    assert [round(edf("oadev", 0, m, 4097)) for m in (1, 2, 8)] == [3205, 2218, 686]


def test_mixture_scatters_less_than_fully_correlated_parts():
    """At the crossing the two contributions are only partly correlated: the mixture's EDF exceeds
    2/(w√(2/ν_P) + (1 − w)√(2/ν_F))², the EDF if they were fully correlated, and lies between the pure
    noises' here (white FM alone 751, white PM alone 2101, both 1525 at m = 8)."""
    pm, fm = (float(white_mixture_edf("oadev", 8, 4097, w)) for w in (1.0, 0.0))
    for w in (0.2, 0.5, 0.8):
        both = float(white_mixture_edf("oadev", 8, 4097, w))
        assert both > 2.0 / (w * math.sqrt(2.0 / pm) + (1 - w) * math.sqrt(2.0 / fm)) ** 2
        assert fm < both < pm


@pytest.mark.parametrize("statistic, w", [("oadev", 0.5), ("oadev", 0.0), ("adev", 0.5)])
def test_monte_carlo(statistic, w, rng):
    """2000 records of 4096 samples, m = 8: the sample EDF 2(mean)²/var of the Allan variance
    estimates lies within 3.29 standard errors of the exact value (relative SE of a sample variance
    of nearly normal estimates: √(2/(R − 1))). For the overlapping estimator the dominant-type
    Greenhall value lies outside that band (mixture: 2101 for PM, 751 exact for FM, against 1525;
    FM alone: 686 against 751)."""
    records, n, m = 2000, 4096, 8
    s_x = 1.0
    a_pm = 3.0 * s_x**2 / m**2
    s_y = math.sqrt(a_pm * (1 - w) / w * m) if w > 0 else 1.0
    x = rng.standard_normal((records, n + 1)) * (s_x if w > 0 else 0.0)
    y = np.diff(x, axis=1) + rng.standard_normal((records, n)) * s_y
    c = np.concatenate([np.zeros((records, 1)), np.cumsum(y, axis=1)], axis=1)
    ybar = (c[:, m:] - c[:, :-m]) / m
    if statistic == "oadev":
        d = ybar[:, m:] - ybar[:, :-m]
    else:
        blocks = ybar[:, ::m]
        d = blocks[:, 1:] - blocks[:, :-1]
    avar = 0.5 * np.mean(d * d, axis=1)
    nu_mc = 2.0 * avar.mean() ** 2 / avar.var(ddof=1)
    exact = float(white_mixture_edf(statistic, m, n + 1, w))
    band = 3.29 * math.sqrt(2.0 / (records - 1))
    assert abs(nu_mc / exact - 1.0) < band, (nu_mc, exact)
    if statistic == "oadev":
        dominant = edf(statistic, 2 if w >= 0.5 else 0, m, n + 1)
        assert abs(nu_mc / dominant - 1.0) > band, (nu_mc, dominant)


@pytest.mark.parametrize("kwargs, match", [
    (dict(statistic="mdev", m=1, N=100, pm_share=0.5), "oadev"),
    (dict(statistic=None, m=1, N=100, pm_share=0.5), "oadev"),
    (dict(statistic="oadev", m=0, N=100, pm_share=0.5), "at least 1"),
    (dict(statistic="oadev", m=1.5, N=100, pm_share=0.5), "whole"),
    (dict(statistic="oadev", m=float("nan"), N=100, pm_share=0.5), "whole"),
    (dict(statistic="oadev", m=1e30, N=100, pm_share=0.5), "whole"),
    (dict(statistic="oadev", m=10**30, N=100, pm_share=0.5), "whole"),
    (dict(statistic="oadev", m=1, N=100, pm_share=1.5), "0 … 1"),
    (dict(statistic="oadev", m=1, N=100, pm_share=float("nan")), "0 … 1"),
    (dict(statistic="oadev", m=1, N=1, pm_share=0.5), "phase points"),
    (dict(statistic="oadev", m=1, N=100.0, pm_share=0.5), "phase points"),
])
def test_bad_arguments_get_one_clear_error(kwargs, match):
    with pytest.raises(ParameterError, match=match):
        white_mixture_edf(**kwargs)


def test_too_short_a_record_gives_nan_and_shapes_broadcast():
    assert math.isnan(float(white_mixture_edf("oadev", 10, 15, 0.5)))
    assert white_mixture_edf("adev", [[1, 2], [3, 4]], 1001, [0.1, 0.9]).shape == (2, 2)
