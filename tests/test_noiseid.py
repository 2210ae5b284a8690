"""Noise identification (sigmatau.noiseid) against its sources.

Sources and what each test ties to:

* numerics.md §5.2 — lag-1 autocorrelation method: exact ρ1 identities, the
  Monte-Carlo fractions of its table (N = 16384) and, §7.4, the NBS values.
* numerics.md §5.3 — B1: closed forms and Monte-Carlo means (Nb = 16).
* numerics.md §5.4 — R(n): WPM 1/n, the FPM formula and the large-n limits.
* numerics.md §3/§5.5 — TheoBR κ thresholds (0.4/0.6/1.0/1.71/2.24).
* numerics.md §5.1 and dt0064.md — the design tip's slope table.
* numerics.md §6.1/§6.3 — Kasdin–Walter noise with a known h_α, and the
  response constants the power-law fit uses.
* tests/data/allantools — the Alpha column of Stable32 tables, on every row (lag-1
  and B1 rows, octave, decade and all-τ grids).

Monte-Carlo checks are statistical: many runs, and a binomial bound derived from the
method's published or documented error rate, never a list of seeds that happen to pass.

Noise is generated here by the Kasdin–Walter fractional-difference filter
(numerics.md §6.1) so that every level h_α is known exactly.
"""

from __future__ import annotations

import dataclasses
import math
import warnings

import numpy as np
import pytest

import sigmatau
from sigmatau.datasets import nbs1000
from sigmatau.errors import DataError, ParameterError
from sigmatau.noiseid import (
    NOISE_NAMES,
    InsufficientDataError,
    b1_expected,
    b1_min_averages,
    b1_noise_id,
    b1_ratio,
    fit_power_law,
    identify,
    lag1_acf_noise_id,
    local_slopes,
    power_law_variance,
    rn_expected,
    rn_ratio,
    theo_noise_id,
)

import refdata

# --------------------------------------------------------------------- generator


def kasdin(n: int, beta: float, rng: np.random.Generator, q: float = 1.0) -> np.ndarray:
    """Kasdin–Walter series with discrete PSD ∝ |2 sin(ω/2)|^β (numerics.md §6.1).

    ``h_0 = 1, h_k = h_{k−1}(k − 1 − β/2)/k`` convolved with white N(0, q) noise,
    linearly (FFT with zero padding to ≥ 2n), starting at rest.
    """
    k = np.arange(1, n)
    h = np.concatenate(([1.0], np.cumprod((k - 1 - beta / 2.0) / k)))
    w = rng.normal(0.0, math.sqrt(q), n)
    nfft = 1 << int(math.ceil(math.log2(2 * n)))
    return np.fft.irfft(np.fft.rfft(h, nfft) * np.fft.rfft(w, nfft), nfft)[:n]


def noise(alpha: int, n: int, rng: np.random.Generator, data_type: str = "freq") -> np.ndarray:
    """n samples of power-law noise S_y ∝ f^α as phase (β = α − 2) or frequency (β = α)."""
    if data_type == "phase":
        return kasdin(n, alpha - 2, rng)
    if alpha >= 1:  # frequency of WPM/FPM: difference of the phase series
        return np.diff(kasdin(n + 1, alpha - 2, rng))
    return kasdin(n, alpha, rng)


# ------------------------------------------------ lag-1 ACF: exact identities (§5.2)


def test_lag1_white_has_zero_rho1_and_differenced_white_minus_half():
    rng = np.random.default_rng(11)
    w = rng.standard_normal(100_000)
    tol = 4.0 / math.sqrt(w.size)  # SD of r1 is ≈ 1/√n
    white = lag1_acf_noise_id(w, 1)  # frequency data, d = 0
    assert white.d == 0 and abs(white.rho1) < tol and white.alpha == 0
    diffed = lag1_acf_noise_id(np.diff(w), 1)  # first difference of white: ρ1 = −1/2
    assert diffed.d == 0 and abs(diffed.rho1 + 0.5) < tol and diffed.alpha == 2
    # as phase: white phase is WPM (θ = 1), a random walk of it WFM after one difference
    assert lag1_acf_noise_id(w, 1, data_type="phase").alpha == 2
    walk = lag1_acf_noise_id(np.cumsum(w), 1, data_type="phase")
    assert walk.d == 1 and abs(walk.rho1) < tol and walk.alpha == 0


def test_lag1_rho1_matches_fractional_noise_formula():
    # ρ1 = −α_z/(2 + α_z) for stationary discrete power-law noise, α_z = β here
    rng = np.random.default_rng(12)
    for beta in (1.0, 0.5, -0.5):
        z = kasdin(200_000, beta, rng)
        r = lag1_acf_noise_id(z, 1, dmax=0)
        assert r.rho1 == pytest.approx(-beta / (2.0 + beta), abs=0.01)


def test_lag1_nbs_reference_values():
    # numerics.md §7.4: NBS phase = cumulative sum of the NBS frequency set from 0
    x = sigmatau.frequency_to_phase(nbs1000())
    r1 = lag1_acf_noise_id(x, 1, data_type="phase")
    assert (r1.d, r1.alpha) == (1, 0)
    assert r1.rho1 == pytest.approx(-0.0267, abs=5e-5)
    assert r1.alpha_estimate == pytest.approx(0.055, abs=5e-4)
    r10 = lag1_acf_noise_id(x, 10, data_type="phase")
    assert r10.alpha == 0 and r10.alpha_estimate == pytest.approx(0.36, abs=5e-3)
    # detrending (quadratic off the phase) changes nothing visible here
    det = lag1_acf_noise_id(x, 1, data_type="phase", detrend=True)
    assert det.alpha == 0 and det.rho1 == pytest.approx(-0.0267, abs=1e-4)
    # m = 100 leaves 11 points: the method refuses (numerics: it would say α = 4)
    with pytest.raises(InsufficientDataError):
        lag1_acf_noise_id(x, 100, data_type="phase")


