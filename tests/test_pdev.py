"""Parabolic deviation PDEV (sigmatau.stats.parabolic) and its EDF (sigmatau.uncertainty.pdev_edf).

Sources and oracles:

* SigmaTheta v3.0 PDEV of the NBS 1000-point frequency set, as printed in allantools'
  test suite (``tests/nbs14/pdev_nbs14.txt`` of https://github.com/aewallin/allantools;
  the values are typed in below).
* The definition of Vernotte, Lenczner, Bourgeois & Rubiola, IEEE TUFFC 63(4) 611 (2016),
  written as a plain O(N·m) loop, in float and in exact rational arithmetic.
* Power-law expectations: white PM and white FM closed forms on discrete samples, and
  their limits, the paper's 3h₂/(2π²τ³) and 3h₀/(5τ).
* The EDF against a dense time-domain quadratic form (ν = tr(C)²/tr(C²)) and Monte Carlo.
"""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest

from sigmatau import mdev
from sigmatau.core.taus import long_factors_expected
from sigmatau.datasets import nbs1000
from sigmatau.errors import DataError, ParameterError, RangeWarning
from sigmatau.generate import power_law_noise
from sigmatau.stats.engine import run
from sigmatau.stats.parabolic import PVAR, pdev
from sigmatau.uncertainty.confidence import EDF_STATISTICS, ONE_SIGMA, deviation_interval
from sigmatau.uncertainty.pdev_edf import M_EXACT, _edf_exact, pdev_edf, pdev_edf_array, pdev_edf_reason

# ------------------------------------------------------------------ plain definitions


def plain_pvar(x: np.ndarray, m: int, tau0: float = 1.0) -> tuple[float, int]:
    """PVAR from the definition (Vernotte et al. 2016, with n = N − 2m terms), loops only."""
    N = len(x)
    if m == 1:
        n = N - 2
        total = 0.0
        for i in range(n):
            d = x[i + 2] - 2.0 * x[i + 1] + x[i]
            total += d * d
        return total / (2.0 * n * tau0**2), n
    n = N - 2 * m
    total = 0.0
    for i in range(n):
        s = 0.0
        for k in range(m):
            s += ((m - 1) / 2.0 - k) * (x[i + k] - x[i + m + k])
        total += s * s
    return 72.0 * total / (n * m**4 * (m * tau0) ** 2), n


def exact_pvar(x: list, m: int) -> Fraction:
    """The same definition in exact rational arithmetic (τ0 = 1)."""
    N = len(x)
    if m == 1:
        n = N - 2
        return sum((x[i + 2] - 2 * x[i + 1] + x[i]) ** 2 for i in range(n)) / (2 * n)
    n = N - 2 * m
    c = [Fraction(m - 1, 2) - k for k in range(m)]
    total = Fraction(0)
    for i in range(n):
        s = sum(c[k] * (x[i + k] - x[i + m + k]) for k in range(m))
        total += s * s
    return 72 * total / (n * m**6)


def term_filter_on_freq(m: int) -> np.ndarray:
    """Weights g of one PVAR term on the frequency samples: S_i = τ0 Σ_a g_a y_{i+a}.

    From the phase weights w (c_k on the first window, −c_k on the second; the second
    difference at m = 1) and x_k = x_0 + τ0 Σ_{a<k} y_a: g_a = Σ_{k>a} w_k.
    """
    if m == 1:
        w = np.array([1.0, -2.0, 1.0])
    else:
        c = (m - 1) / 2.0 - np.arange(m)
        w = np.concatenate((c, -c))
    return np.cumsum(w[::-1])[::-1][1:]


def pvar_scale(m: int) -> float:
    """PVAR = pvar_scale·E[(g·y)²] at τ0 = 1."""
    return 0.5 if m == 1 else 72.0 / m**6


