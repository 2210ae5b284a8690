"""Tests of the total family: TOTDEV, MTOTDEV, TTOTDEV, HTOTDEV.

Reference values
----------------
* NBS 1000-point set, m = 1, 10, 100: SP1065 Table 31 / Riley / Stable32 v1.60
  as collected in numerics.md §7.2 (7 printed digits).
* NBS 9-point set: SP1065 Table 30, numerics.md §7.3 (7 printed digits).
* Stable32 output tables in tests/data/allantools (5 printed digits; see the
  README there). Which tables are bias-corrected was read from the tables
  themselves and is stated next to each one below.

The plain definitions (explicit loops, written from numerics.md §1.7–1.11) are
the oracles for the fast kernels.
"""

from __future__ import annotations

import math
import tracemalloc
import warnings
from dataclasses import replace

import numpy as np
import pytest

import refdata
import sigmatau.stats.total as total_mod
import sigmatau.stats.total_sums as total_sums
from refdata import (
    PINK_RATE,
    gps_phase,
    load_table,
    ocxo_frequency,
    phase_dat,
    pink_frequency,
    tic_phase,
)
from sigmatau import oadev
from helpers import half_unit
from sigmatau.core.driver import prepare
from sigmatau.datasets import nbs1000, nbs9
from sigmatau.errors import DataError, ParameterError, RangeWarning
from sigmatau.stats.total import htotdev, mtotdev, totdev, ttotdev


def assert_printed(values, printed, rel_slack=0.0):
    """Each value equals its printed reference to the printed digits.

    The allowance is half a unit of the last printed digit (plus 1 % of that
    for the rounding calls the source marks with "full …" digits), plus
    ``rel_slack`` relative where the source is known to be less exact.
    """
    values = np.atleast_1d(values)
    assert values.size == len(printed)
    for v, text in zip(values, printed):
        allowed = 1.01 * half_unit(text) + rel_slack * abs(float(text))
        assert abs(v - float(text)) <= allowed, f"{v!r} differs from printed {text}"


# --- NBS 1000-point set (numerics.md §7.2) -----------------------------------------

M3 = [1, 10, 100]


def test_nbs1000_totdev():
    r = totdev(nbs1000(), m=M3)
    assert_printed(r.dev, ["2.922319e-01", "9.134743e-02", "3.406530e-02"])
    assert r.n.tolist() == [999, 999, 999]
    assert r.bias == "none" and r.bias_factor is None


def test_nbs1000_mtotdev_raw_and_published():
    y = nbs1000()
    raw = mtotdev(y, m=M3)
    assert_printed(raw.dev, ["2.066391e-01", "5.552886e-02", "1.954675e-02"])
    assert raw.n.tolist() == [999, 972, 702]
    pub = mtotdev(y, m=M3, bias="published", alpha=0)
    assert_printed(pub.dev, ["2.418528e-01", "6.499161e-02", "2.287774e-02"])
    assert pub.bias == "published alpha=0"
    np.testing.assert_array_equal(pub.bias_factor, [0.73, 0.73, 0.73])
    np.testing.assert_allclose(pub.var, raw.var / 0.73, rtol=1e-15)


def test_nbs1000_ttotdev_raw_and_published():
    y = nbs1000()
    assert_printed(ttotdev(y, m=M3).dev, ["1.193032e-01", "3.205960e-01", "1.128532e+00"])
    pub = ttotdev(y, m=M3, bias="published", alpha=0)
    assert_printed(pub.dev, ["1.396338e-01", "3.752293e-01", "1.320847e+00"])
    assert pub.n.tolist() == [999, 972, 702]


def test_nbs1000_htotdev_published_and_raw():
    y = nbs1000()
    pub = htotdev(y, m=M3, bias="published", alpha=0)
    # m = 1 is OHDEV (Stable32/SP1065 convention), unbiased: factor 1. At m = 10
    # the source's digit is a rounding call (full 9.6147875e-02; ours 9.61478750e-02).
    assert_printed(pub.dev, ["2.943883e-01", "9.614787e-02", "3.058103e-02"])
    np.testing.assert_array_equal(pub.bias_factor, [1.0, 0.995, 0.995])
    assert pub.n.tolist() == [998, 971, 701]
    raw = htotdev(y, m=M3)
    assert_printed(raw.dev[1:], ["9.590720e-02", "3.050448e-02"])
    # The construction itself at m = 1 (not what the public function reports).
    x, _, _ = prepare(total_mod.HTOT, y, 1.0, "freq")
    var, n = total_mod._htot_formula_kernel(x, np.array([1]), 1.0)
    assert_printed(np.sqrt(var), ["2.081640e-01"])
    assert n.tolist() == [998]