# -------------------------------------------- lag-1 ACF: Monte-Carlo table (§5.2)

# numerics.md §5.2 publishes the fraction of correct identifications in 50 runs of
# N = 16384 points (independent implementation); per case the lowest value of its range:
#
#   data, α              m = 1   m = 8
#   phase, WPM            1.00    1.00
#   phase, FPM            1.00    0.72
#   phase, WFM            1.00    1.00
#   phase, FFM            1.00    0.80
#   phase, RWFM           1.00    1.00
#   freq,  FWFM (dmax 3)  1.00    0.00   (α̂ ≈ −3.9 rounds to RRFM, numerics §8 item 3)
#   freq,  RRFM (dmax 3)  1.00    0.00   (α̂ ≈ −5.3 rounds to −5)
#
# The test runs MC_RUNS series per case and asks whether our rate is consistent with
# the published one: from k published successes of 50 the rate is at least the 99 %
# Clopper–Pearson lower bound p_lo (0.912 for 50/50, 0.55 for 36/50); our count X of
# MC_RUNS must not fall below the 0.1 % quantile of Binomial(MC_RUNS, p_lo). For the
# documented misidentifications (0/50 correct) X must not exceed the 99.9 % quantile of
# Binomial(MC_RUNS, p_hi), p_hi = 0.088 the 99 % upper bound. With 14 comparisons a
# correct method fails one by chance with probability below 1.4 %.
# Measured (200 runs; correct at m = 1 and m = 8 of 200, mean α̂ at m = 8): WPM 200, 200,
# 2.00; FPM 200, 153, 1.43; WFM 200, 200, −0.00; FFM 200, 172, −1.43; RWFM 200, 200,
# −2.39; FWFM 200, 0, −3.91; RRFM 200, 1, −5.52.
# At m = 8 identify() with the Hadamard family clips RRFM's −5 to −4 and so names it.
MC_RUNS = 200
MC_N = 16384
MC_PUBLISHED_RUNS = 50
MC_ALPHA = 1e-3
MC_CASES = [  # α, data type, dmax, published correct of 50 at m = 1 and at m = 8
    (2, "phase", 2, 50, 50),
    (1, "phase", 2, 50, 36),
    (0, "phase", 2, 50, 50),
    (-1, "phase", 2, 50, 40),
    (-2, "phase", 2, 50, 50),
    (-3, "freq", 3, 50, 0),
    (-4, "freq", 3, 50, 0),
]


def _binomial_bounds(published: int, runs: int) -> tuple[int, int]:
    """Least and greatest count of ``runs`` consistent with ``published`` of 50 (see above)."""
    from scipy import stats

    n = MC_PUBLISHED_RUNS
    p_lo = stats.beta.ppf(0.01, published, n - published + 1) if published > 0 else 0.0
    p_hi = stats.beta.ppf(0.99, published + 1, n - published) if published < n else 1.0
    least = int(stats.binom.ppf(MC_ALPHA, runs, p_lo))
    most = int(stats.binom.isf(MC_ALPHA, runs, p_hi)) if p_hi < 1.0 else runs
    return least, most


@pytest.fixture(scope="module")
def mc_lag1():
    out = {}
    for alpha, dtype, dmax, _, _ in MC_CASES:
        rng = np.random.default_rng([20261124, alpha + 10])
        runs = {1: [], 8: []}
        hadamard_rrfm = []
        for _ in range(MC_RUNS):
            z = noise(alpha, MC_N, rng, dtype)
            for m in (1, 8):
                runs[m].append(lag1_acf_noise_id(z, m, data_type=dtype, dmax=dmax))
            if alpha == -4:
                hadamard_rrfm.append(identify(z, [8], data_type=dtype, family="hadamard").alpha[0])
        out[alpha] = (runs, hadamard_rrfm)
    return out


def test_binomial_bounds_of_the_published_table():
    # Closed forms of the 99 % Clopper–Pearson bounds at the ends: 50/50 gives
    # p_lo = 0.01**(1/50) = 0.912, 0/50 gives p_hi = 1 − 0.01**(1/50) = 0.088; the
    # count bounds are the 0.1 % / 99.9 % binomial quantiles at those rates.
    from scipy import stats

    p_lo = 0.01 ** (1 / 50)
    least, most = _binomial_bounds(50, MC_RUNS)
    assert most == MC_RUNS
    assert stats.binom.cdf(least - 1, MC_RUNS, p_lo) <= MC_ALPHA < stats.binom.cdf(least, MC_RUNS, p_lo)
    _, most = _binomial_bounds(0, MC_RUNS)
    assert stats.binom.sf(most, MC_RUNS, 1 - p_lo) <= MC_ALPHA < stats.binom.sf(most - 1, MC_RUNS, 1 - p_lo)


@pytest.mark.slow
@pytest.mark.parametrize("alpha, dtype, dmax, published_m1, published_m8", MC_CASES)
def test_lag1_identification_rate_binomial(mc_lag1, alpha, dtype, dmax, published_m1, published_m8):
    runs, hadamard_rrfm = mc_lag1[alpha]
    correct = {m: int(sum(r.alpha == alpha for r in rs)) for m, rs in runs.items()}
    for m, published in ((1, published_m1), (8, published_m8)):
        least, most = _binomial_bounds(published, MC_RUNS)
        assert least <= correct[m] <= most, (alpha, m, correct[m], (least, most))
    est8 = np.mean([r.alpha_estimate for r in runs[8]])
    if alpha == -3:  # the documented misidentification: FWFM → RRFM
        assert est8 == pytest.approx(-3.9, abs=0.15)
        least, _ = _binomial_bounds(MC_PUBLISHED_RUNS, MC_RUNS)
        assert sum(r.alpha == -4 for r in runs[8]) >= least
    elif alpha == -4:  # α̂ far below −4 rounds to −5; the Hadamard family clips it to −4
        assert est8 < -4.9
        least, _ = _binomial_bounds(MC_PUBLISHED_RUNS, MC_RUNS)
        assert int(np.sum(np.array(hadamard_rrfm) == -4)) >= least