def freq_covariance(alpha: int, size: int) -> np.ndarray:
    """Covariance of ``size`` frequency samples of the generator's discrete process, per unit
    of its driving variance (white phase; white frequency; random-walk frequency from rest)."""
    i = np.arange(size)
    if alpha == 2:  # y = Δx, x white
        return 2.0 * np.eye(size) - np.eye(size, k=1) - np.eye(size, k=-1)
    if alpha == 0:
        return np.eye(size)
    if alpha == -2:  # y_k = Σ_{j≤k} w_j
        return np.minimum.outer(i, i) + 1.0
    raise ValueError(alpha)


def q_level(alpha: int) -> float:
    """Driving variance of power_law_noise at h = 1, τ0 = 1 (its Q_d, for the sequence it cumsums)."""
    return 1.0 / (2.0 * (2.0 * math.pi) ** alpha)


# ------------------------------------------------------------------ SigmaTheta reference

#: SigmaTheta v3.0 PDEV of the NBS 1000-point frequency set (τ0 = 1 s), AF → PDEV, from
#: allantools tests/nbs14/pdev_nbs14.txt.
SIGMATHETA_PDEV = {
    1: 0.29223187810675200, 2: 0.21445233564252639, 4: 0.15618112158618463,
    8: 0.11709745745448434, 16: 0.069029585189839343, 32: 0.049749707730398392,
    64: 0.038947417330713739, 128: 0.030862392741372108, 256: 0.012447414341332683,
    500: 0.00093531187831254377,
}


def sigmatheta_rtol(m: int) -> float:
    """Tolerance against SigmaTheta's printed (17-digit) values.

    The printed digits are not all right: exact rational arithmetic on the same float64
    data (test_nbs14_exact_rational) differs from them by 8e-15 at m = 2 growing to
    1.0e-12 at m = 256 and 9.8e-12 at m = 500. That is the size of the round-off of an
    O(N·m) double-precision sum over the integrated phase (magnitude ~500): at m = 500 the
    single term adds 500 products of ~6e4 that cancel to ~14, so 1e-11 relative is
    expected there. Our values agree with the exact ones to 2e-14, so the tolerance is
    that measured error of the printed values.
    """
    return 1e-12 if m <= 128 else 2e-12 if m <= 256 else 1.5e-11


def test_nbs14_sigmatheta():
    ms = list(SIGMATHETA_PDEV)
    with pytest.warns(RangeWarning, match=r"m > 250"):
        res = pdev(nbs1000(), m=ms, ci=None)
    assert res.m.tolist() == ms
    assert res.n.tolist() == [999] + [1001 - 2 * m for m in ms[1:]]
    for m, dev in zip(ms, res.dev):
        assert dev == pytest.approx(SIGMATHETA_PDEV[m], rel=sigmatheta_rtol(m), abs=0), m
    # the same from the phase (SP1065: x = cumsum of y, x_0 = 0)
    x = np.concatenate(([0.0], np.cumsum(nbs1000())))
    with pytest.warns(RangeWarning):
        res_x = pdev(x, data_type="phase", m=ms, ci=None)
    for m, dev in zip(ms, res_x.dev):
        assert dev == pytest.approx(SIGMATHETA_PDEV[m], rel=sigmatheta_rtol(m), abs=0), m


@pytest.mark.parametrize("m", [1, 2, 16, 500])
def test_nbs14_exact_rational(m):
    y = nbs1000()
    x = [Fraction(0)]
    for v in y.tolist():
        x.append(x[-1] + Fraction(v))
    exact = math.sqrt(exact_pvar(x, m))
    with long_factors_expected():
        ours = float(pdev(y, m=m, ci=None).dev[0])
    assert ours == pytest.approx(exact, rel=2e-14, abs=0)
    # SigmaTheta's printed value is off the exact one by what sigmatheta_rtol allows
    assert abs(SIGMATHETA_PDEV[m] / exact - 1) <= sigmatheta_rtol(m)


