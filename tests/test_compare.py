"""Groslambert covariance and cornered hats (sigmatau.compare).

Sources of the expected values:
- SigmaTheta v3.0 GCoDev tables (allantools examples, in /work/shared/refdata; see its README for how
  the data were made: legacy ``numpy.random.seed(42)``, ``randn(100000)`` three times scaled 1, 5, 10);
- plain loops written here straight from the definitions;
- the exact three-cornered-hat arithmetic of the issue (pairwise 1.00e-11, 1.28e-11, 1.17e-11);
- simulated independent clocks whose Allan variance is known exactly (white FM: AVAR(m) = σ_y²/m).
"""

from __future__ import annotations

import math
import os

import numpy as np
import pytest

import sigmatau
from sigmatau.compare import classical_hat, cornered_hat, gcodev, three_cornered_hat
from sigmatau.errors import DataError, ParameterError, RangeWarning
from sigmatau.uncertainty.confidence import ONE_SIGMA, edf

REFDIR = "/work/shared/refdata/allantools/examples"
STATS = ("adev", "oadev", "mdev", "hdev", "ohdev")


# ---------------------------------------------------------------- GCoDev against SigmaTheta

def _sigmatheta_pairs():
    # RandomState(42) is the legacy generator behind numpy.random.seed(42): same stream, no global state.
    rs = np.random.RandomState(42)
    a, b, c = rs.randn(100000), 5 * rs.randn(100000), 10 * rs.randn(100000)
    return {"AB": a - b, "BC": b - c, "CA": c - a}


@pytest.mark.parametrize("first,second", [("BC", "AB"), ("BC", "CA"), ("CA", "AB")])
def test_gcodev_matches_sigmatheta(first, second):
    path = os.path.join(REFDIR, f"gcodev_{first}_{second}.txt")
    if not os.path.exists(path):
        pytest.skip(f"{path} absent (shared reference data)")
    table = np.loadtxt(path)
    pairs = _sigmatheta_pairs()
    # The table's last factor (32768) is past N/4: computed as requested, with the warning.
    with pytest.warns(RangeWarning, match="few degrees of freedom"):
        r = gcodev(pairs[first], pairs[second], m=table[:, 0].astype(int), rate=1.0, data_type="phase")
    assert np.array_equal(r.m, table[:, 0])
    assert np.all(np.sign(r.dev) == np.sign(table[:, 1]))  # SigmaTheta keeps the sign (negative here)
    # 17 digits printed; the sums over 1e5 products agree to about 1e-12 (measured 1.3e-12 worst).
    np.testing.assert_allclose(r.dev, table[:, 1], rtol=1e-10, atol=0)


# ---------------------------------------------------------------- plain oracle

def _oracle_cov(xa, xb, m, statistic, tau0):
    """Covariance straight from the definitions, one term at a time."""
    n_pts = len(xa)
    tau = m * tau0

    def d2(x, i, step):
        return x[i + 2 * step] - 2 * x[i + step] + x[i]

    def d3(x, i, step):
        return x[i + 3 * step] - 3 * x[i + 2 * step] + 3 * x[i + step] - x[i]

    total, count = 0.0, 0
    if statistic == "oadev":
        for i in range(n_pts - 2 * m):
            total += d2(xa, i, m) * d2(xb, i, m)
            count += 1
        return total / (2 * tau**2 * count)
    if statistic == "adev":
        for i in range(0, n_pts - 2 * m, m):
            total += d2(xa, i, m) * d2(xb, i, m)
            count += 1
        return total / (2 * tau**2 * count)
    if statistic == "mdev":
        for j in range(n_pts - 3 * m + 1):
            sa = sum(d2(xa, i, m) for i in range(j, j + m))
            sb = sum(d2(xb, i, m) for i in range(j, j + m))
            total += sa * sb
            count += 1
        return total / (2 * m**2 * tau**2 * count)
    if statistic == "hdev":
        for i in range(0, n_pts - 3 * m, m):
            total += d3(xa, i, m) * d3(xb, i, m)
            count += 1
        return total / (6 * tau**2 * count)
    for i in range(n_pts - 3 * m):
        total += d3(xa, i, m) * d3(xb, i, m)
        count += 1
    return total / (6 * tau**2 * count)