# ------------------------------------------------------------------ B1 (§5.3)


@pytest.mark.parametrize("nb", [2, 3, 5, 16, 100, 1000])
def test_b1_closed_forms_equal_general_formula(nb):
    closed = {-2: 2 * (nb + 1) / (3 * nb), -1: 1.0, 1: nb / 2, 2: nb * (nb + 1) / 6}
    for mu, value in closed.items():
        assert float(b1_expected(nb, mu)) == pytest.approx(value, rel=1e-12)
    # μ = 0 is the limit of the general formula
    assert float(b1_expected(nb, 1e-7)) == pytest.approx(float(b1_expected(nb, 0)), rel=1e-6)
    assert float(b1_expected(nb, 0)) == pytest.approx(nb * math.log(nb) / (2 * (nb - 1) * math.log(2)), rel=1e-12)


def test_b1_expected_validates():
    with pytest.raises(ParameterError):
        b1_expected(1, 0)


@pytest.mark.slow
@pytest.mark.parametrize("alpha, mu, published_mc", [(2, -2, 0.709), (0, -1, 0.998), (-1, 0, 2.05), (-2, 1, 8.04)])
def test_b1_monte_carlo_means(alpha, mu, published_mc):
    # numerics.md §5.3: Nb = 16, frequency samples that are true τ0-averages.
    # The series is generated 16× finer and averaged (m = 16), which makes each
    # average a true average up to O(1/m²). B1 is a ratio of expectations, so
    # the MC value is mean(s²)/mean(AVAR); the mean of the per-run ratios is
    # higher (1.07 for WFM at Nb = 16: the denominator scatters).
    # Measured (1000 runs): 0.706, 1.004, 2.104, 7.939.
    rng = np.random.default_rng(50 + alpha)
    nb, m = 16, 16
    s2, avar = [], []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", sigmatau.RangeWarning)
        for _ in range(1000):
            y = noise(alpha, nb * m, rng)
            s2.append(sigmatau.stdev(y, m=[m], ci=None).var[0])
            avar.append(sigmatau.adev(y, m=[m], ci=None).var[0])
            if len(s2) <= 3:
                assert b1_ratio(y, m) == pytest.approx(s2[-1] / avar[-1], rel=1e-10)
    mean = float(np.mean(s2) / np.mean(avar))
    assert mean == pytest.approx(float(b1_expected(nb, mu)), rel=0.05)
    assert mean == pytest.approx(published_mc, rel=0.05)


def test_b1_noise_id_classifies_and_hadamard_mode_reaches_rrfm():
    rng = np.random.default_rng(60)
    for alpha in (0, -1, -2):
        calls = [b1_noise_id(noise(alpha, 20 * 16, rng), 16).alpha for _ in range(40)]
        assert np.mean(np.array(calls) == alpha) >= 0.6, (alpha, calls)
    wpm = b1_noise_id(noise(2, 20 * 16, rng), 16)
    assert wpm.ambiguous and wpm.alpha == 1 and wpm.mu == -2
    for alpha in (-3, -4):
        calls = [b1_noise_id(noise(alpha, 20 * 16, rng), 16, hadamard=True).alpha for _ in range(40)]
        assert np.mean(np.array(calls) == alpha) >= 0.6, (alpha, calls)
    with pytest.raises(InsufficientDataError):
        b1_noise_id(np.arange(40.0), 16)  # 2 averages: B1 ≡ 1 for every noise


# ---------------------------------------------------------------- R(n) (§5.4)


def test_rn_expected_values():
    n = np.array([1, 4, 16, 64, 1024])
    assert np.allclose(rn_expected(n, 2), 1.0 / n, rtol=1e-14)
    assert np.allclose(rn_expected(n, 1), 3.374 / (1.0385 + 3 * np.log(np.pi * n)), rtol=2e-4)
    assert float(rn_expected(10, 0)) == pytest.approx(0.5)
    # ((27/8) ln 3 − 4 ln 2)/(2 ln 2) = 0.674625; numerics.md prints 0.6747
    assert float(rn_expected(10, -1)) == pytest.approx(0.674625, abs=1e-6)
    assert float(rn_expected(10, -2)) == pytest.approx(0.825, abs=5e-4)
    with pytest.raises(ParameterError):
        rn_expected(10, -3)


def test_rn_ratio_monte_carlo():
    rng = np.random.default_rng(70)
    for m in (4, 16):
        wpm = np.mean([rn_ratio(noise(2, 8192, rng, "phase"), m, data_type="phase") for _ in range(10)])
        assert wpm == pytest.approx(1.0 / m, rel=0.05)  # exact for discrete white PM
    fpm = np.mean([rn_ratio(noise(1, 8192, rng, "phase"), 16, data_type="phase") for _ in range(10)])
    # continuous model; the discrete FPM excess of AVAR (≈ 6 % at m = 16, §6.1) lowers it
    assert fpm == pytest.approx(float(rn_expected(16, 1)), rel=0.15)


def test_identify_splits_wpm_from_fpm_with_rn_for_every_family():
    # 150 phase points: ⌊N/m⌋ < 30 at m = 8, 10, 12 → B1, which says μ = −2 (WPM or
    # FPM). Stable32's manual splits them with R(n) for the modified family only and
    # reports α = 1 (FPM) for the others; white PM called FPM made OADEV/OHDEV
    # intervals cover 99.9 % instead of 68.3 % (test_confidence_mc), so every family
    # uses R(n) (no row of the Stable32 tables changes).
    rng = np.random.default_rng(80)
    x = noise(2, 150, rng, "phase")
    ms = [8, 10, 12]
    for family in ("oadev", "mdev", "ohdev", "allan"):
        r = identify(x, ms, data_type="phase", family=family)
        assert r.method == ("b1+rn",) * 3 and r.alpha.tolist() == [2, 2, 2], family