def test_docstring_nine_point_set_against_oracle():
    y = np.array([892, 809, 823, 798, 671, 644, 883, 903, 677], dtype=float)
    x = np.concatenate(([0.0], np.cumsum(y)))
    res = pdev(y, m=[1, 2], ci=None)
    for m, var in zip([1, 2], res.var):
        assert var == pytest.approx(plain_pvar(x, m)[0], rel=1e-13)


# ------------------------------------------------------------------ fast kernel vs plain loop

ORACLE_MS = [1, 2, 3, 4, 5, 7, 8, 12, 13, 31, 64, 100]


@pytest.mark.parametrize("kind", ["white_phase", "random_walk_phase", "drifting_freq"])
def test_kernel_matches_plain_definition(kind, rng):
    N = 601
    if kind == "white_phase":
        x = rng.standard_normal(N)
    elif kind == "random_walk_phase":
        x = np.cumsum(rng.standard_normal(N))
    else:  # frequency with a drift and an offset, integrated
        y = 3.0 + 1e-3 * np.arange(N - 1) + rng.standard_normal(N - 1)
        x = np.concatenate(([0.0], np.cumsum(y)))
    rate = 4.0
    tau0 = 1.0 / rate
    xp = x * tau0  # phase in seconds of a 4 Hz record whose frequency steps are Δx
    want = np.array([plain_pvar(xp, m, tau0)[0] for m in ORACLE_MS])
    n_want = [N - 2 if m == 1 else N - 2 * m for m in ORACLE_MS]
    by_phase = pdev(xp, rate=rate, data_type="phase", m=ORACLE_MS, ci=None)
    by_freq = pdev(np.diff(xp) / tau0, rate=rate, data_type="freq", m=ORACLE_MS, ci=None)
    np.testing.assert_allclose(by_phase.var, want, rtol=1e-10, atol=0)
    np.testing.assert_allclose(by_freq.var, want, rtol=1e-10, atol=0)
    assert by_phase.n.tolist() == n_want == by_freq.n.tolist()
    np.testing.assert_allclose(by_phase.taus, np.array(ORACLE_MS) * tau0)


@pytest.mark.parametrize("data_type", ["freq", "phase"])
def test_long_windows_exact_on_integer_data(data_type, rng):
    # On integer frequency samples every moment sum of the kernel is a multiple of 1/4
    # far below 2**53, so its parabolic means are exact; the reference is integer
    # arithmetic straight from the definition (2U_i = Σ_k (k+1)(m−1−k) y_{i+k}), so the
    # only rounding left is in the final sum of squares.
    y = rng.integers(-1000, 1001, size=40_000)
    ms = [2, 37, 1024, 4097]
    data = y if data_type == "freq" else np.concatenate(([0], np.cumsum(y)))
    res = pdev(data.astype(float), data_type=data_type, m=ms, ci=None)
    for m, var, n in zip(ms, res.var, res.n.tolist()):
        k = np.arange(m - 1, dtype=np.int64)
        two_u = np.convolve(y, ((k + 1) * (m - 1 - k))[::-1], mode="valid")
        z = (two_u[m:] - two_u[:-m])[: y.size + 1 - 2 * m]
        assert n == z.size
        total = sum(int(v) * int(v) for v in z)
        assert var == pytest.approx(float(Fraction(72 * total, 4 * n * m**6)), rel=1e-14), m


def test_grids_give_the_same_values(rng):
    # Octave (carried sums), decade and "all" (restarts and unit steps) agree with one another.
    y = rng.standard_normal(3000)
    octave = pdev(y, ci=None)
    every = pdev(y, taus="all", ci=None)
    decade = pdev(y, taus="decade", ci=None)
    for part in (octave, decade):
        idx = np.searchsorted(every.m, part.m)
        np.testing.assert_allclose(part.var, every.var[idx], rtol=1e-12, atol=0)
    x = np.concatenate(([0.0], np.cumsum(y)))
    for m in (9, 250, 511, 750):
        assert every.var[m - 1] == pytest.approx(plain_pvar(x, m)[0], rel=1e-10)