@pytest.mark.parametrize("statistic", STATS)
def test_gcodev_matches_plain_loops(statistic, rng):
    n, tau0 = 61, 0.25
    shared = np.cumsum(rng.standard_normal(n))
    xa = shared + rng.standard_normal(n)
    xb = -shared + 3.0 * rng.standard_normal(n) + np.arange(n) * 0.7  # a frequency offset too
    ms = [1, 2, 3, 5]
    r = gcodev(xa, xb, rate=1 / tau0, m=ms, statistic=statistic)
    expected = [_oracle_cov(xa, xb, m, statistic, tau0) for m in ms]
    np.testing.assert_allclose(r.cov, expected, rtol=1e-10)
    np.testing.assert_allclose(r.tau, np.array(ms) * tau0)
    np.testing.assert_allclose(r.dev, np.sign(r.cov) * np.sqrt(np.abs(r.cov)))


@pytest.mark.parametrize("statistic", STATS)
def test_gcodev_frequency_input_is_the_integrated_phase(statistic, rng):
    ya, yb = rng.standard_normal(80), rng.standard_normal(80)
    xa = np.concatenate(([0.0], np.cumsum(ya))) / 10.0
    xb = np.concatenate(([0.0], np.cumsum(yb))) / 10.0
    ms = [1, 2, 4]
    f = gcodev(ya, yb, rate=10.0, data_type="freq", m=ms, statistic=statistic)
    expected = [_oracle_cov(xa, xb, m, statistic, 0.1) for m in ms]
    np.testing.assert_allclose(f.cov, expected, rtol=1e-10)


@pytest.mark.parametrize("statistic", STATS)
def test_gcodev_of_a_series_with_itself_is_its_variance(statistic, rng):
    x = rng.standard_normal(500)
    r = gcodev(x, x, statistic=statistic, m=[1, 3, 10])
    ref = getattr(sigmatau, statistic)(x, data_type="phase", m=[1, 3, 10])
    np.testing.assert_allclose(r.cov, ref.dev**2, rtol=1e-12)
    np.testing.assert_array_equal(r.n, ref.n)


def test_gcodev_scale_invariance(rng):
    a, b = rng.standard_normal(300), rng.standard_normal(300)
    r1 = gcodev(a, b, m=[1, 4])
    r2 = gcodev(a * 1e-9, b * 1e12, m=[1, 4])
    np.testing.assert_allclose(r2.cov, r1.cov * 1e3, rtol=1e-12)


# ---------------------------------------------------------------- classical hat arithmetic

def test_three_cornered_hat_exact_arithmetic():
    # Issue 15: pairwise 1.00e-11 (AB), 1.28e-11 (BC), 1.17e-11 (CA) give 6.0e-12, 8.0e-12, 1.0e-11.
    v = classical_hat({("A", "B"): 1.00e-11**2, ("B", "C"): 1.28e-11**2, ("C", "A"): 1.17e-11**2})
    dev = {k: math.sqrt(x) for k, x in v.items()}
    # Inputs are given to 3 digits; the answer is printed to 2.
    assert f"{dev['A']:.1e}" == "6.0e-12"
    assert f"{dev['B']:.1e}" == "8.0e-12"
    assert f"{dev['C']:.1e}" == "1.0e-11"
    # And from the exact pair variances the formula is exact.
    w = classical_hat({("B", "A"): 100e-24, ("C", "B"): 164e-24, ("A", "C"): 136e-24})
    np.testing.assert_allclose([w["A"], w["B"], w["C"]], [36e-24, 64e-24, 100e-24], rtol=1e-14)


def test_four_cornered_classical_is_least_squares():
    truth = {"A": 1.0, "B": 2.0, "C": 3.0, "D": 4.0}
    pairs = {(p, q): truth[p] + truth[q] for p, q in [("A", "B"), ("A", "C"), ("A", "D"), ("B", "C"),
                                                      ("B", "D"), ("C", "D")]}
    pairs[("A", "B")] += 0.6  # an inconsistent pair: least squares shares it out
    v = classical_hat(pairs)
    design = np.array([[1, 1, 0, 0], [1, 0, 1, 0], [1, 0, 0, 1], [0, 1, 1, 0], [0, 1, 0, 1], [0, 0, 1, 1]], float)
    expected = np.linalg.lstsq(design, np.array(list(pairs.values())), rcond=None)[0]
    np.testing.assert_allclose([v[k] for k in "ABCD"], expected, rtol=1e-12)