# ------------------------------------------------------------- identify (§5.5)


def test_identify_switches_method_at_30_points_and_clips():
    rng = np.random.default_rng(90)
    y = noise(0, 3000, rng)
    r = identify(y, [1, 10, 100, 101, 1000, 1500], rate=2.0)
    assert r.method == ("lag1", "lag1", "lag1", "b1", "b1", "carried")
    assert np.allclose(r.taus, np.array([1, 10, 100, 101, 1000, 1500]) / 2.0)
    assert r.alpha[-1] == r.alpha[-2]  # 2 averages at m = 1500: nearest identified m
    assert np.isnan(r.alpha_estimate[-1])
    assert "WFM" in repr(r)
    # RRFM frequency data: Allan family clipped at RWFM, Hadamard reaches RRFM
    z = noise(-4, 4096, rng)
    assert identify(z, [1], family="allan").alpha.tolist() == [-2]
    assert identify(z, [1], family="hadamard").alpha.tolist() == [-4]
    assert identify(z, [1], family="allan").alpha_estimate[0] == pytest.approx(-4, abs=0.3)


def test_identify_validates():
    with pytest.raises(ParameterError):
        identify(np.zeros(100) + np.arange(100), [1], family="bogus")
    with pytest.raises(ParameterError):
        identify(np.arange(100.0), [0])
    with pytest.raises(ParameterError):
        identify(np.arange(100.0), [1.5])
    with pytest.raises(ParameterError):
        lag1_acf_noise_id(np.arange(100.0), 1, dmin=3, dmax=2)
    with pytest.raises(ParameterError):
        lag1_acf_noise_id(np.arange(100.0), 1, acf="other")
    with pytest.raises(ParameterError):
        lag1_acf_noise_id(np.arange(100.0), 1, data_type="time")
    assert issubclass(InsufficientDataError, DataError) and issubclass(InsufficientDataError, ValueError)


# ------------------------------------------------ Stable32 Alpha column (tables)

_DATASETS = {  # folder: (loader, data type, rate) per tests/data/allantools/README.md
    "phasedat": (refdata.phase_dat, "phase", 1.0),
    "gps": (refdata.gps_phase, "phase", 1.0),
    "ocxo": (refdata.ocxo_frequency, "freq", 1.0),
    "Keysight53230A_ti_noise_floor": (refdata.tic_phase, "phase", 1.0),
    "pink_frequency": (refdata.pink_frequency, "freq", refdata.PINK_RATE),
}

# Tables whose Alpha column is not an identification, left out:
# * Theo1 runs with α forced (header "Alpha = 1", or "alpha0" in the name) and the
#   MTOT/TOTDEV "alpha0" runs: constant by construction;
# * ocxo/stable32_totdev_alltau.txt: α = 0 on all 310 rows although the octave
#   TOTDEV run of the same data identifies 1, 0, −2, −1 … — α fixed for that run;
# * phasedat/phase_dat_htotdev_octave_nobias.txt: tested separately below.
_EXCLUDED = {
    "ocxo/stable32_totdev_alltau.txt",
    "pink_frequency/totdev_alpha0.txt",
    "phasedat/phase_dat_theo1.txt",
    "phasedat/phase_dat_theo1_alpha0.txt",
    "phasedat/phase_dat_theo1_alpha0_decade.txt",
    "phasedat/phase_dat_mtotdev_octave_alpha0.txt",
    "phasedat/phase_dat_htotdev_octave_nobias.txt",
}


def _family(filename: str) -> str:
    name = filename.lower()
    for token, family in (("htot", "hadamard"), ("mtot", "modified"), ("ttot", "modified"),
                          ("totdev", "allan"), ("hdev", "hadamard"), ("mdev", "modified"),
                          ("tdev", "modified")):
        if token in name:
            return family
    return "allan"


def _alpha_tables():
    tables = []
    for path in sorted(refdata.DATA.glob("*/*.txt")):
        rel = path.relative_to(refdata.DATA).as_posix()
        folder = rel.split("/")[0]
        if rel in _EXCLUDED or folder not in _DATASETS:
            continue
        try:
            table = refdata.load_table(rel)
        except (ValueError, IndexError):
            continue  # data files, not tables
        if table.alpha is not None:
            tables.append((rel, table))
    return tables


@pytest.fixture(scope="module")
def stable32_comparison():
    """{table: (m, Stable32 α, our α (standard r1), our α (Stable32 r1), d)} on lag-1 rows."""
    data_cache = {}
    out = {}
    for rel, table in _alpha_tables():
        folder = rel.split("/")[0]
        loader, dtype, rate = _DATASETS[folder]
        if folder not in data_cache:
            data_cache[folder] = loader()
        data = data_cache[folder]
        rows = data.size // table.af >= 30  # where Stable32 used the lag-1 method
        ms = table.af[rows]
        fam = _family(rel)
        std = identify(data, ms, data_type=dtype, family=fam, rate=rate)
        s32 = identify(data, ms, data_type=dtype, family=fam, rate=rate, acf="stable32")
        assert set(std.method) == {"lag1"}
        dmax = 3 if fam == "hadamard" else 2
        d = np.array([lag1_acf_noise_id(data, int(m), data_type=dtype, dmax=dmax).d for m in ms])
        out[rel] = (ms, table.alpha[rows], std.alpha, s32.alpha, std.alpha_estimate, d)
    return out