# --- NBS 9-point set (numerics.md §7.3) --------------------------------------------


# SP1065 divided by the factor 0.73 held in single precision (0.7300000191):
# two of its four corrected 9-point values are then 0.6 of a last digit away
# from raw/√0.73 (see test_nbs9_published_values_used_a_float32_factor).
FLOAT32_073 = float(np.float32(0.73))
SP1065_FACTOR_SLACK = 0.5 * (FLOAT32_073 / 0.73 - 1)


def test_nbs9():
    y = nbs9()
    assert_printed(totdev(y, m=[1, 2]).dev, ["91.22945", "93.90379"])
    assert_printed(mtotdev(y, m=[1, 2]).dev, ["64.50896", "64.79436"])
    assert_printed(ttotdev(y, m=[1, 2]).dev, ["37.24427", "74.81809"])
    pub = mtotdev(y, m=[1, 2], bias="published", alpha=0).dev
    assert_printed(pub, ["75.50203", "75.83606"], rel_slack=SP1065_FACTOR_SLACK)
    pub = ttotdev(y, m=[1, 2], bias="published", alpha=0).dev
    assert_printed(pub, ["43.59112", "87.56794"], rel_slack=SP1065_FACTOR_SLACK)


def test_nbs9_published_values_used_a_float32_factor():
    y = nbs9()
    raw = np.concatenate((mtotdev(y, m=[1, 2]).dev, ttotdev(y, m=[1, 2]).dev))
    printed = ["75.50203", "75.83606", "43.59112", "87.56794"]
    assert [f"{v:.5f}" for v in raw / math.sqrt(FLOAT32_073)] == printed
    assert [f"{v:.5f}" for v in raw / math.sqrt(0.73)] != printed


# --- Stable32 tables ---------------------------------------------------------------

# Noise exponents for which each statistic has a bias factor. Stable32 applies
# its factor for the α it identified (the table's Alpha column) and nothing
# where the statistic has no factor.
_HAS_FACTOR = {
    totdev: {0, -1, -2},
    mtotdev: {2, 1, 0, -1, -2},
    ttotdev: {2, 1, 0, -1, -2},
    htotdev: {0, -1, -2, -3, -4},
}


def _s32_devs(func, table, data, **kw):
    """Deviations with the published factor for each row's Alpha (none where there is none)."""
    dev = np.empty(table.af.size)
    n = np.empty(table.af.size, dtype=np.int64)
    for alpha in np.unique(table.alpha):
        rows = table.alpha == alpha
        if int(alpha) in _HAS_FACTOR[func]:
            r = func(data, m=table.af[rows], bias="published", alpha=int(alpha), **kw)
        else:
            r = func(data, m=table.af[rows], **kw)
        dev[rows], n[rows] = r.dev, r.n
    return dev, n


_PHASE = dict(data_type="phase")