def test_hat_classical_is_the_textbook_formula_and_the_groslambert_covariance(rng):
    n = 3000
    a, b, c = rng.standard_normal(n), 2 * rng.standard_normal(n), 3 * rng.standard_normal(n)
    ab, bc, ca = a - b, b - c, c - a
    ms = [1, 4, 16]
    r = three_cornered_hat(ab, bc, ca, m=ms, alpha=2)
    var = {k: sigmatau.oadev(s, data_type="phase", m=ms).dev ** 2 for k, s in (("ab", ab), ("bc", bc), ("ca", ca))}
    np.testing.assert_allclose(r.device("A").classical_var, 0.5 * (var["ab"] + var["ca"] - var["bc"]), rtol=1e-9)
    np.testing.assert_allclose(r.device("B").classical_var, 0.5 * (var["ab"] + var["bc"] - var["ca"]), rtol=1e-9)
    np.testing.assert_allclose(r.device("C").classical_var, 0.5 * (var["bc"] + var["ca"] - var["ab"]), rtol=1e-9)
    # The shared device of two pairs is minus their covariance.
    np.testing.assert_allclose(r.device("A").classical_var, -gcodev(ab, ca, m=ms).cov, rtol=1e-9)
    np.testing.assert_allclose(r.device("B").classical_var, -gcodev(ab, bc, m=ms).cov, rtol=1e-9)
    # Records and pair series give the same answer.
    rec = cornered_hat({"A": a, "B": b, "C": c}, m=ms, alpha=2)
    np.testing.assert_allclose(rec.classical_var, r.classical_var, rtol=1e-9)
    np.testing.assert_allclose(rec.high, r.high, rtol=1e-9)


def test_common_reference_cancels(rng):
    n = 4000
    own = {k: s * rng.standard_normal(n) for k, s in zip("ABCD", (1.0, 2.0, 1.5, 3.0))}
    table = 1e3 * np.cumsum(rng.standard_normal(n))  # a huge common motion, seen by every unit
    r0 = cornered_hat(own, data_type="freq", m=[2, 8], alpha=0)
    r1 = cornered_hat({k: v + table for k, v in own.items()}, data_type="freq", m=[2, 8], alpha=0)
    np.testing.assert_allclose(r1.classical_var, r0.classical_var, rtol=1e-6)
    np.testing.assert_allclose(r1.high, r0.high, rtol=1e-6)


def test_result_access(rng):
    rec = {k: s * rng.standard_normal(2000) for k, s in zip("XYZ", (1.0, 2.0, 3.0))}
    r = cornered_hat(rec, data_type="freq", m=[1, 10], alpha=0)
    assert r.names == ("X", "Y", "Z") and r.classical_var.shape == (2, 3)
    d = r.device("Y")
    np.testing.assert_array_equal(d.dev, r.dev[:, 1])
    rows = r.to_rows()
    assert len(rows) == 6 and rows[4]["device"] == "Y" and rows[4]["m"] == 10
    assert np.all(r.low <= r.dev) and np.all(r.dev <= r.high) and np.all(r.low >= 0)
    with pytest.raises(ParameterError, match="not one of the devices"):
        r.device("Q")


# ---------------------------------------------------------------- simulated clocks

def _clocks(levels, n, rng):
    """White-FM clocks with σ_y = level: OAVAR(m) = level²/m exactly."""
    return {k: sigmatau.power_law_noise(n, "wfm", h=2.0 * s**2, rng=rng) for k, s in zip("ABCDEF", levels)}


def _truth(levels, ms):
    return np.asarray(levels)[None, :] / np.sqrt(np.asarray(ms, float))[:, None]


@pytest.mark.parametrize("levels", [(1.0, 2.0, 3.0), (1.0, 10.0, 10.0), (2.0, 1.0, 3.0, 4.0), (1.0, 10.0, 10.0, 10.0)])
def test_estimates_consistent_with_truth(levels, rng):
    ms = [4, 32, 128]
    r = cornered_hat(_clocks(levels, 8000, rng), data_type="freq", m=ms, alpha=0, confidence=0.9999)
    truth = _truth(levels, ms)
    # 0.9999 intervals: all 9 or 12 must hold the truth unless something is wrong (P(fail) ≈ 1e-3).
    assert np.all(r.low <= truth) and np.all(truth <= r.high)
    # Loud clocks: the classical estimate is within 4 times 2·σ²·sqrt(2/ν), an upper bound of its standard
    # deviation here (each pair variance has relative sd sqrt(2/ν) and the loud pairs are ≤ 2σ²).
    loud = np.asarray(levels) >= 2.0
    sd = truth**2 * np.sqrt(2.0 / r.edf)[:, None] * 2.0
    assert np.all(np.abs(r.classical_var - truth**2)[:, loud] <= 4.0 * sd[:, loud])