# Agreement on the lag-1 rows (⌊N/m⌋ ≥ 30), measured: 100 % for every table
# except these (standard r1 → Stable32's (n−1)/n r1):
#   Keysight53230A_ti_noise_floor/tic_adev.txt   175/184 (95.1 %) → 175/184
#   ocxo/stable32_{adev,hdev,mdev,oadev,ohdev,tdev}_alltau.txt
#                                                165/167 (98.8 %) → 167/167
#   pink_frequency/{adev,hdev}.txt               130/132 (98.5 %) → 132/132
#   pink_frequency/{mdev,oadev,ohdev,tdev}.txt   112/113 (99.1 %) → 113/113
# Overall (55 tables) 2475/2504 rows (98.8 %) → 2495/2504 (99.6 %).
#
# Two classes of disagreement:
# 1. Rounding boundary (ocxo m = 113, 463; pink m = 218, 280): α̂ lies within
#    0.015 of a half-integer (−1.498, −1.491, 0.514, 0.507). Stable32 scales r1
#    by (n−1)/n (numerics §5.2 variant), which moves α̂ across; acf="stable32"
#    reproduces all of them and changes no other row.
# 2. Keysight TIC all-τ ADEV (m = 126, 190, 360, 408, 789, 890, 1004, 1370,
#    1824): exactly the rows where the decimated phase has r1 ≥ 1/3, so the
#    method takes one difference (d = 1) — the only d = 1 rows of that run
#    apart from m = 1658, where both say 0. Stable32 reports about one less
#    than round(α̂) there (e.g. α̂ 1.38 → 0, 1.67 → 1). The σ values of these
#    rows match ours to 5 digits, so the data are the same; those rows are
#    reproduced (181/184) if the phase is differenced *before* decimation
#    (point-sampled frequency) — but that breaks the GPS octave tables, where
#    d = 1 on every row and Stable32 agrees with the Riley–Greenhall form
#    (13/13 vs 1/13). So this run of Stable32 behaves differently; we keep §5.2.
def test_stable32_alpha_column_on_lag1_rows(stable32_comparison):
    total = agree_std = agree_s32 = 0
    for rel, (ms, ref, std, s32, est, d) in stable32_comparison.items():
        total += ms.size
        agree_std += int(np.sum(std == ref))
        agree_s32 += int(np.sum(s32 == ref))
        for i in np.flatnonzero(std != ref):
            half = np.floor(est[i]) + 0.5
            boundary = abs(est[i] - half) < 0.02 and s32[i] == ref[i]
            tic_d1 = rel.endswith("tic_adev.txt") and d[i] == 1
            assert boundary or tic_d1, (rel, int(ms[i]), int(ref[i]), int(std[i]), float(est[i]))
        for i in np.flatnonzero(s32 != ref):
            assert rel.endswith("tic_adev.txt") and d[i] == 1, (rel, int(ms[i]))
        if not rel.endswith("tic_adev.txt"):
            assert np.all(s32 == ref), rel
    assert total == 2504
    assert agree_std == 2475  # 98.8 %
    assert agree_s32 == 2495  # 99.6 %: only the TIC d = 1 rows remain


def test_stable32_htot_on_frequency_reads_the_data_as_phase():
    # phase_dat_htotdev_octave_nobias.txt: Stable32 HTOT run on the NBS
    # *frequency* file reports α = 2 everywhere, while the same data as phase
    # (phase_dat_htotdev_octave.txt) gives 0. Lag-1 on the frequency samples read
    # as phase gives exactly 2 on every lag-1 row: that run identified the noise
    # of the frequency series taken as phase (α + 2) and did not shift it back.
    table = refdata.load_table("phasedat/phase_dat_htotdev_octave_nobias.txt")
    y = nbs1000()
    rows = y.size // table.af >= 30
    as_phase = [lag1_acf_noise_id(y, int(m), data_type="phase", dmax=3).alpha for m in table.af[rows]]
    as_freq = identify(y, table.af[rows], family="htotdev").alpha
    assert as_phase == table.alpha[rows].tolist() == [2] * int(rows.sum())
    assert as_freq.tolist() == [0] * int(rows.sum())


# Every row, also where fewer than 30 points remain (B1). Stable32 compares the B1
# ratio with its expectation B1(N, μ) for N = the statistic's number of terms (the "#"
# column), and applies B1 only while the Nb = ⌊M/m⌋ averages number at least twice the
# statistic's stop ratio, carrying α from the preceding τ beyond (identify, Notes).
# Agreement over all rows of these 55 tables (4818 rows), before → after that rule:
# 4142 (86.0 %) → 4787 (99.4 %); per dense table, e.g. phase_dat_oadev 121/139 →
# 139/139, phase_dat_mtotdev 118/158 → 158/158, ocxo oadev all-τ 212/273 → 271/273.
# The 31 rows left: the Keysight ADEV d = 1 rows and the rounding-boundary rows of
# test_stable32_alpha_column_on_lag1_rows (9 + 20), and phase_dat_totdev_octave.txt
# m = 128, 256, where that octave run says 0 although Stable32's all-τ TOTDEV run of
# the same file says 1 at m = 123…146 (its B1 ratio is 0.62–0.78, well inside WPM/FPM)
# — the octave run carried α from m = 64; no rule reproduces both runs.
# (Outside the repository, on the 1253-point Sr87 record of allantoolkit's test assets,
# all 60 octave, decade and all-τ tables: 2290/3320 (69.0 %) → 3320/3320 rows.)
_ALPHA_EXCEPTIONS = {"phasedat/phase_dat_totdev_octave.txt": 7}


@pytest.mark.slow
def test_stable32_alpha_column_on_every_row():
    data_cache = {}
    total = agree = 0
    for rel, table in _alpha_tables():
        folder = rel.split("/")[0]
        loader, dtype, rate = _DATASETS[folder]
        if folder not in data_cache:
            data_cache[folder] = loader()
        got = identify(data_cache[folder], table.af, data_type=dtype, family=_statistic(rel), rate=rate,
                       n_terms=table.n)
        same = int(np.sum(got.alpha == table.alpha))
        total += table.af.size
        agree += same
        least = _ALPHA_EXCEPTIONS.get(rel, math.ceil(0.95 * table.af.size))
        assert same >= least, (rel, same, table.af.size, got.alpha.tolist(), table.alpha.tolist())
    assert total == 4818
    assert agree >= 4787, agree