# (table, function, data loader, keyword arguments, convention, rtol)
#   "raw"   : Stable32 printed the raw estimator.
#   "alpha" : Stable32 divided by the published factor for the row's Alpha.
STABLE32 = [
    # PHASE.DAT = NBS phase minus its mean frequency; Alpha 0 → TOTVAR a = 0, 1 → none.
    ("phasedat/phase_dat_totdev.txt", totdev, phase_dat, _PHASE, "alpha", 1e-4),
    ("phasedat/phase_dat_totdev_octave.txt", totdev, phase_dat, _PHASE, "alpha", 1e-4),
    # S32 1.53 all-τ run: raw/0.73 where Alpha = 0, raw/0.83 where Alpha = 1 (numerics §7.2, §8.10).
    ("phasedat/phase_dat_mtotdev.txt", mtotdev, phase_dat, _PHASE, "alpha", 1e-4),
    ("phasedat/phase_dat_ttotdev_all.txt", ttotdev, phase_dat, _PHASE, "alpha", 1e-4),
    # S32 1.60 octave/decade MTOT and TTOT runs are raw (m = 1: 2.0664e-01 = raw MTOT).
    ("phasedat/phase_dat_mtotdev_octave.txt", mtotdev, phase_dat, _PHASE, "raw", 1e-4),
    ("phasedat/phase_dat_mtotdev_decade.txt", mtotdev, phase_dat, _PHASE, "raw", 1e-4),
    ("phasedat/phase_dat_mtotdev_octave_alpha0.txt", mtotdev, phase_dat, _PHASE, "raw", 1e-4),
    ("phasedat/phase_dat_ttotdev_decade.txt", ttotdev, phase_dat, _PHASE, "raw", 1e-4),
    ("phasedat/phase_dat_ttotdev_octave.txt", ttotdev, phase_dat, _PHASE, "raw", 1e-4),
    # HTOT: raw/0.995 where Alpha = 0 (m = 1 is OHDEV, factor 1), raw where Alpha = 1.
    ("phasedat/phase_dat_htotdev_octave.txt", htotdev, phase_dat, _PHASE, "alpha", 1e-4),
    # Same data as frequency; Alpha = 2 everywhere, where HTOT has no factor: raw.
    ("phasedat/phase_dat_htotdev_octave_nobias.txt", htotdev, nbs1000, {}, "alpha", 1e-4),
    # Frequency data; Alpha 0 everywhere.
    ("ocxo/stable32_totdev_alltau.txt", totdev, ocxo_frequency, {}, "alpha", 1e-4),
    ("pink_frequency/totdev_alpha0.txt", totdev, pink_frequency, dict(rate=PINK_RATE), "alpha", 1e-4),
    # Phase data; Alpha 2, 1, 0 (TOTVAR a = 0 or no factor).
    ("gps/stable32_TOTDEV_octave.txt", totdev, gps_phase, _PHASE, "alpha", 1e-4),
    ("Keysight53230A_ti_noise_floor/tic_totdev.txt", totdev, tic_phase, _PHASE, "alpha", 1e-4),
    # ocxo/totdev_octave.txt (S32 1.60 octave run on f/1e7, not on y): see
    # test_stable32_ocxo_totdev_octave_* below.
]

_CACHE: dict = {}


def _data(loader):
    if loader not in _CACHE:
        _CACHE[loader] = loader()
    return _CACHE[loader]


@pytest.mark.parametrize(
    "relpath, func, loader, kw, convention, rtol", STABLE32, ids=[row[0] for row in STABLE32]
)
def test_stable32_table(relpath, func, loader, kw, convention, rtol):
    table = load_table(relpath)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RangeWarning)
        if convention == "raw":
            r = func(_data(loader), m=table.af, **kw)
            dev, n = r.dev, r.n
        else:
            dev, n = _s32_devs(func, table, _data(loader), **kw)
    np.testing.assert_array_equal(n, table.n)
    np.testing.assert_allclose(dev, table.sigma, rtol=rtol, atol=0)


def test_stable32_ocxo_octave_needs_totvar_bias():
    table = load_table("ocxo/totdev_octave.txt")
    raw = totdev(ocxo_frequency(), m=table.af)
    big = np.isin(table.af, [512, 1024])
    assert np.all(np.abs(raw.dev[big] / table.sigma[big] - 1) > 5e-3)


# TOTDEV at small m: the OCXO octave table is 4.9e-4, 4.4e-4, 3.8e-4 above the exact
# TOTDEV at m = 1, 2, 4 (up to 1.6e-3 at larger m). Not ends, normalisation or mean
# frequency: Stable32 ran this table on f/1e7 = 1 + y (header "Average = 1.000000e+00")
# and integrated it to a ~2e4 s phase in float64, whose rounding (~1e-12 s a point)
# adds white-PM-like noise to 7.6e-11 s steps. The doubly reflected SP1065 sum on that
# phase, with the TOTVAR bias for the Alpha column, gives every printed value; the same
# sum on y is sigmatau's value, which matches the all-τ table of y (above) and SP1065's
# NBS values (test_nbs1000_totdev).


def test_stable32_ocxo_totdev_octave_reproduced_on_f_over_1e7():
    table = load_table("ocxo/totdev_octave.txt")
    as_seen = refdata.stable32_float_freq_dev("totdev", refdata.ocxo_normalised(), table.af, table.alpha)
    np.testing.assert_allclose(as_seen, table.sigma, rtol=1e-4, atol=0)  # measured 9.0e-6
    exact = refdata.stable32_float_freq_dev("totdev", ocxo_frequency(), table.af, table.alpha)
    small = table.af <= 4
    assert np.all((table.sigma[small] / exact[small] - 1) > 3e-4)  # the reported symptom