def _coverage(levels, ms, trials, seed, n=2000, alpha=0):
    g = np.random.default_rng(seed)
    hit = np.zeros((len(ms), len(levels)))
    negative = np.zeros_like(hit)
    for _ in range(trials):
        r = cornered_hat(_clocks(levels, n, g), data_type="freq", m=ms, alpha=alpha)
        truth = _truth(levels, ms)
        hit += (r.low <= truth) & (truth <= r.high)
        negative += r.classical_var < 0
    return hit / trials, negative / trials


def _assert_nominal(cov, trials, p=ONE_SIGMA):
    # Each cell is binomial(trials, p) under a correct interval: 3 binomial sigmas either side.
    tol = 3.0 * math.sqrt(p * (1 - p) / trials)
    assert np.all(np.abs(cov - p) <= tol), (cov, p, tol)


@pytest.mark.slow
def test_coverage_quiet_clock_small():
    # 1 : 10 : 10 in deviation at m = 64 (ν ≈ 44.7); the quiet clock's classical estimate is negative
    # about half the time, yet its interval must cover at the nominal rate.
    cov, negative = _coverage((1.0, 10.0, 10.0), [64], trials=120, seed=20261125)
    assert negative[0, 0] > 0.3
    _assert_nominal(cov, 120)


@pytest.mark.slow
@pytest.mark.parametrize("levels", [(1.0, 2.0, 3.0), (1.0, 10.0, 10.0)])
def test_coverage_on_the_identified_path(levels):
    # What users get: no alpha, the noise type identified at each τ on the first difference.
    cov, _ = _coverage(levels, [32, 128], trials=250, seed=20261126, alpha=None)
    _assert_nominal(cov, 250)


@pytest.mark.slow
@pytest.mark.parametrize("levels", [(1.0, 2.0, 3.0), (1.0, 10.0, 10.0)])
def test_coverage_three_clocks(levels):
    cov, _ = _coverage(levels, [32, 128], trials=250, seed=151)
    _assert_nominal(cov, 250)


@pytest.mark.slow
@pytest.mark.parametrize("levels", [(2.0, 1.0, 3.0, 4.0), (1.0, 10.0, 10.0, 10.0)])
def test_coverage_four_clocks(levels):
    cov, _ = _coverage(levels, [128], trials=250, seed=152)
    _assert_nominal(cov, 250)


# ---------------------------------------------------------------- bad input

def _one_line(excinfo):
    assert "\n" not in str(excinfo.value)


def test_bad_input_messages(rng):
    a, b, c = rng.standard_normal(100), rng.standard_normal(100), rng.standard_normal(100)
    cases = [
        (DataError, "same length", lambda: gcodev(a, b[:-1])),
        (DataError, "non-finite", lambda: gcodev(np.where(np.arange(100) == 5, np.nan, a), b)),
        (ParameterError, "statistic", lambda: gcodev(a, b, statistic="totdev")),
        (ParameterError, "rate", lambda: gcodev(a, b, rate=-1)),
        (DataError, "same length", lambda: cornered_hat({"A": a, "B": b, "C": c[:-3]})),
        (DataError, "same length", lambda: three_cornered_hat(a, b, c[:-3])),
        (DataError, "at least 3 devices", lambda: cornered_hat({"A": a, "B": b})),
        (DataError, "at least 3 devices", lambda: cornered_hat({("A", "B"): a})),
        (DataError, "do not connect", lambda: cornered_hat({("A", "B"): a, ("C", "D"): b})),
        (DataError, "non-finite", lambda: cornered_hat({"A": a, "B": np.where(np.arange(100) == 7, np.nan, b),
                                                        "C": c})),
        (ParameterError, "mixes", lambda: cornered_hat({"A": a, ("B", "C"): b, "D": c})),
        (ParameterError, "mapping", lambda: cornered_hat([a, b, c])),
        (ParameterError, "confidence", lambda: cornered_hat({"A": a, "B": b, "C": c}, confidence=1.5)),
        (ParameterError, "alpha", lambda: cornered_hat({"A": a, "B": b, "C": c}, alpha=7)),
        (ParameterError, "itself", lambda: cornered_hat({("A", "A"): a, ("B", "C"): b})),
        (ParameterError, "given twice", lambda: cornered_hat({("A", "B"): a, ("B", "A"): b, ("B", "C"): c})),
        (ParameterError, "three distinct", lambda: three_cornered_hat(a, b, c, names=("A", "A", "C"))),
        (DataError, "missing", lambda: classical_hat({("A", "B"): 1.0, ("B", "C"): 1.0, ("C", "D"): 1.0})),
        (DataError, "needs at least", lambda: gcodev([1.0, 2.0], [1.0, 3.0])),
    ]
    for error, text, call in cases:
        with pytest.raises(error, match=text) as excinfo:
            call()
        _one_line(excinfo)