def test_scaling_and_offset(rng):
    y = rng.standard_normal(500)
    base = pdev(y, ci=None).var
    np.testing.assert_allclose(pdev(1e-9 * y + 5e-7, ci=None).var, 1e-18 * base, rtol=1e-10)
    np.testing.assert_allclose(pdev(3e12 * y, ci=None).var, 9e24 * base, rtol=1e-10)
    x = np.cumsum(y)
    shifted = x + 1e3 + 0.25 * np.arange(x.size)  # phase offset and frequency offset
    np.testing.assert_allclose(pdev(shifted, data_type="phase", ci=None).var,
                               pdev(x, data_type="phase", ci=None).var, rtol=1e-9)


@pytest.mark.parametrize("data_type", ["freq", "phase"])
def test_gaps_pool_the_gap_free_runs(data_type, rng):
    # A missing sample splits the record; PVAR is the terms-weighted mean over the runs
    # (core/gaps.py, as MDEV), each run by the plain definition.
    y = rng.standard_normal(400)
    data = y if data_type == "freq" else np.concatenate(([0.0], np.cumsum(y)))
    data[[57, 58, 200]] = np.nan
    res = pdev(data, data_type=data_type, m=[1, 2, 4, 8], ci=None)
    if data_type == "freq":
        runs = [np.concatenate(([0.0], np.cumsum(r))) for r in (data[:57], data[59:200], data[201:])]
    else:
        runs = [data[:57], data[59:200], data[201:]]
    for m, var, n in zip(res.m.tolist(), res.var, res.n):
        parts = [plain_pvar(r, m) for r in runs if r.size >= 2 * m + 1]
        assert n == sum(p[1] for p in parts)
        assert var == pytest.approx(sum(v * k for v, k in parts) / n, rel=1e-10)
    assert res.n_missing == 3


def test_default_grid_and_limits(rng):
    y = rng.standard_normal(1000)
    res = pdev(y, ci=None)
    assert res.m.tolist() == [1, 2, 4, 8, 16, 32, 64, 128]  # m ≤ ⌊1001/4⌋
    assert res.m.max() <= 1001 // 4
    with pytest.raises(ParameterError, match=r"pdev: m=\[501\] outside the range 1\.\.500"):
        pdev(y, m=501, ci=None)
    with pytest.warns(RangeWarning, match="few degrees of freedom"):
        single = pdev(y, m=500, ci=None)
    assert single.n.tolist() == [1]


@pytest.mark.parametrize("bad, error, pattern", [
    ([1.0], DataError, "pdev needs at least 2 frequency samples, got 1"),
    ([], DataError, "data is empty"),
    ([1.0, np.inf, 2.0], DataError, "infinite value"),
])
def test_bad_data(bad, error, pattern):
    with pytest.raises(error, match=pattern):
        pdev(bad)


def test_bad_options():
    y = np.arange(50.0) % 7
    with pytest.raises(ParameterError, match="alpha=-3"):
        pdev(y, alpha=-3)
    with pytest.raises(ParameterError, match="data_type"):
        pdev(y, data_type="rate")
    with pytest.raises(ParameterError, match="ci="):
        pdev(y, ci="bootstrap")


# ------------------------------------------------------------------ power-law expectations


def expected_wpm(m: np.ndarray) -> np.ndarray:
    """E[PVAR] of white phase samples of variance q (per unit q, τ0 = 1): 12(m²−1)/(m³τ²), m ≥ 2;
    AVAR's 3/τ² at m = 1."""
    m = np.asarray(m, dtype=float)
    return np.where(m == 1, 3.0, 12.0 * (m * m - 1.0) / m**5)


def expected_wfm(m: np.ndarray) -> np.ndarray:
    """E[PVAR] of white frequency samples of variance q (per unit q): (6/5)(1 − m⁻⁴)/m, m ≥ 2;
    AVAR's 1 at m = 1."""
    m = np.asarray(m, dtype=float)
    return np.where(m == 1, 1.0, 1.2 * (1.0 - m**-4) / m)