def test_stable32_ocxo_totdev_octave_within_its_roundoff():
    table = load_table("ocxo/totdev_octave.txt")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RangeWarning)
        dev, n = _s32_devs(totdev, table, _data(ocxo_frequency))
    np.testing.assert_array_equal(n, table.n)
    exact = refdata.stable32_float_freq_dev("totdev", ocxo_frequency(), table.af, table.alpha)
    as_seen = refdata.stable32_float_freq_dev("totdev", refdata.ocxo_normalised(), table.af, table.alpha)
    np.testing.assert_allclose(dev, exact, rtol=1e-9, atol=0)
    artefact = np.abs(as_seen / exact - 1)
    assert np.all(np.abs(dev / table.sigma - 1) <= artefact + 1e-4)


def test_ocxo_octave_oadev_is_roundoff_of_one_plus_y():
    """The OADEV octave table of the same run shows the same artefact."""
    table = load_table("ocxo/oadev_octave.txt")
    err = oadev(ocxo_frequency(), m=table.af).dev / table.sigma - 1
    assert 4e-4 < np.abs(err).max() < 2e-3
    as_seen = refdata.stable32_float_freq_dev("oadev", refdata.ocxo_normalised(), table.af)
    np.testing.assert_allclose(as_seen, table.sigma, rtol=1e-4, atol=0)


def test_stable32_mtot_all_tau_alpha1_rows_use_083():
    # The α = 1 rows are where the 1.53 all-τ table switches factor.
    table = load_table("phasedat/phase_dat_mtotdev.txt")
    rows = table.alpha == 1
    assert rows.sum() > 10
    r = mtotdev(phase_dat(), data_type="phase", m=table.af[rows], bias="published", alpha=1)
    np.testing.assert_allclose(r.dev, table.sigma[rows], rtol=1e-4)
    np.testing.assert_array_equal(r.bias_factor, 0.83)


# --- plain definitions (oracles) -----------------------------------------------------


def totvar_plain(x, m, tau0):
    n_pts = len(x)

    def xs(i):
        if i < 0:
            return 2 * x[0] - x[-i]
        if i > n_pts - 1:
            return 2 * x[n_pts - 1] - x[2 * (n_pts - 1) - i]
        return x[i]

    acc = 0.0
    for i in range(1, n_pts - 1):
        acc += (xs(i - m) - 2 * xs(i) + xs(i + m)) ** 2
    return acc / (2 * (m * tau0) ** 2 * (n_pts - 2)), n_pts - 2


def _tot_construction_plain(u, m):
    """Mean over subsequences of (1/6m)·Σ_j z_j², by the steps of numerics §1.9."""
    length = 3 * m
    h1, h2 = length // 2, (length + 1) // 2
    windows = len(u) - length + 1
    acc = 0.0
    for n in range(windows):
        s = np.array(u[n : n + length], dtype=float)
        slope = (np.mean(s[h2:]) - np.mean(s[:h1])) / h2
        s = s - slope * np.arange(length)
        e = np.concatenate((s[::-1], s, s[::-1]))
        a = [np.sum(e[j : j + m]) / m for j in range(8 * m + 1)]
        inner = 0.0
        for j in range(6 * m):
            inner += (a[j] - 2 * a[j + m] + a[j + 2 * m]) ** 2
        acc += inner / (6 * m)
    return acc / windows, windows


def mtot_plain(x, m, tau0):
    mean, windows = _tot_construction_plain(x, m)
    return mean / (2 * (m * tau0) ** 2), windows


def ohvar_plain(x, m, tau0):
    terms = [(x[i + 3 * m] - 3 * x[i + 2 * m] + 3 * x[i + m] - x[i]) ** 2 for i in range(len(x) - 3 * m)]
    return sum(terms) / (6 * (m * tau0) ** 2 * len(terms)), len(terms)


def htot_plain(x, m, tau0):
    y = np.diff(x) / tau0
    mean, windows = _tot_construction_plain(y, m)
    return mean / 6, windows


def _noise(kind, size, rng):
    w = rng.standard_normal(size + 2)
    series = {
        "white": w,
        "cumsum": np.cumsum(w),
        "cumsum2": np.cumsum(np.cumsum(w)),
        "diff": np.diff(w),
    }[kind]
    return series[:size]