def _statistic(filename: str) -> str:
    """The statistic a Stable32 table was computed with (its name decides the rules)."""
    name = filename.lower().rsplit("/", 1)[-1]
    for token, stat in (("htot", "htotdev"), ("mtot", "mtotdev"), ("ttot", "ttotdev"), ("totdev", "totdev"),
                        ("ohdev", "ohdev"), ("hdev", "hdev"), ("mdev", "mdev"), ("tdev", "tdev"),
                        ("oadev", "oadev"), ("adev", "adev")):
        if token in name:
            return stat
    raise AssertionError(filename)


@pytest.mark.parametrize("rel", ["phasedat/phase_dat_adev.txt", "phasedat/phase_dat_oadev.txt",
                                 "phasedat/phase_dat_mdev.txt", "phasedat/phase_dat_hdev.txt",
                                 "phasedat/phase_dat_totdev.txt", "phasedat/phase_dat_mtotdev.txt"])
def test_default_path_alpha_on_a_dense_grid(rel):
    # What users get: the statistic itself (its n → identify) on an all-τ grid of the
    # 1001-point PHASE.DAT. Before: 112/125, 121/139, 121/139, 112/125, 157/185, 118/158
    # rows agreed and α changed 22–40 times between neighbouring τ where Stable32
    # changes 11–23 times. Now every row agrees, so α changes exactly where Stable32's does.
    table = refdata.load_table(rel)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", sigmatau.RangeWarning)
        res = getattr(sigmatau, _statistic(rel))(refdata.phase_dat(), data_type="phase", m=table.af)
    np.testing.assert_array_equal(res.alpha, table.alpha)


def test_b1_applies_only_with_enough_averages_then_carries():
    # 1001 phase points, M = 1000: OADEV needs Nb ≥ 8 (m ≤ 125), ADEV Nb ≥ 10 (m ≤ 100),
    # TOTDEV Nb ≥ 4 (m ≤ 250); beyond, α is that of the preceding identified factor.
    assert [b1_min_averages(s) for s in ("adev", "hdev", "oadev", "mdev", "tdev", "ohdev")] == [10, 10, 8, 8, 8, 8]
    assert [b1_min_averages(s) for s in ("totdev", "mtotdev", "ttotdev", "htotdev")] == [4, 6, 6, 6]
    assert [b1_min_averages(s) for s in ("allan", "modified", "hadamard", "theo1")] == [3, 3, 3, 3]
    x = refdata.phase_dat()
    ms = [50, 100, 101, 125, 126, 250, 251, 333]
    for stat, last in (("adev", 100), ("oadev", 125), ("totdev", 250)):
        r = identify(x, ms, data_type="phase", family=stat)
        computed = [m for m, tag in zip(ms, r.method) if tag != "carried"]
        assert computed == [m for m in ms if m <= last], (stat, r.method)
        i_last = ms.index(last)
        assert np.all(r.alpha[i_last:] == r.alpha[i_last]) and np.all(np.isnan(r.alpha_estimate[i_last + 1:]))


def test_n_terms_sets_the_b1_expectation():
    # B1 with N = n_terms: for n_terms ≫ Nb the WFM/FFM boundary sqrt(B1(N, 0)) rises
    # from 1.36 (Nb = 10) to 2.33 (N = 900), so a ratio of 1.5 reads WFM, not FFM.
    rng = np.random.default_rng(7)
    y = noise(0, 1000, rng)
    ratio = b1_ratio(y, 100)
    r_nb = b1_noise_id(y, 100)
    r_n = b1_noise_id(y, 100, n_expected=900)
    assert r_nb.nb == r_n.nb == 10 and r_nb.ratio == r_n.ratio == ratio
    for res, n in ((r_nb, 10), (r_n, 900)):
        expected = b1_expected(n, np.array([-2, -1, 0, 1, 2.0]))
        mu = [-2, -1, 0, 1, 2][int(np.searchsorted(np.sqrt(expected[:-1] * expected[1:]), ratio))]
        assert res.mu == mu
    with pytest.raises(ParameterError, match="n_terms"):
        identify(y, [1, 2], n_terms=[5])
    with pytest.raises(ParameterError, match="n_terms"):
        identify(y, [1, 2], n_terms=[5, -1])
    with pytest.raises(ParameterError, match="n_expected"):
        b1_noise_id(y, 100, n_expected=2.5)


# ------------------------------------------------------------- Theo κ (§3, §5.5)


def test_theo_noise_id_thresholds():
    nominal = np.array([0.4, 0.6, 1.0, 1.71, 2.24])
    assert theo_noise_id(nominal).tolist() == [2, 1, 0, -1, -2]
    bounds = np.sqrt(nominal[:-1] * nominal[1:])
    assert np.allclose(bounds, [0.4899, 0.7746, 1.3077, 1.9571], atol=1e-4)
    assert theo_noise_id(bounds * 0.999).tolist() == [2, 1, 0, -1]
    assert theo_noise_id(bounds * 1.001).tolist() == [1, 0, -1, -2]
    assert theo_noise_id([0.01, 100.0]).tolist() == [2, -2]
    # τ-dependent factors (Howe & Tasset): each nominal a + b/t^c maps to itself
    for m in (10, 100, 1000):
        t = 0.75 * m
        abc = [(0.09, 0.74, 0.40), (0.14, 0.82, 0.30), (1.0, 0.0, 0.0), (1.87, -1.05, 0.79), (2.70, -1.53, 0.85)]
        factors = [a + b / t**c for a, b, c in abc]
        assert theo_noise_id(factors, m=m).tolist() == [2, 1, 0, -1, -2]
    with pytest.raises(ParameterError):
        theo_noise_id(-1.0)