@pytest.mark.parametrize("m", [1, 2, 3, 8, 33])
def test_closed_forms_match_the_term_filter(m):
    # Σ-of-weights expectation from the definition's filter against the closed forms.
    g = term_filter_on_freq(m)
    size = g.size
    for alpha, closed in ((2, expected_wpm), (0, expected_wfm)):
        cov = freq_covariance(alpha, size)
        assert pvar_scale(m) * g @ cov @ g == pytest.approx(float(closed(m)), rel=1e-12)


def test_closed_forms_tend_to_the_papers_constants():
    # Vernotte et al. (2016): PVAR = 3h₂/(2π²τ³) (WPM, white samples of variance
    # h₂/(8π²τ0)) and 3h₀/(5τ) (WFM, white samples of variance h₀/(2τ0)).
    tau0, m = 1.0, 1000
    tau = m * tau0
    assert expected_wpm(m) / (8 * math.pi**2 * tau0) == pytest.approx(3 / (2 * math.pi**2 * tau**3), rel=2e-6)
    assert expected_wfm(m) / (2 * tau0) == pytest.approx(3 / (5 * tau), rel=1e-12)


@pytest.mark.parametrize("alpha", [2, 0])
def test_monte_carlo_mean_matches_expectation(alpha):
    # 200 Kasdin–Walter records of 2049 phase points, h = 1: the mean of PVAR against
    # the closed form, within 4 standard errors of the mean (from the runs' own scatter).
    rng = np.random.default_rng([20261125, alpha + 10])
    ms = [1, 2, 4, 16, 64]
    runs = np.array([run(PVAR, power_law_noise(2049, alpha, data_type="phase", rng=rng), rate=1.0,
                         data_type="phase", taus="octave", m=ms, raw=True).var for _ in range(200)])
    closed = (expected_wpm if alpha == 2 else expected_wfm)(np.array(ms)) * q_level(alpha)
    se = runs.std(axis=0, ddof=1) / math.sqrt(len(runs))
    assert np.all(np.abs(runs.mean(axis=0) - closed) <= 4.0 * se), (runs.mean(axis=0) / closed, se / closed)
    # slopes: τ⁻³ for WPM, τ⁻¹ for WFM (between m = 16 and 64, within 3 % of the exponent)
    slope = math.log(closed[4] / closed[3]) / math.log(4.0)
    assert slope == pytest.approx(-3.0 if alpha == 2 else -1.0, abs=0.03)


# ------------------------------------------------------------------ EDF


def dense_edf(alpha: int, m: int, n_points: int) -> float:
    """ν = tr(C)²/tr(C²), C the covariance of the n PVAR terms built in the time domain."""
    g = term_filter_on_freq(m)
    n = n_points - 2 if m == 1 else n_points - 2 * m
    size = n + g.size - 1
    rows = np.zeros((n, size))
    for i in range(n):
        rows[i, i:i + g.size] = g
    cov = rows @ freq_covariance(alpha, size) @ rows.T
    return float(np.trace(cov) ** 2 / np.sum(cov * cov))


@pytest.mark.parametrize("alpha", [2, 0, -2])
@pytest.mark.parametrize("m", [1, 2, 4, 16, 64])
def test_edf_matches_dense_quadratic_form(alpha, m):
    N = 257 if m < 64 else 300
    assert pdev_edf(alpha, m, N) == pytest.approx(dense_edf(alpha, m, N), rel=1e-9)


@pytest.mark.parametrize("alpha", [2, 1, 0, -1, -2])
def test_edf_above_m_exact_tracks_the_full_computation(alpha):
    # Beyond m = M_EXACT the EDF is taken at M_EXACT with the same n/m: within 1.5 %
    # of the full computation (worst: WPM with 2 … 10 terms), within 0.1 % from n ≥ m.
    for m in (M_EXACT + 1, 200, 512):
        for n in (1, 3, 10, 100, 2 * m, 20 * m):
            full = _edf_exact(alpha, m, n)
            approx = pdev_edf(alpha, m, n + 2 * m)
            assert approx == pytest.approx(full, rel=0.015 if n < m else 1e-3), (m, n)