def test_pairs_need_only_connect_the_devices(rng):
    n = 3000
    rec = {k: s * rng.standard_normal(n) for k, s in zip("ABCD", (1.0, 2.0, 3.0, 1.5))}
    chain = {("A", "B"): rec["A"] - rec["B"], ("C", "B"): rec["C"] - rec["B"], ("D", "C"): rec["D"] - rec["C"]}
    r_pairs = cornered_hat(chain, m=[1, 8], alpha=2)
    r_rec = cornered_hat(rec, m=[1, 8], alpha=2)
    assert r_pairs.names == ("A", "B", "C", "D")
    np.testing.assert_allclose(r_pairs.classical_var, r_rec.classical_var, rtol=1e-9)


@pytest.mark.parametrize("statistic", STATS)
def test_noise_identified_when_alpha_not_given(statistic, rng):
    rec = _clocks((1.0, 2.0, 3.0), 4000, rng)
    r = cornered_hat(rec, data_type="freq", statistic=statistic, m=[1, 2, 4, 8])
    assert np.all(r.alpha == 0)  # white FM, identified by lag-1 autocorrelation at these factors
    assert np.all(np.isfinite(r.edf)) and np.all(r.high > r.low)
    expected = [edf(statistic, 0, int(m), 4001) for m in r.m]
    np.testing.assert_allclose(r.edf, expected)


def test_quiet_clock_gets_an_upper_limit():
    # A clock 100 times quieter in variance, at m = 128 (ν ≈ 21): the classical estimate is negative here.
    g = np.random.default_rng(7)
    for _ in range(20):
        r = cornered_hat(_clocks((1.0, 10.0, 10.0), 2000, g), data_type="freq", m=[128], alpha=0)
        if r.classical_var[0, 0] < 0:
            break
    else:
        pytest.fail("no negative classical estimate in 20 draws (expected about half)")
    assert r.low[0, 0] == 0.0 and r.high[0, 0] > 0.0 and r.dev[0, 0] >= 0.0
    assert r.classical_dev[0, 0] < 0  # the signed estimate is kept beside it


@pytest.mark.slow
def test_coverage_flicker_fm_quiet_clock():
    # Flicker FM (α = −1) clocks 1 : 10 : 10; truth = the exact OAVAR expectation of the discrete noise.
    from sigmatau.noise.expected import expected_oavar_discrete
    levels, ms, trials = (1.0, 10.0, 10.0), [16, 64], 250
    truth = np.sqrt([[expected_oavar_discrete("ffm", s**2, [m])[0] for s in levels] for m in ms])
    g = np.random.default_rng(153)
    hit = np.zeros_like(truth)
    for _ in range(trials):
        rec = {k: sigmatau.power_law_noise(4000, "ffm", h=s**2, rng=g) for k, s in zip("ABC", levels)}
        r = cornered_hat(rec, data_type="freq", m=ms, alpha=-1)
        hit += (r.low <= truth) & (truth <= r.high)
    _assert_nominal(hit / trials, trials)


def test_the_same_record_twice_is_refused_in_one_line():
    x = np.random.default_rng(4).standard_normal(500)
    y = np.random.default_rng(5).standard_normal(500)
    with pytest.raises(DataError, match=r"records 'A' and 'C' are the same"):
        cornered_hat({"A": x, "B": y, "C": x + 3.0}, data_type="freq")