KINDS = ["white", "cumsum", "cumsum2", "diff"]
# Frequency sample counts (N = M + 1 phase points): tiny, odd, prime, even.
SIZES = [2, 3, 5, 9, 16, 37, 101, 160]


def _factors(upper):
    return sorted({m for m in (1, 2, 3, 4, 5, 7, 10, upper // 2, upper) if 1 <= m <= upper})


def _check_against_plain(func, stat, plain, kind, size, rate, seed):
    rng = np.random.default_rng(seed)
    y = _noise(kind, size, rng) * 1e-3
    x, rate_f, _ = prepare(stat, y, rate, "freq")
    ms = _factors(stat.max_m(x.size))
    if not ms:
        return
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RangeWarning)
        r = func(y, rate=rate, m=ms)
    for i, m in enumerate(ms):
        want, n_want = plain(x, m, 1.0 / rate_f)
        assert r.n[i] == n_want
        assert r.var[i] == pytest.approx(want, rel=1e-10, abs=0), (kind, size, m)


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("size", SIZES)
def test_totdev_equals_plain_definition(kind, size):
    _check_against_plain(totdev, total_mod.TOTVAR, totvar_plain, kind, size, 2.5, size)


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("size", SIZES)
def test_mtotdev_equals_plain_definition(kind, size):
    _check_against_plain(mtotdev, total_mod.MTOT, mtot_plain, kind, size, 1.0, 100 + size)


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("size", SIZES)
def test_ttotdev_equals_plain_definition(kind, size):
    def ttot_plain(x, m, tau0):
        var, n = mtot_plain(x, m, tau0)
        return var * (m * tau0) ** 2 / 3, n

    _check_against_plain(ttotdev, total_mod.TTOT, ttot_plain, kind, size, 0.5, 200 + size)


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("size", SIZES[1:])
def test_htotdev_equals_plain_definition(kind, size):
    def htot_reported(x, m, tau0):
        return ohvar_plain(x, m, tau0) if m == 1 else htot_plain(x, m, tau0)

    _check_against_plain(htotdev, total_mod.HTOT, htot_reported, kind, size, 4.0, 300 + size)


@pytest.mark.parametrize("kind", KINDS)
def test_htot_formula_at_m1_equals_plain_definition(kind):
    x = np.cumsum(_noise(kind, 60, np.random.default_rng(7)))
    var, n = total_mod._htot_formula_kernel(x, np.array([1, 2]), 1.0)
    for i, m in enumerate((1, 2)):
        want, n_want = htot_plain(x, m, 1.0)
        assert n[i] == n_want and var[i] == pytest.approx(want, rel=1e-10)


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("block", [1, 7, 40])
def test_blocked_windows_equal_plain_definition(kind, block):
    """Blocks of one row, blocks that do not divide the count, several rows."""
    x = np.cumsum(_noise(kind, 97, np.random.default_rng(block)))
    for m in (1, 2, 5, 11):
        got, windows = total_sums.tot_sums(x, m, block=block * (3 * m + 1))
        want, w_want = _tot_construction_plain(x, m)
        assert windows == w_want
        assert got / (6 * m * windows) == pytest.approx(want, rel=1e-10)


# --- properties ----------------------------------------------------------------------


@pytest.mark.parametrize("func", [totdev, mtotdev, ttotdev, htotdev])
def test_linear_phase_trend_is_ignored(func):
    x = np.cumsum(np.random.default_rng(3).standard_normal(300))
    t = np.arange(x.size)
    base = func(x, data_type="phase", taus="all")
    ramp = func(x + 5.0 + 0.8 * t, data_type="phase", taus="all")
    np.testing.assert_allclose(ramp.var, base.var, rtol=1e-9)


def test_htotdev_ignores_linear_frequency_drift():
    y = np.random.default_rng(4).standard_normal(300)
    base = htotdev(y, taus="all")
    drift = htotdev(y + 0.05 * np.arange(y.size), taus="all")
    np.testing.assert_allclose(drift.var, base.var, rtol=1e-9)


@pytest.mark.parametrize("func", [totdev, mtotdev, ttotdev, htotdev])
def test_phase_and_frequency_input_agree(func):
    y = np.random.default_rng(5).standard_normal(200)
    x = np.concatenate(([0.0], np.cumsum(y) / 4.0))
    a = func(y, rate=4.0, taus="octave")
    b = func(x, rate=4.0, data_type="phase", taus="octave")
    np.testing.assert_array_equal(a.m, b.m)
    np.testing.assert_allclose(a.var, b.var, rtol=1e-10)
    np.testing.assert_allclose(a.taus, a.m / 4.0)


@pytest.mark.parametrize("func", [totdev, mtotdev, ttotdev, htotdev])
def test_scaling(func):
    y = np.random.default_rng(6).standard_normal(120)
    np.testing.assert_allclose(func(3.0 * y).var, 9.0 * func(y).var, rtol=1e-12)


def test_default_grids_follow_stable32_stop_ratios():
    y = np.random.default_rng(2).standard_normal(100)  # N = 101 phase points
    assert totdev(y).m[-1] == 32 and totdev(y, taus="all").m[-1] == 50
    assert mtotdev(y, taus="all").m[-1] == 33
    assert ttotdev(y, taus="all").m[-1] == 33
    assert htotdev(y, taus="all").m[-1] == 33


def test_largest_factors():
    y = np.random.default_rng(8).standard_normal(30)  # N = 31
    with pytest.warns(RangeWarning):
        assert totdev(y, m=30).n.tolist() == [29]
    with pytest.raises(ParameterError):
        totdev(y, m=31)
    assert mtotdev(y, m=10).n.tolist() == [2]  # N/3 is also the default limit
    with pytest.raises(ParameterError):
        mtotdev(y, m=11)
    assert htotdev(y, m=10).n.tolist() == [1]
    with pytest.raises(ParameterError):
        htotdev(y, m=11)


# --- bias ----------------------------------------------------------------------------


def test_estimator_factors():
    y = nbs1000()
    raw = mtotdev(y, m=M3)
    for alpha, b in {2: 0.995, 1: 0.85, 0: 0.77, -1: 0.72, -2: 0.68}.items():
        r = mtotdev(y, m=M3, bias="estimator", alpha=alpha)
        np.testing.assert_allclose(r.var, raw.var / b, rtol=1e-15)
        assert r.bias == f"estimator alpha={alpha}"
    raw = htotdev(y, m=M3)
    for alpha, b in {0: 0.994, -1: 0.850, -2: 0.771, -3: 0.717, -4: 0.679}.items():
        r = htotdev(y, m=M3, bias="estimator", alpha=alpha)
        np.testing.assert_allclose(r.bias_factor, [1.0, b, b])
        np.testing.assert_allclose(r.var, raw.var / r.bias_factor, rtol=1e-15)


def test_published_htot_factors():
    raw = htotdev(nbs1000(), m=[1, 10])
    for alpha, a in {0: -0.005, -1: -0.149, -2: -0.229, -3: -0.283, -4: -0.321}.items():
        r = htotdev(nbs1000(), m=[1, 10], bias="published", alpha=alpha)
        np.testing.assert_allclose(r.bias_factor, [1.0, 1.0 + a])
        np.testing.assert_allclose(r.var, raw.var / r.bias_factor, rtol=1e-15)


def test_totdev_bias_is_one_minus_a_tau_over_t():
    y = nbs1000()
    raw = totdev(y, m=M3)
    t_rec = 1000.0  # (N - 1)·τ0
    for alpha, a in {0: 0.0, -1: 1 / (3 * math.log(2)), -2: 0.75}.items():
        for mode in ("published", "estimator"):
            r = totdev(y, m=M3, bias=mode, alpha=alpha)
            np.testing.assert_allclose(r.bias_factor, 1 - a * np.array(M3) / t_rec, rtol=1e-15)
            np.testing.assert_allclose(r.var, raw.var / r.bias_factor, rtol=1e-15)


# --- errors --------------------------------------------------------------------------


@pytest.mark.parametrize("func", [totdev, mtotdev, ttotdev, htotdev])
def test_bias_without_alpha_uses_identified_noise(func):
    y = nbs1000()
    for mode in ("published", "estimator", "auto"):
        r = func(y, m=[2, 8, 32], bias=mode)
        raw = func(y, m=[2, 8, 32])
        assert "identified" in r.bias
        np.testing.assert_array_equal(r.alpha, raw.alpha)
        table = total_mod._FACTORS[func.__name__][total_mod._table_name(mode)]
        for i, a in enumerate(r.alpha):
            if func is totdev:
                expect = 1.0 - table[int(a)] * r.taus[i] / 1000.0
            else:
                expect = table[int(a)]
            assert r.bias_factor[i] == pytest.approx(expect, rel=1e-15)
        np.testing.assert_allclose(r.var, raw.var / r.bias_factor, rtol=1e-15)
        # the interval moves with the estimate (a fixed divisor scales chi-square bounds)
        np.testing.assert_allclose(r.ci_low / r.dev, raw.ci_low / raw.dev, rtol=1e-12)


def test_bias_auto_reproduces_stable32_all_tau_mtot():
    # Stable32 1.53 all-tau MTOT on PHASE.DAT divides by 0.73 or 0.83 according to its own
    # noise identification (Alpha column). Where the lag-1 method applies (N/m >= 30),
    # bias="auto" must find the same alpha and so give the published value.
    table = load_table("phasedat/phase_dat_mtotdev.txt")
    rows = (1001 // table.af) >= 30
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RangeWarning)
        r = mtotdev(phase_dat(), data_type="phase", m=table.af[rows], bias="auto")
    np.testing.assert_array_equal(r.alpha, table.alpha[rows])
    np.testing.assert_allclose(r.dev, table.sigma[rows], rtol=1e-4)


def test_bias_none_is_raw_even_with_alpha():
    y = nbs1000()
    r = mtotdev(y, m=[10], alpha=0)
    assert r.bias == "none" and r.bias_factor is None
    assert r.dev[0] == pytest.approx(5.552886e-02, rel=1e-6)


@pytest.mark.parametrize(
    "func, alpha",
    [(totdev, 1), (totdev, -3), (mtotdev, 3), (mtotdev, -3), (ttotdev, -4), (htotdev, 1), (htotdev, -5)],
)
def test_unsupported_alpha(func, alpha):
    # alpha outside -4..2 is refused for every statistic; inside it, the message lists the
    # alphas that have a factor.
    with pytest.raises(ParameterError, match="allowed|from -4 to 2") as info:
        func(nbs9(), bias="published", alpha=alpha)
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("bias", ["none", "published"])
@pytest.mark.parametrize("alpha", [0.5, "0", True])
def test_alpha_must_be_an_integer(alpha, bias):
    with pytest.raises(ParameterError, match="integer"):
        mtotdev(nbs9(), bias=bias, alpha=alpha)


def test_integral_float_alpha_is_accepted():
    a = mtotdev(nbs9(), bias="published", alpha=0.0)
    b = mtotdev(nbs9(), bias="published", alpha=0)
    np.testing.assert_array_equal(a.var, b.var)
    assert a.bias == "published alpha=0"


def test_bad_bias():
    with pytest.raises(ParameterError, match="bias"):
        mtotdev(nbs9(), bias="stable32")


def test_alpha_alone_leaves_the_variance_raw():
    r = htotdev(nbs1000(), m=M3, alpha=0)
    np.testing.assert_array_equal(r.var, htotdev(nbs1000(), m=M3).var)
    assert r.bias == "none" and r.bias_factor is None


def test_bias_scales_an_attached_interval():
    raw = mtotdev(nbs1000(), m=M3)
    lo, hi = 0.9 * raw.dev, 1.1 * raw.dev
    raw = replace(raw, ci_low=lo, ci_high=hi, alpha=np.zeros(len(raw)))
    r = total_mod._apply_bias(raw, "published", 0)
    np.testing.assert_allclose(r.ci_low, lo / math.sqrt(0.73), rtol=1e-15)
    np.testing.assert_allclose(r.ci_high, hi / math.sqrt(0.73), rtol=1e-15)


@pytest.mark.parametrize(
    "func, short", [(totdev, [1.0]), (mtotdev, [1.0]), (ttotdev, [1.0]), (htotdev, [1.0, 2.0])]
)
def test_too_short(func, short):
    with pytest.raises(DataError, match="at least"):
        func(short)
    func(short + [3.0], m=1)  # one sample more is enough


def test_validation_comes_first():
    # The bias check runs before the data are looked at.
    with pytest.raises(ParameterError, match="bias="):
        mtotdev([np.nan], bias="stable32")


# --- memory --------------------------------------------------------------------------


def test_memory_stays_blocked():
    """An (N × 9m) array would take 430 MB here; the blocks keep it to a few MB."""
    u = np.random.default_rng(9).standard_normal(6000)
    tracemalloc.start()
    try:
        total_sums.tot_sums(u, 1000)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < 5 * 8 * total_sums.BLOCK_ELEMENTS + 8 * u.size