# ---------------------------------------------------------- local slopes (§5.1)

# The design tip's deviation slopes (dt0064.md; numerics.md §5.1). ADEV-like
# rows cannot split WPM/FPM and FPM's ADEV slope is only ≈ −1 (log factor).
TIP_SLOPES = {
    "oadev": {2: -1.0, 0: -0.5, -1: 0.0, -2: 0.5},
    "adev": {2: -1.0, 0: -0.5, -1: 0.0, -2: 0.5},
    "mdev": {2: -1.5, 1: -1.0, 0: -0.5, -1: 0.0, -2: 0.5},
    "tdev": {2: -0.5, 1: 0.0, 0: 0.5, -1: 1.0, -2: 1.5},
    "hdev": {2: -1.0, 0: -0.5, -1: 0.0, -2: 0.5, -3: 1.0, -4: 1.5},
    "ohdev": {2: -1.0, 0: -0.5, -1: 0.0, -2: 0.5, -3: 1.0, -4: 1.5},
}


@pytest.fixture(scope="module")
def slope_data():
    rng = np.random.default_rng(100)
    return {alpha: noise(alpha, 1 << 14, rng) for alpha in NOISE_NAMES}


@pytest.mark.parametrize("stat", sorted(TIP_SLOPES))
def test_local_slopes_match_the_tip(slope_data, stat):
    # From m = 4 on (the discrete-sampling excess at small m is ≤ 5 %, §6.1).
    # About 50 slope pairs per statistic: all within 4σ, 85 % within 2σ (the
    # simple 1/√n error is conservative for overlapped estimators), and at least
    # 75 % of the pairs name the generated noise. Over seeds 100–119: max |z|
    # 3.2, at least 94 % within 2σ and 80 % named right for every statistic.
    func = getattr(sigmatau, stat)
    zs, named = [], []
    for alpha, expected in TIP_SLOPES[stat].items():
        ls = local_slopes(func(slope_data[alpha]))
        use = ls.taus >= 4 * math.sqrt(2)
        zs.append((ls.slope[use] - expected) / ls.slope_err[use])
        if stat in ("adev", "oadev", "hdev", "ohdev") and alpha == 2:
            named.append(ls.ambiguous[use] & (ls.alpha[use] == 1))  # WPM or FPM
        else:
            named.append(ls.alpha[use] == alpha)
    z = np.concatenate(zs)
    assert np.max(np.abs(z)) < 4, np.round(z, 1)
    assert np.mean(np.abs(z) < 2) >= 0.85, np.round(z, 1)
    assert np.mean(np.concatenate(named)) >= 0.75