def test_edf_arguments():
    assert pdev_edf(0, 500, 1001) == 1.0
    assert math.isnan(pdev_edf(0, 501, 1001))
    assert pdev_edf_reason(0, 501, 1001) == "N=1001 phase points is fewer than the 1003 pdev needs at m=501"
    assert pdev_edf_reason(0, 5, 1001) == ""
    with pytest.raises(ParameterError, match=r"alpha=-3 \(FWFM\): PVAR diverges"):
        pdev_edf(-3, 4, 100)
    with pytest.raises(ParameterError, match="m=0"):
        pdev_edf(0, 0, 100)
    with pytest.raises(ParameterError, match="alpha=0.5"):
        pdev_edf(0.5, 1, 100)
    np.testing.assert_array_equal(pdev_edf_array([2, 0], [4, 8], 999),
                                  [pdev_edf(2, 4, 999), pdev_edf(0, 8, 999)])
    # m = 1 is AVAR, n = N − 2 terms y_{i+1} − y_i: independent for RWFM (ν = n), lag-1
    # correlation −½ for WFM (ν = n²/(n + 2(n−1)/4))
    n = 999
    assert pdev_edf(-2, 1, n + 2) == pytest.approx(n, rel=1e-12)
    assert pdev_edf(0, 1, n + 2) == pytest.approx(n * n / (n + (n - 1) / 2), rel=1e-12)


def test_edf_cost_is_bounded():
    # Every τ of a 10^7-point record: no term count or factor makes it expensive.
    import time
    start = time.perf_counter()
    for alpha in (2, -1):
        for m in (1, 3, 64, 1000, 10**6, 4 * 10**6):
            assert pdev_edf(alpha, m, 10**7 + 1) > 1.0
    assert time.perf_counter() - start < 10.0


def nu_mc_and_se(v: np.ndarray) -> tuple[float, float]:
    """ν_MC = 2·mean²/var of the runs and the standard error of ln ν_MC (delta method with the
    sample central moments: Var ln ν ≈ [4V/μ² − 4μ3/(μV) + (μ4 − V²)/V²]/R)."""
    R = v.size
    mu = v.mean()
    c = v - mu
    var = np.sum(c * c) / (R - 1)
    m3, m4 = np.mean(c**3), np.mean(c**4)
    var_log = (4.0 * var / mu**2 - 4.0 * m3 / (mu * var) + (m4 - var**2) / var**2) / R
    return 2.0 * mu**2 / var, math.sqrt(var_log)


def expected_pvar(alpha: int, m: int) -> float:
    """Exact E[PVAR] of the generator's process (h = 1, τ0 = 1), from the term filter."""
    g = term_filter_on_freq(m)
    return pvar_scale(m) * q_level(alpha) * float(g @ freq_covariance(alpha, g.size) @ g)


def monte_carlo(alpha: int, runs: int, ms: list, seed: int) -> np.ndarray:
    rng = np.random.default_rng([seed, alpha + 10])
    return np.array([run(PVAR, power_law_noise(2049, alpha, data_type="phase", rng=rng), rate=1.0,
                         data_type="phase", taus="octave", m=ms, raw=True).var for _ in range(runs)])