def test_local_slopes_fpm_on_adev_is_ambiguous_and_uncertainty_from_edf(slope_data):
    ls = local_slopes(sigmatau.oadev(slope_data[1]))
    assert ls.ambiguous[2:].mean() >= 0.7
    r = sigmatau.oadev(slope_data[0], ci=None)  # no EDF: the 1/√n fallback
    nu = np.full(len(r), 50.0)
    ls_edf = local_slopes(dataclasses.replace(r, edf=nu))
    expected = math.sqrt(2 / (2 * 50.0)) / np.diff(np.log(r.taus))
    assert np.allclose(ls_edf.slope_err, expected)
    # without an EDF: relative deviation error 1/√n, n = non-overlapping terms
    n_eff = np.minimum(r.n, (r.n_points - 1) // r.m).astype(float)
    fallback = np.sqrt(1 / n_eff[:-1] + 1 / n_eff[1:]) / np.diff(np.log(r.taus))
    assert np.allclose(local_slopes(r).slope_err, fallback)
    with pytest.raises(ParameterError):
        local_slopes(sigmatau.stdev(slope_data[0]))


# ------------------------------------------------------- power-law fit (§6.3)


def test_power_law_variance_constants():
    # numerics.md §6.3, per unit h_α
    t = np.array([1.0, 10.0])
    assert np.allclose(power_law_variance("oadev", -1, t), 1.386294, rtol=1e-6)
    assert np.allclose(power_law_variance("mdev", -1, t), 0.935228, rtol=1e-6)
    assert np.allclose(power_law_variance("hdev", -1, t), 1.124670, rtol=1e-6)
    assert np.allclose(power_law_variance("adev", -2, t), 6.579736 * t, rtol=1e-6)
    assert np.allclose(power_law_variance("mdev", -2, t), 5.428282 * t, rtol=1e-6)
    assert np.allclose(power_law_variance("ohdev", -2, t), 3.289868 * t, rtol=1e-6)
    assert np.allclose(power_law_variance("hdev", -3, t), 12.307104 * t**2, rtol=1e-6)
    assert np.allclose(power_law_variance("hdev", -4, t), 71.433333 * t**3, rtol=1e-6)
    assert np.allclose(power_law_variance("mdev", 1, t), 0.085465 / t**2, rtol=1e-5)
    assert np.allclose(power_law_variance("tdev", 1, t), 0.028488, rtol=1e-5)
    assert np.allclose(power_law_variance("oadev", 0, t, h=2.0), 1.0 / t)
    # WPM with f_h = rate/2: AVAR 3 f_h/(4π²τ²), HVAR 10/9 of it
    av = power_law_variance("oadev", 2, t, rate=100.0)
    assert np.allclose(av, 3 * 50 / (4 * math.pi**2 * t**2))
    assert np.allclose(power_law_variance("ohdev", 2, t, rate=100.0), av * 10 / 9)
    with pytest.raises(ParameterError):
        power_law_variance("oadev", -3, t)


def test_power_law_variance_mvar_white_fm_is_exact_for_sampled_data():
    # MVAR of white y (variance 1 = h0/(2τ0)) is (m² + 1)/(2m³) exactly; the
    # model writes it h0/(4τ)·(1 + 1/m²)
    rng = np.random.default_rng(110)
    ms = np.array([1, 2, 3, 8])
    runs = [sigmatau.mdev(rng.standard_normal(20_000), m=ms).var for _ in range(10)]
    mean = np.mean(runs, axis=0)
    exact = (ms**2 + 1) / (2.0 * ms**3)
    assert np.allclose(power_law_variance("mdev", 0, ms, h=2.0), exact)
    assert np.allclose(mean, exact, rtol=0.03)


RATE = 100.0
H_TRUE = {2: 1e-4, 0: 1e-2, -2: 2e-5}  # WPM, WFM, RWFM; crossings near τ = 0.08 s and 6 s


def _mix(rng: np.random.Generator, n: int = 1 << 16) -> np.ndarray:
    tau0 = 1.0 / RATE
    # numerics.md §6.1 scaling: WPM phase variance h2/(8π²τ0), WFM y variance
    # h0/(2τ0), RWFM y = cumsum of white with Q_d = h−2(2π)²τ0/2
    x = rng.normal(0.0, math.sqrt(H_TRUE[2] / (8 * math.pi**2 * tau0)), n + 1)
    y = np.diff(x) / tau0
    y += rng.normal(0.0, math.sqrt(H_TRUE[0] / (2 * tau0)), n)
    y += np.cumsum(rng.normal(0.0, math.sqrt(H_TRUE[-2] * (2 * math.pi) ** 2 * tau0 / 2), n))
    return y


FIT_RUNS = 40
FIT_CASES = (("oadev", (2, 0, -2)), ("mdev", None), ("ohdev", None))


def _fit_fails(stat: str, alphas, y: np.ndarray) -> bool:
    """One fit of the WPM + WFM + RWFM mix; True if it misses a term, a level by ≥ 3σ,
    or keeps a spurious term that makes up a quarter of the curve anywhere."""
    result = getattr(sigmatau, stat)(y, rate=RATE)
    fit = fit_power_law(result, alphas=alphas)
    total = fit.variance(result.taus)
    assert np.allclose(total, sum(fit.terms(result.taus).values()))
    assert np.allclose(fit.deviation(result.taus) ** 2, total)
    if any(alpha not in fit.kept for alpha in H_TRUE):
        return True
    if any(abs(fit.h[alpha] - h) >= 3 * fit.h_err[alpha] for alpha, h in H_TRUE.items()):
        return True
    return any(np.any(fit.term(alpha, result.taus) >= 0.25 * total) for alpha in set(fit.kept) - set(H_TRUE))


def test_fit_power_law_recovers_known_levels(rng):
    # A statistical test over FIT_RUNS mixes (3 fits each), not a list of seeds that pass.
    # Known error rate of a fit: the docstring's calibration (z-scores with unit spread
    # within ±30 %, so SD ≤ 1.3) puts |z| ≥ 3 for one of three terms at
    # 1 − (2Φ(3/1.3) − 1)³ = 6.2 %; the documented selection failure (a flicker-FM term
    # kept at 3σ takes over part of the long-τ RWFM: 4 of 52 MDEV/OHDEV fits when this
    # test was first written) adds 7.7 %: p0 = 0.139. The failures must not exceed the
    # 99.9 % quantile of Binomial(3·FIT_RUNS, p0). Measured over 200 other mixes: 5, 13,
    # 15 failures of 200 for OADEV, MDEV, OHDEV (5.5 %); z-scores with SD ≈ 2 (no
    # τ-correlation term) would fail about 35 % of fits.
    from scipy import stats

    p0 = 1.0 - (2.0 * stats.norm.cdf(3.0 / 1.3) - 1.0) ** 3 + 4.0 / 52.0
    fails = 0
    for _ in range(FIT_RUNS):
        y = _mix(rng)
        fails += sum(_fit_fails(stat, alphas, y) for stat, alphas in FIT_CASES)
    fits = FIT_RUNS * len(FIT_CASES)
    assert fails <= stats.binom.isf(1e-3, fits, p0), (fails, fits)


def test_fit_power_law_drops_unsupported_terms():
    rng = np.random.default_rng(120)
    result = sigmatau.oadev(rng.standard_normal(1 << 15), rate=RATE)  # pure WFM
    fit = fit_power_law(result)
    assert fit.kept == (0,)
    assert set(fit.dropped) == {2, 1, -1, -2}
    assert fit.h[0] == pytest.approx(2.0 / RATE, rel=3 * fit.h_err[0] / fit.h[0])  # h0 = 2σ²τ0
    assert np.all(fit.term(-2, result.taus) == 0)
    assert "WFM" in repr(fit)
    with pytest.raises(ParameterError):
        fit_power_law(result, alphas=(-3,))
    with pytest.raises(ParameterError):
        fit_power_law(sigmatau.stdev(rng.standard_normal(1000)))


def test_fit_power_law_uses_edf_weights():
    rng = np.random.default_rng(130)
    result = sigmatau.oadev(rng.standard_normal(1 << 14), rate=RATE)
    nu = np.linspace(50.0, 5.0, len(result))
    explicit = fit_power_law(result, edf=nu)
    carried = fit_power_law(dataclasses.replace(result, edf=nu))
    assert explicit.h == carried.h and explicit.h_err == carried.h_err
    # a larger EDF gives a smaller uncertainty, until χ²/dof > 1 takes over
    loose = fit_power_law(result, alphas=(0,), edf=5.0)
    tight = fit_power_law(result, alphas=(0,), edf=50.0)
    assert loose.h_err[0] > tight.h_err[0]


def test_public_names_are_exported_by_the_module():
    import sigmatau.uncertainty.noiseid as mod

    for name in mod.__all__:
        assert hasattr(mod, name), name
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        identify(np.random.default_rng(0).standard_normal(500), [1, 20, 100], family="mdev")