def check_edf_and_coverage(alpha: int, runs: int, ms: list, seed: int) -> None:
    """ν_MC against pdev_edf within 4 SE of ln ν; coverage of the 68.3 % χ² interval within
    3 binomial standard deviations of 0.683 (the EDF is exact, so nominal is expected)."""
    v = monte_carlo(alpha, runs, ms, seed)
    for j, m in enumerate(ms):
        nu = pdev_edf(alpha, m, 2049)
        nu_mc, se = nu_mc_and_se(v[:, j])
        assert abs(math.log(nu_mc / nu)) <= 4.0 * se, (alpha, m, nu_mc, nu, se)
        truth = math.sqrt(expected_pvar(alpha, m))
        low, high = deviation_interval(np.sqrt(v[:, j]), np.full(runs, nu), ONE_SIGMA)
        cover = float(np.mean((low <= truth) & (truth <= high)))
        band = 3.0 * math.sqrt(ONE_SIGMA * (1 - ONE_SIGMA) / runs)
        assert abs(cover - ONE_SIGMA) <= band, (alpha, m, cover)


@pytest.mark.parametrize("alpha", [2, 0, -2])
def test_edf_monte_carlo(alpha):
    # 400 records of 2048 samples per noise type (coverage band ±7.0 points).
    check_edf_and_coverage(alpha, 400, [4, 16, 64], seed=463917)


@pytest.mark.slow
@pytest.mark.parametrize("alpha", [2, 0, -2])
def test_edf_monte_carlo_large(alpha):
    # 4000 records per noise type (coverage band ±2.2 points, ln ν to ±9 %): about 4 s each.
    check_edf_and_coverage(alpha, 4000, [4, 16, 64], seed=905113)


# ------------------------------------------------------------------ noise type and intervals


@pytest.mark.parametrize("alpha", [2, 1, 0, -1, -2])
def test_identified_noise_type(alpha):
    # pdev identifies α as MDEV does (same B1/R(n)/lag-1 rules, family "modified"), so
    # it must give MDEV's α on the same record; and on simulated noise, where lag-1
    # applies (⌊N/m⌋ ≥ 30, m ≤ 256), within one of the truth and exactly right at
    # most factors (lag-1 misreads a flicker type by one now and then).
    rng = np.random.default_rng([5150, alpha + 10])
    y = power_law_noise(8192, alpha, data_type="freq", rng=rng)
    res = pdev(y)
    ref = mdev(y)
    np.testing.assert_array_equal(res.m, ref.m)
    np.testing.assert_array_equal(res.alpha, ref.alpha)
    near = res.alpha[res.m <= 256]
    assert np.all(np.abs(near - alpha) <= 1)
    assert np.mean(near == alpha) >= 2 / 3


def test_intervals_when_wired_into_confidence():
    if "pdev" not in EDF_STATISTICS:
        pytest.skip("pdev is not yet in confidence.EDF_STATISTICS (wiring given in the H1 report)")
    y = power_law_noise(4096, 0, rng=np.random.default_rng(77))
    res = pdev(y, alpha=0)
    np.testing.assert_allclose(res.edf, pdev_edf_array(0, res.m, res.n_points), rtol=1e-12)
    low, high = deviation_interval(res.dev, res.edf, ONE_SIGMA)
    np.testing.assert_allclose(res.ci_low, low)
    np.testing.assert_allclose(res.ci_high, high)


@pytest.mark.parametrize("alpha", [2, 0, -2])
def test_coverage_on_the_identified_path(alpha):
    # What users get: pdev(y) with the noise type identified at each τ (no alpha given).
    # 400 records of 2048 samples per type; the 68.3 % interval must cover the exact
    # expectation within 3 binomial standard deviations (±7.0 points).
    runs, ms = 400, [4, 16, 64]
    rng = np.random.default_rng([20261125, alpha + 10])
    cover = np.zeros(len(ms))
    for _ in range(runs):
        res = pdev(power_law_noise(2049, alpha, data_type="phase", rng=rng), data_type="phase", m=ms)
        truth = np.sqrt([expected_pvar(alpha, m) for m in ms])
        cover += (res.ci_low <= truth) & (truth <= res.ci_high)
    band = 3.0 * math.sqrt(ONE_SIGMA * (1 - ONE_SIGMA) / runs)
    for m, c in zip(ms, cover / runs):
        assert abs(c - ONE_SIGMA) <= band, (alpha, m, c)
