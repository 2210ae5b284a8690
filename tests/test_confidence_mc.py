"""Confidence intervals of the public statistics, checked two ways.

1. Monte Carlo (``@pytest.mark.slow``): R independent Kasdin–Walter series of each
   power-law noise type go through the public statistic with ``alpha=`` forced to
   the true type, so the EDF model under test is the one the library reports; and
   (part 1b) through the default path, noise type identified per τ, as users get it. The
   spread of the estimates gives the empirical EDF, and the reported 68.3 %
   intervals must cover the true deviation about as often as they claim.
   A deterministic companion compares the reported EDF with the *exact* EDF of the
   same discrete process (a quadratic form in Gaussian noise, computed below).
2. End to end (fast): ``ci_low``/``ci_high`` of the public statistics on the
   reference data sets against Stable32's Min/Max Sigma, plus the ``ci="simple"``,
   ``ci=None`` and ``confidence=`` keywords.

References: /work/shared/reference/numerics.md §2 (EDF rules, §2.3 "Model note",
§2.5 Monte-Carlo table), §6.1 (Kasdin–Walter generator and its exact discrete
expectations); tests/data/allantools/README.md for the reference tables.
"""

from __future__ import annotations

import functools
import math
import warnings

import numpy as np
import pytest
from scipy import fft, stats

import refdata
import sigmatau
from refdata import load_table
from sigmatau.confidence import ONE_SIGMA, deviation_interval, edf
from sigmatau.errors import ParameterError
from sigmatau.generate import expected_variance_discrete, power_law_noise
from test_confidence import KNOWN_DEVIATIONS, S32_RTOL

# =====================================================================================
# Part 1 — Monte-Carlo validation of the EDF and of the interval coverage
# =====================================================================================

N_MC = 2049  # phase points (2048 frequency samples for the FM types)
R_MC = 500  # independent series per noise type
R_FULL = 50  # of which fully through the public interval path (see mc_runs)
M_MC = (1, 4, 16, 64)
MC_SEED = 20240611
NOISE = {2: "WPM", 1: "FPM", 0: "WFM", -1: "FFM", -2: "RWFM"}

#: Finite-difference statistics with a Greenhall–Riley EDF and an exact discrete
#: expectation (generate.expected_variance_discrete).
GREENHALL_STATS = ("oadev", "mdev", "ohdev")

#: Total-variance cases (empirical EDF rules of numerics.md §2.4), as in the §2.5 table.
#: No exact expectation exists for them: the "true" deviation is the root of the mean
#: variance over the runs.
TOTAL_CASES = {("totdev", 0): (4, 16, 64), ("totdev", -2): (4, 16, 64),
               ("mtotdev", 2): (4, 16, 64), ("mtotdev", -1): (4, 16, 64)}

MC_CASES = [(s, a) for a in NOISE for s in GREENHALL_STATS] + sorted(TOTAL_CASES, key=lambda c: -c[1])
MC_IDS = [f"{s}-{NOISE[a]}" for s, a in MC_CASES]

#: Acceptance band of the coverage of the nominal 68.3 % interval over R ≥ 400 runs
#: (the issue's criterion; binomial sd at R = 500 is 2.1 points).
COVERAGE_BAND = (0.60, 0.76)

#: Standard errors allowed for Monte-Carlo scatter on top of a model gap (ln ν_MC against
#: the rule; coverage against its expectation). About 40 roughly independent
#: comparisons are made per seed; at 3 SE, 2 of 8 trial seeds failed one by chance.
Z_STAT = 3.5
#: The same for ν_MC against the exact EDF of the simulated process, where nothing else
#: absorbs the scatter (1 of 13 trial seeds had a 3.6 SE excursion there: RWFM m = 1,
#: whose s² is exactly χ²(2047)/2047). With these values all of 36 trial seeds besides
#: MC_SEED passed every slow test of this file.
Z_EXACT = 4.0


def model_gap(statistic: str, alpha: int, m: int) -> tuple[float, float]:
    """Documented gap (below, above) between the EDF rule and discrete noise.

    ν of point-sampled discrete noise may lie in [ν_rule/(1 + below), ν_rule·(1 + above)].

    Greenhall–Riley statistics (numerics.md §2.3 "Model note", §2.5). The algorithm
    models phase samples as τ0-averages of a continuous process, not as the discrete
    Kasdin–Walter series:

    * m = 1: up to ~30 % either way (§2.3: WFM OAVAR MC 334 vs rule 400, RWFM 508 vs
      390, N = 513). The exact computation below (:func:`discrete_edf`) gives
      −19.6 % … +31.1 % (OHDEV FFM; OADEV/MDEV RWFM): 0.33 both ways.
    * 2 ≤ m < 16: "up to ~17 %" (§2.3, WFM OAVAR/OHVAR at m = 4); exact: +13.5 % at
      m = 4, +17.1 % at m = 2 (OADEV RWFM): 0.18.
    * m ≥ 16: "within ~5 %" (§2.3/§2.5; that MC had a ~3 % standard error); exact:
      at most +6.1 % (OHDEV WFM, m = 16), ≤ 0.7 % from m = 64 on: 0.07.
    * FPM with an unmodified statistic (OADEV, OHDEV), m ≥ 2: the rule is 20–25 %
      *conservative* (§2.5; the FPM EDF depends on the high-frequency cut-off, which
      differs between the continuous model and discrete data); exact: +13.6 … +20.8 %.
      Above: 0.25; below: the generic value of that m.

    Empirical rules of TOTDEV/MTOT (§2.4, "[S, MC-checked]"): §2.5 lists MC/rule from
    0.90 to 1.25 at m = 4 (MTOT FFM 136/109) and 0.90 to 1.11 at m ≥ 16 (MTOT WPM
    53.2/58.8, MTOT FFM 29.7/26.8), each MC with a 5–8 % error of its own: 0.25 and
    0.15 both ways.
    """
    if statistic in ("totdev", "mtotdev"):
        gap = 0.25 if m < 16 else 0.15
        return gap, gap
    generic = 0.33 if m == 1 else 0.18 if m < 16 else 0.07
    if alpha == 1 and statistic in ("oadev", "ohdev", "adev", "hdev") and m >= 2:
        return generic, 0.25
    return generic, generic


def nu_mc_and_se(v: np.ndarray) -> tuple[float, float]:
    """Empirical EDF ν_MC = 2·mean(s²)²/var(s²) and the standard error of ln ν_MC.

    Delta method on ln ν = ln 2 + 2 ln μ − ln V with the sample central moments
    (μ mean, V variance, μ3, μ4 of s² over the R runs):

        Var(ln ν̂) ≈ [4V/μ² − 4μ3/(μV) + (μ4 − V²)/V²] / R.

    For s² ∝ χ²_ν this is (2 + 4/ν)/R, i.e. a relative error sqrt(2/R)·sqrt(1 + 2/ν)
    (6.4 % at R = 500, ν ≥ 100); the sample moments also carry any excess kurtosis of
    the real distribution. Checked against a 2000-resample bootstrap while this file
    was written (agreement within 10 % of the SE in every case).
    """
    R = v.size
    mu = v.mean()
    c = v - mu
    var = np.sum(c * c) / (R - 1)
    m3 = np.mean(c**3)
    m4 = np.mean(c**4)
    var_log = (4.0 * var / mu**2 - 4.0 * m3 / (mu * var) + (m4 - var**2) / var**2) / R
    return 2.0 * mu**2 / var, math.sqrt(var_log)


def edf_agrees(nu_mc: float, se_log: float, nu_rule: float, gap: tuple[float, float]) -> bool:
    """ν_MC and the rule agree within the model gap plus Z_STAT statistical errors."""
    r = math.log(nu_mc / nu_rule)
    return -math.log1p(gap[0]) - Z_STAT * se_log <= r <= math.log1p(gap[1]) + Z_STAT * se_log


def discrete_edf(alpha: int, statistic: str, m: int, n_points: int, k_grid: int = 1 << 15) -> float:
    """Exact EDF of OAVAR/MVAR/OHVAR on stationary discrete Kasdin–Walter noise.

    The estimator is s² ∝ Σ_i z_i², z_i the M overlapping terms (second or third
    differences of the phase at lag m, moving-summed over m for MVAR), a stationary
    Gaussian sequence with autocovariance c(k). Then E[s²] ∝ M c(0) and
    Var[s²] ∝ 2 Σ_{i,j} c(i−j)², so

        ν = 2 E²/Var = (M c0)² / (M c0² + 2 Σ_{k=1}^{M−1} (M − k) c_k²),

    with c(k) ∝ ∫_0^π |2 sin(ω/2)|^{α−2} (2 sin(mω/2))^{2d} [(sin(mω/2)/sin(ω/2))²] cos(kω) dω
    (numerics.md §6.1). The integral is the midpoint rule on k_grid nodes, i.e. a
    DCT-II; the integrand is smooth but for a |ω| kink at 0 (odd α), so the error is
    O(k_grid⁻²). Checked while this file was written against the dense quadratic form
    x = T w of the generator started at rest (tr(B)²/tr(B²), N = 1025): agreement to
    4 digits for all five types, i.e. the start-up transient does not matter here.
    """
    d = 3 if statistic in ("hdev", "ohdev") else 2
    modified = statistic in ("mdev", "tdev")
    M = n_points - d * m - (m - 1 if modified else 0)
    w = (np.arange(k_grid) + 0.5) * (math.pi / k_grid)
    s = 2.0 * np.sin(0.5 * w)
    t = 2.0 * np.sin(0.5 * m * w)
    spec = s ** (alpha - 2) * t ** (2 * d)
    if modified:
        spec *= (t / s) ** 2
    c = fft.dct(spec, type=2)[:M]
    k = np.arange(1, M)
    return float((M * c[0]) ** 2 / (M * c[0] ** 2 + 2.0 * np.sum((M - k) * c[1:] ** 2)))


def _case_ms(statistic: str, alpha: int) -> tuple[int, ...]:
    return TOTAL_CASES.get((statistic, alpha), M_MC)


@functools.cache
def mc_runs(alpha: int) -> dict[str, dict[str, np.ndarray]]:
    """R_MC seeded series of one noise type through every statistic of its cases.

    Returns {statistic: {"var", "dev", "edf", "low", "high": arrays (R, len(m))}}.
    The series are phase data of N_MC points, h_α = 1, τ0 = 1 s; ``data_type="phase"``
    of power_law_noise integrates the frequency series for α ≤ 0 and generates the
    phase directly for WPM/FPM (numerics.md §6.1), so every type is the Kasdin–Walter
    process whose discrete expectation expected_variance_discrete gives.

    The first R_FULL runs go through the public statistic with ``alpha=`` forced and
    keep its edf, ci_low and ci_high. The EDF depends on (statistic, α, m, N) only and
    costs 95 % of such a call (Greenhall's sums are recomputed each time; 5–20 ms per
    call for α = ±1), so the other runs call the statistic with ``ci=None`` and get
    the interval the library would report, deviation_interval(dev, edf) — the
    identity is asserted on the full runs (test_mc_interval_coverage).
    """
    names = [s for s, a in MC_CASES if a == alpha]
    rng = np.random.default_rng([MC_SEED, alpha + 10])
    out = {s: {k: np.full((R_MC, len(_case_ms(s, alpha))), np.nan)
               for k in ("var", "dev", "edf", "low", "high")} for s in names}
    for r in range(R_MC):
        x = power_law_noise(N_MC, alpha, data_type="phase", rng=rng)
        for s in names:
            ms = list(_case_ms(s, alpha))
            if r < R_FULL:
                res = getattr(sigmatau, s)(x, data_type="phase", m=ms, alpha=alpha)
                assert np.all(res.alpha == alpha) and res.confidence == ONE_SIGMA
                assert res.n_points == N_MC
                out[s]["edf"][r], out[s]["low"][r], out[s]["high"][r] = res.edf, res.ci_low, res.ci_high
            else:
                res = getattr(sigmatau, s)(x, data_type="phase", m=ms, ci=None)
            out[s]["var"][r], out[s]["dev"][r] = res.var, res.dev
    for s in names:
        runs = out[s]
        # the reported EDF is the same in every run
        assert np.all(runs["edf"][:R_FULL] == runs["edf"][0])
        runs["edf"][R_FULL:] = runs["edf"][0]
        runs["low"][R_FULL:], runs["high"][R_FULL:] = deviation_interval(
            runs["dev"][R_FULL:], runs["edf"][R_FULL:], ONE_SIGMA)
    return out


def true_variance(statistic: str, alpha: int, var_runs: np.ndarray) -> np.ndarray:
    """E[var]: exact discrete expectation where available, else the mean over the runs."""
    if statistic in GREENHALL_STATS:
        return expected_variance_discrete(alpha, 1.0, list(_case_ms(statistic, alpha)), statistic=statistic)
    return var_runs.mean(axis=0)


def predicted_coverage(nu_rule: float, nu_true: float, confidence: float = ONE_SIGMA) -> float:
    """Coverage of the χ² interval built with ν_rule when s²/σ² ~ χ²(ν_true)/ν_true.

    The interval contains σ² iff χ²_lo(ν_rule)/ν_rule ≤ s²/σ² ≤ χ²_hi(ν_rule)/ν_rule.
    """
    q = stats.chi2.ppf([(1 - confidence) / 2, (1 + confidence) / 2], nu_rule) / nu_rule
    lo, hi = stats.chi2.cdf(q * nu_true, nu_true)
    return float(hi - lo)


def sanity_factor(statistic: str, m: int) -> float:
    """Error factor of the EDF that the MC check must reject whatever the seed.

    Rejection needs ln f > ln(1 + gap) + |ln(ν_true/ν_rule)| + Z_STAT·SE with margin
    for the MC scatter (SE ≈ 6.4 %). For the Greenhall statistics at m ≥ 4 (gap
    ≤ 18 %, or 25 % on the conservative side for FPM) a factor 2 leaves ≥ 2.7 SE. At
    m = 1 (±33 %, and a rule 31 % conservative for RWFM) and for the empirical rules
    (±25 % at m = 4, MTOT FFM measured +19 %) a factor 2 would sit within ~2 SE of the
    edge, so 3 and 2.5 are used; test_rule_vs_exact_discrete_edf, which has no
    statistical error, rejects a factor 2 at every m.
    """
    if statistic not in GREENHALL_STATS:
        return 2.5
    return 2.0 if m >= 4 else 3.0


# Measured with MC_SEED (N = 2049, R = 500). ν_rule: reported edf; ν_ex: discrete_edf
# (exact for the simulated process); ν_MC and its relative SE in %; cov: coverage of the
# 68.3 % interval of the R runs in %; pred: predicted_coverage(ν_rule, ν_ex or ν_MC).
# OADEV and MDEV are the same estimator at m = 1. Every measured coverage lies in the
# 60–76 % band (61.6 … 74.6 %).
#
#   case         m    ν_rule    ν_ex    ν_MC   SE    cov  pred
#   oadev WPM      1  1053.0  1053.0  1090.7  6.5   69.0  68.3
#   oadev WPM      4  1050.7  1050.7  1036.7  6.4   69.0  68.3
#   oadev WPM     16  1041.6  1041.6  1022.2  5.9   66.8  68.3
#   oadev WPM     64  1005.2  1005.2  1002.8  6.5   68.4  68.3
#   mdev WPM       1  1053.0  1053.0  1090.7  6.5   69.0  68.3
#   mdev WPM       4   599.7   599.7   605.6  6.3   69.8  68.3
#   mdev WPM      16   160.8   160.8   172.7  6.2   67.8  68.3
#   mdev WPM      64    38.2    38.2    34.4  7.5   66.4  68.3
#   ohdev WPM      1   886.0   886.0   926.1  6.5   71.0  68.3
#   ohdev WPM      4   882.9   882.9   888.6  6.5   69.2  68.3
#   ohdev WPM     16   870.8   870.8   859.2  5.7   67.4  68.3
#   ohdev WPM     64   822.3   822.3   831.6  6.5   69.6  68.3
#   oadev FPM      1  1301.9  1180.2  1103.0  6.2   65.8  65.9
#   oadev FPM      4   798.5   907.9   932.3  6.5   73.0  71.4
#   oadev FPM     16   395.0   468.6   434.0  6.0   70.2  72.4
#   oadev FPM     64   164.0   193.3   223.0  6.3   74.6  72.2
#   mdev FPM       1  1301.9  1180.2  1103.0  6.2   65.8  65.9
#   mdev FPM       4   509.0   528.2   544.7  6.3   71.4  69.2
#   mdev FPM      16   126.2   126.9   129.9  5.5   65.0  68.4
#   mdev FPM      64    29.8    29.8    34.3  6.1   71.0  68.3
#   ohdev FPM      1  1042.4   958.7   877.7  6.2   65.4  66.2
#   ohdev FPM      4   670.4   761.5   775.1  6.5   70.4  71.3
#   ohdev FPM     16   334.0   396.8   358.1  6.0   69.2  72.4
#   ohdev FPM     64   136.8   161.5   185.3  6.5   74.6  72.3
#   oadev WFM      1  1602.2  1364.9  1340.2  6.3   64.0  64.4
#   oadev WFM      4   628.5   710.6   745.6  6.7   71.4  71.2
#   oadev WFM     16   179.0   188.9   186.1  6.0   67.8  69.6
#   oadev WFM     64    45.8    45.8    44.7  6.3   67.2  68.3
#   mdev WFM       1  1602.2  1364.9  1340.2  6.3   64.0  64.4
#   mdev WFM       4   493.5   506.9   517.7  6.8   70.4  68.9
#   mdev WFM      16   121.7   121.9   122.8  5.8   67.2  68.3
#   mdev WFM      64    28.7    28.7    27.9  6.8   66.8  68.3
#   ohdev WFM      1  1247.3  1052.5   999.1  6.3   61.6  64.2
#   ohdev WFM      4   528.1   599.4   617.6  6.5   71.6  71.3
#   ohdev WFM     16   151.4   160.7   158.7  5.9   66.0  69.7
#   ohdev WFM     64    38.2    38.1    37.4  6.2   68.0  68.3
#   oadev FFM      1  1834.2  1659.4  1586.5  6.2   65.4  65.8
#   oadev FFM      4   579.8   616.8   592.0  6.7   71.2  69.8
#   oadev FFM     16   147.9   148.6   150.6  6.5   68.0  68.4
#   oadev FFM     64    35.8    35.6    33.2  6.9   66.8  68.2
#   mdev FFM       1  1834.2  1659.4  1586.5  6.2   65.4  65.8
#   mdev FFM       4   486.9   494.2   471.5  6.8   68.0  68.6
#   mdev FFM      16   119.9   119.1   119.6  6.2   67.4  68.1
#   mdev FFM      64    28.2    28.0    26.3  6.5   67.0  68.1
#   ohdev FFM      1  1467.9  1179.6  1129.3  6.5   62.2  63.0
#   ohdev FFM      4   492.7   527.9   513.1  6.6   69.6  69.9
#   ohdev FFM     16   125.5   126.9   128.7  6.7   67.4  68.5
#   ohdev FFM     64    29.7    29.8    28.7  7.5   69.2  68.3
#   oadev RWFM     1  1561.8  2047.0  2011.3  6.1   73.8  74.8
#   oadev RWFM     4   466.4   488.6   512.0  6.4   70.6  69.4
#   oadev RWFM    16   117.1   117.4   111.3  6.4   66.4  68.3
#   oadev RWFM    64    28.1    28.2    26.0  6.7   67.4  68.3
#   mdev RWFM      1  1561.8  2047.0  2011.3  6.1   73.8  74.8
#   mdev RWFM      4   391.6   402.7   418.2  6.3   70.6  68.9
#   mdev RWFM     16    96.4    96.6    91.6  6.4   67.0  68.3
#   mdev RWFM     64    22.6    22.6    21.1  6.9   67.8  68.3
#   ohdev RWFM     1  1636.3  1364.2  1320.8  6.3   62.2  63.9
#   ohdev RWFM     4   487.5   506.6   558.0  6.0   69.6  69.2
#   ohdev RWFM    16   121.5   121.8   117.2  6.0   65.4  68.3
#   ohdev RWFM    64    28.7    28.7    27.4  6.7   66.4  68.3
#   mtotdev WPM    4   971.2       –   830.2  6.4   65.2  64.5
#   mtotdev WPM   16   241.2       –   236.8  6.2   68.0  67.8
#   mtotdev WPM   64    58.7       –    50.2  6.9   64.4  64.5
#   totdev WFM     4   768.4       –   747.0  6.8   68.4  67.6
#   totdev WFM    16   192.1       –   189.2  5.9   66.0  67.9
#   totdev WFM    64    48.0       –    46.1  6.1   67.0  67.3
#   mtotdev FFM    4   434.9       –   516.7  6.8   74.6  72.4
#   mtotdev FFM   16   108.4       –   130.2  6.3   72.0  72.7
#   mtotdev FFM   64    26.7       –    28.5  6.6   69.0  69.9
#   totdev RWFM    4   476.0       –   512.8  6.4   70.6  70.1
#   totdev RWFM   16   118.7       –   112.4  6.5   66.0  67.0
#   totdev RWFM   64    29.4       –    26.7  6.7   67.2  65.9


@pytest.mark.slow
@pytest.mark.parametrize("statistic, alpha", MC_CASES, ids=MC_IDS)
def test_mc_edf_matches_rule(statistic, alpha):
    runs = mc_runs(alpha)[statistic]
    ms = _case_ms(statistic, alpha)
    for j, m in enumerate(ms):
        nu_rule = float(runs["edf"][:R_FULL, j].mean())  # the same in every run
        nu_mc, se = nu_mc_and_se(runs["var"][:, j])
        gap = model_gap(statistic, alpha, m)
        assert edf_agrees(nu_mc, se, nu_rule, gap), (
            f"{statistic} {NOISE[alpha]} m={m}: nu_MC={nu_mc:.1f} (SE {se:.1%}) vs edf {nu_rule:.1f}, "
            f"allowed gap -{gap[0]:.0%}/+{gap[1]:.0%} + {Z_STAT:g} SE")
        # The check can fail: an EDF off by a clear factor is rejected (sanity_factor).
        f = sanity_factor(statistic, m)
        assert not edf_agrees(nu_mc, se, f * nu_rule, gap), (statistic, alpha, m, f)
        assert not edf_agrees(nu_mc, se, nu_rule / f, gap), (statistic, alpha, m, 1 / f)
        if statistic in GREENHALL_STATS:
            # The simulation itself: ν_MC against the exact EDF of the simulated
            # process, statistical error only (a factor 2 is 11 SE).
            nu_ex = discrete_edf(alpha, statistic, m, N_MC)
            assert abs(math.log(nu_mc / nu_ex)) <= Z_EXACT * se, (statistic, alpha, m, nu_mc, nu_ex)


@pytest.mark.slow
@pytest.mark.parametrize("statistic, alpha", MC_CASES, ids=MC_IDS)
def test_mc_interval_coverage(statistic, alpha):
    runs = mc_runs(alpha)[statistic]
    ms = _case_ms(statistic, alpha)
    truth = np.sqrt(true_variance(statistic, alpha, runs["var"]))
    # the reported interval is the χ² interval of the reported dev and EDF
    full = slice(0, R_FULL)
    lo, hi = deviation_interval(runs["dev"][full], runs["edf"][full], ONE_SIGMA)
    np.testing.assert_allclose(runs["low"][full], lo, rtol=1e-12)
    np.testing.assert_allclose(runs["high"][full], hi, rtol=1e-12)
    band_lo, band_hi = COVERAGE_BAND
    for j, m in enumerate(ms):
        label = f"{statistic} {NOISE[alpha]} m={m}"
        coverage = np.mean((runs["low"][:, j] <= truth[j]) & (truth[j] <= runs["high"][:, j]))
        nu_true = (discrete_edf(alpha, statistic, m, N_MC) if statistic in GREENHALL_STATS
                   else nu_mc_and_se(runs["var"][:, j])[0])
        expected = predicted_coverage(runs["edf"][0, j], nu_true)
        sd = math.sqrt(expected * (1 - expected) / R_MC)
        # 1. The expected coverage of the reported interval is inside the band:
        #    the documented model gaps move it to 63–75 %, never out. (Not for the total
        #    variances: without an exact EDF their expectation comes from ν_MC itself,
        #    ±1 point, and MTOT FFM, whose rule §2.5 puts 25 % on the conservative side
        #    at m = 4, expects ~75 %.)
        if statistic in GREENHALL_STATS:
            assert band_lo <= expected <= band_hi, f"{label}: expected coverage {expected:.1%}"
        # 2. The measured coverage is the expected one within binomial error.
        assert abs(coverage - expected) <= Z_STAT * sd, f"{label}: {coverage:.1%} vs {expected:.1%}"
        # 3. The criterion, 60–76 % over the R runs, wherever R decides it. Where
        #    the expectation is within 2.5 sd (~5 points) of an edge, the outcome depends
        #    on the seed (binomial chance of a miss 1–25 % per row at R = 500), and 1. and
        #    2. are the test: 19 of the 72 rows, pred < 65.3 % or > 70.9 % in the table
        #    above (m = 1 of WFM and of OHDEV FFM/RWFM, 63–64 %; RWFM OADEV/MDEV m = 1,
        #    74.8 %, the rule being 31 % conservative; FPM OADEV/OHDEV at m ≥ 4 and WFM
        #    OADEV/OHDEV at m = 4, 71–72.5 %; MTOT WPM and FFM). For the other 53 rows
        #    the chance of a miss is below 0.3 % each, 2.6 % in all.
        if band_lo + 2.5 * sd <= expected <= band_hi - 2.5 * sd:
            assert band_lo <= coverage <= band_hi, f"{label}: coverage {coverage:.1%} of the 68.3 % interval"
        # The band has power: an interval whose EDF is twice the true one shrinks by
        # 1/√2 (coverage ≈ 52 %), half the true one grows by √2 (≈ 84 %).
        for factor, outside in ((2.0, lambda c: c < band_lo), (0.5, lambda c: c > band_hi)):
            lo_f, hi_f = deviation_interval(runs["dev"][:, j], factor * nu_true, ONE_SIGMA)
            wrong = np.mean((lo_f <= truth[j]) & (truth[j] <= hi_f))
            assert outside(wrong), (label, factor, wrong)


@pytest.mark.parametrize("statistic", GREENHALL_STATS)
@pytest.mark.parametrize("alpha", list(NOISE), ids=list(NOISE.values()))
def test_rule_vs_exact_discrete_edf(statistic, alpha):
    # No simulation: the reported EDF against the exact EDF of discrete power-law
    # noise, within the documented model gap (model_gap). A factor 2 either way in the
    # rule is rejected at every m.
    for m in M_MC:
        res_edf = edf(statistic, alpha, m, N_MC)
        nu_ex = discrete_edf(alpha, statistic, m, N_MC)
        below, above = model_gap(statistic, alpha, m)
        lo, hi = -math.log1p(below), math.log1p(above)
        assert lo <= math.log(nu_ex / res_edf) <= hi, (m, nu_ex, res_edf)
        for wrong in (2.0 * res_edf, 0.5 * res_edf):
            assert not lo <= math.log(nu_ex / wrong) <= hi, (m, nu_ex, wrong)


def test_discrete_edf_closed_forms():
    # Where the terms are independent or a simple MA process, ν is known by hand:
    # WPM OADEV m = 1: z_i = x_{i+2} − 2x_{i+1} + x_i has lag-1/2 correlations −2/3, 1/6;
    # RWFM OADEV m = 1: z_i = y_{i+1} − y_i is white, ν = M = N − 2.
    N = 1001
    assert discrete_edf(-2, "oadev", 1, N) == pytest.approx(N - 2, rel=1e-9)
    M = N - 2
    rho1, rho2 = -4 / 6, 1 / 6
    nu = M**2 / (M + 2 * ((M - 1) * rho1**2 + (M - 2) * rho2**2))
    assert discrete_edf(2, "oadev", 1, N) == pytest.approx(nu, rel=1e-9)
    # The Greenhall model of white PM is the discrete one: its basic sum is exact (to
    # rounding); MDEV past J_max = 100 summands (m ≥ 34 here) uses the fitted Table 1
    # asymptote (a0 − a1/r)/r, good to ~1e-3.
    for stat in GREENHALL_STATS:
        for m in (1, 3, 10, 33):
            assert discrete_edf(2, stat, m, N) == pytest.approx(edf(stat, 2, m, N), rel=1e-12)
    assert discrete_edf(2, "mdev", 40, N) == pytest.approx(edf("mdev", 2, 40, N), rel=2e-3)


# =====================================================================================
# Part 1b — the default path users get: identified noise type → EDF → interval
# =====================================================================================

# No alpha=: each run's noise type is identified per τ (lag-1 ACF where ⌊N/m⌋ ≥ 30, B1 and
# R(n) below, α carried past 2×stop ratio averages), which sets the EDF and the interval.
# Truth: the exact discrete expectation of the statistic (expected_variance_discrete).
# m = 1, 16 are lag-1 rows, m = 128, 512 B1 rows of N = 2049 (m = 512 is carried for
# OADEV/OHDEV: 4 averages < 8). Criterion: the coverage of the nominal 68.3 % interval is
# within ±DEFAULT_TARGET of nominal; an observed coverage fails when it lies more than 3
# binomial SE (2.3 points at R = 400) outside that band, i.e. beyond ±12.0 points.
#
# Coverage in % of the 68.3 % interval, R = 1000 runs (seed [20261124, α + 10]): before the
# Stable32 few-averages rule and R(n) for every family (noiseid) → with them → with the
# redder-type EDF rule as well (attach.edf_alpha):
#
#   noise stat    m=1    m=16                m=128               m=512
#   WPM   oadev   68.4   65.9                99.9 → 75.1 → 75.1  100  → 74.4 → 74.4
#   WPM   mdev    68.4   67.8                70.4 → 70.6 → 70.6  78.3 → 75.9 → 75.9
#   WPM   ohdev   68.9   66.8                99.9 → 75.0 → 75.0  100  → 75.7 → 75.7
#   FPM   oadev   66.7   58.3 → 58.3 → 71.2  77.8 → 79.1 → 79.1  87.3 → 83.0 → 83.1
#   FPM   mdev    66.7   62.7 → 62.7 → 66.2  70.0 → 70.0 → 70.1  73.1 → 70.7 → 70.7
#   FPM   ohdev   68.5   57.6 → 57.6 → 71.9  78.3 → 79.3 → 79.3  86.1 → 82.6 → 82.6
#   WFM   oadev   65.1   70.2 → 70.2 → 70.4  64.9 → 64.6 → 69.8  60.7 → 65.9 → 75.0
#   WFM   mdev    65.1   67.4                69.4 → 69.5 → 69.9  74.3 → 73.1 → 73.9
#   WFM   ohdev   67.1   71.1                65.0 → 65.1 → 69.7  63.7 → 66.7 → 76.0
#   FFM   oadev   66.9   72.8                66.4 → 63.6 → 69.9  56.7 → 61.9 → 72.0
#   FFM   mdev    66.9   72.6                67.0 → 66.6 → 69.2  73.2 → 70.7 → 76.3
#   FFM   ohdev   62.5   69.0                65.8 → 62.8 → 67.3  59.8 → 62.7 → 71.5
#   RWFM  oadev   73.7   69.8                66.0 → 62.1 → 67.8  61.1 → 64.5 → 72.7
#   RWFM  mdev    73.7   69.1                67.8 → 64.7 → 69.8  69.6 → 70.3 → 76.0
#   RWFM  ohdev   62.8   69.6                67.2 → 66.1 → 67.4  64.0 → 66.6 → 72.2
#
# (m = 1 rows are unchanged.) Largest miss first 31.7 points, then 14.7, now 14.8 (over);
# within ±5 points 39 → 40 → 42 of 60 cases, within ±8 points 47 → 54 → 56; lowest cell
# 56.7 → 57.6 → 62.5. Outside ±5 now:
# * m = 1 (RWFM OADEV/MDEV 73.7, FFM/RWFM OHDEV 62.5/62.8): the EDF rule's documented
#   model gap at m = 1 (test_mc_interval_coverage gets the same with α forced);
# * FPM with OADEV/OHDEV at the B1 rows (DEFAULT_KNOWN_GAPS) 79–83 %: the FPM EDF rule of
#   the unmodified statistics is 20–25 % conservative (numerics §2.5) and R(n) calls 25 %
#   of runs WPM, which the redder-type rule sends back to FPM's EDF. (At m = 16 lag-1 calls
#   FPM WPM in 59 % of runs; with the WPM EDF that covered 58 %, the redder-type rule
#   brings it to 71–72 %.)
# * WPM at B1 rows, OADEV/OHDEV/MDEV 74–76 %: R(n) calls 20 % of runs FPM (wider);
# * m = 512 (4 averages) 73.9–76.3 % for WFM, FFM and RWFM: the Greenhall EDF at 4
#   averages is conservative; the undercovering misidentifications that used to offset it
#   now get the redder type's EDF.
DEFAULT_N = 2049
DEFAULT_MS = (1, 16, 128, 512)
DEFAULT_STATS = ("oadev", "mdev", "ohdev")
DEFAULT_R = 400
DEFAULT_TARGET = 0.05
DEFAULT_Z = 3.0
#: Cases whose coverage is outside ±DEFAULT_TARGET for an explained reason (see above),
#: held to a band that still rejects the 99.9–100 % of a white PM called flicker PM.
DEFAULT_KNOWN_GAPS = {(s, 1, m): (0.50, 0.90) for s in ("oadev", "ohdev") for m in (128, 512)}
DEFAULT_CASES = [(s, a) for a in NOISE for s in DEFAULT_STATS]


@functools.cache
def default_path_runs(alpha: int) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """{statistic: (covered (R, m) bool, identified α (R, m))} through the default path."""
    rng = np.random.default_rng([20261124, alpha + 10])
    truth = {s: np.sqrt(expected_variance_discrete(alpha, 1.0, list(DEFAULT_MS), statistic=s))
             for s in DEFAULT_STATS}
    covered = {s: np.zeros((DEFAULT_R, len(DEFAULT_MS)), dtype=bool) for s in DEFAULT_STATS}
    ident = {s: np.zeros((DEFAULT_R, len(DEFAULT_MS))) for s in DEFAULT_STATS}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", sigmatau.RangeWarning)  # m = 512 is past N/4 for MDEV
        for r in range(DEFAULT_R):
            x = power_law_noise(DEFAULT_N, alpha, data_type="phase", rng=rng)
            for s in DEFAULT_STATS:
                res = getattr(sigmatau, s)(x, data_type="phase", m=list(DEFAULT_MS))
                assert np.all(np.isfinite(res.ci_low)) and np.all(np.isfinite(res.ci_high)), res.ci_reason
                covered[s][r] = (res.ci_low <= truth[s]) & (truth[s] <= res.ci_high)
                ident[s][r] = res.alpha
    return {s: (covered[s], ident[s]) for s in DEFAULT_STATS}


@pytest.mark.slow
@pytest.mark.parametrize("statistic, alpha", DEFAULT_CASES, ids=[f"{s}-{NOISE[a]}" for s, a in DEFAULT_CASES])
def test_default_path_interval_coverage(statistic, alpha):
    covered, ident = default_path_runs(alpha)[statistic]
    sd = math.sqrt(ONE_SIGMA * (1 - ONE_SIGMA) / DEFAULT_R)
    for j, m in enumerate(DEFAULT_MS):
        coverage = float(covered[:, j].mean())
        band = DEFAULT_KNOWN_GAPS.get((statistic, alpha, m),
                                      (ONE_SIGMA - DEFAULT_TARGET, ONE_SIGMA + DEFAULT_TARGET))
        lo, hi = band[0] - DEFAULT_Z * sd, band[1] + DEFAULT_Z * sd
        assert lo <= coverage <= hi, (
            f"{statistic} {NOISE[alpha]} m={m}: coverage {coverage:.1%} outside [{lo:.1%}, {hi:.1%}]"
            f" (identified correctly in {np.mean(ident[:, j] == alpha):.0%} of runs)")


# The last octaves of a long record, on the default path: N = 2¹⁵ + 1 phase points, the
# whole octave grid computed (so shorter rows inform the long ones), coverage read at
# m = 1024 … 8192 (32, 16, 8 and 4 averages: lag-1, B1, carried, carried). Before the
# redder-type EDF rule (attach.edf_alpha), the same R = 1000 runs (seed [20261128, α + 10]):
#
#   noise stat    m=128  1024   2048   4096   8192
#   FPM   oadev   0.373  0.207  0.791  0.832  0.868   (lag-1 calls flicker PM white)
#   FPM   ohdev   0.375  0.204  0.803  0.839  0.862
#   WFM   oadev   0.662  0.646  0.639  0.595  0.585   (B1 calls white FM FPM/WPM in 16–26 %)
#   WFM   ohdev   0.662  0.631  0.650  0.584  0.575
#   RWFM  oadev   0.681  0.695  0.641  0.637  0.630
#
# and with it, R = 1000 (the test's runs):
#
#   noise stat    m=128  1024   2048   4096   8192
#   WPM   oadev   0.683  0.699  0.746  0.866  0.863
#   WPM   mdev    0.666  0.691  0.721  0.732  0.794
#   WPM   ohdev   0.681  0.707  0.753  0.870  0.856
#   FPM   oadev   0.711  0.723  0.802  0.878  0.906
#   FPM   mdev    0.675  0.686  0.703  0.711  0.775
#   FPM   ohdev   0.705  0.719  0.811  0.884  0.904
#   WFM   oadev   0.662  0.714  0.711  0.703  0.725
#   WFM   mdev    0.676  0.709  0.698  0.673  0.723
#   WFM   ohdev   0.662  0.693  0.721  0.703  0.722
#   FFM   oadev   0.712  0.744  0.747  0.734  0.786
#   FFM   mdev    0.721  0.737  0.733  0.739  0.785
#   FFM   ohdev   0.692  0.707  0.712  0.701  0.747
#   RWFM  oadev   0.681  0.697  0.703  0.746  0.755
#   RWFM  mdev    0.669  0.704  0.713  0.748  0.780
#   RWFM  ohdev   0.681  0.679  0.700  0.723  0.738
#
# No cell is below nominal − 5 points any more (lowest 0.662). Above nominal + 5 points,
# all on the safe side: white and flicker PM with OADEV/OHDEV from 16 averages down, where
# a type seen redder at some shorter τ (R(n) calls white PM flicker PM in a quarter of
# runs) sets the EDF and flicker PM's EDF for the unmodified statistics is itself 20–25 %
# conservative (α forced, R = 300: FPM OADEV 0.733/0.773 at m = 4096/8192); and m = 8192,
# 4 averages, where the Greenhall EDF is conservative with α forced too (FFM OADEV 0.757,
# MDEV 0.793). The lower bound is what this test guards: at R = 1000 it is 0.589, and the
# old rule's 0.57 (WFM, RWFM) and 0.42 (FPM, m = 128) fail it.
LONG_N = 2**15 + 1
LONG_MS = [2**k for k in range(14)]
LONG_READ = (128, 1024, 2048, 4096, 8192)
LONG_R = 1000
#: Cells above nominal + DEFAULT_TARGET for the reasons above: held below 0.95.
LONG_KNOWN_OVER = {(s, a, 8192) for s in DEFAULT_STATS for a in NOISE} \
    | {(s, a, m) for s in ("oadev", "ohdev") for a in (2, 1) for m in (2048, 4096)}


@functools.cache
def long_path_coverage(alpha: int) -> dict[str, np.ndarray]:
    """{statistic: coverage at LONG_READ} over LONG_R records through the default path."""
    rng = np.random.default_rng([20261128, alpha + 10])
    cols = [LONG_MS.index(m) for m in LONG_READ]
    truth = {s: np.sqrt(expected_variance_discrete(alpha, 1.0, list(LONG_READ), statistic=s))
             for s in DEFAULT_STATS}
    covered = {s: np.zeros((LONG_R, len(LONG_READ)), dtype=bool) for s in DEFAULT_STATS}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", sigmatau.RangeWarning)  # m = 8192 is past N/4 for MDEV
        for r in range(LONG_R):
            x = power_law_noise(LONG_N, alpha, data_type="phase", rng=rng)
            for s in DEFAULT_STATS:
                res = getattr(sigmatau, s)(x, data_type="phase", m=LONG_MS)
                covered[s][r] = (res.ci_low[cols] <= truth[s]) & (truth[s] <= res.ci_high[cols])
    return {s: covered[s].mean(axis=0) for s in DEFAULT_STATS}


@pytest.mark.slow
@pytest.mark.parametrize("statistic, alpha", DEFAULT_CASES, ids=[f"{s}-{NOISE[a]}" for s, a in DEFAULT_CASES])
def test_long_record_last_octaves_coverage(statistic, alpha):
    coverage = long_path_coverage(alpha)[statistic]
    slack = DEFAULT_Z * math.sqrt(ONE_SIGMA * (1 - ONE_SIGMA) / LONG_R)
    for c, m in zip(coverage, LONG_READ):
        hi = 0.95 if (statistic, alpha, m) in LONG_KNOWN_OVER else ONE_SIGMA + DEFAULT_TARGET + slack
        assert ONE_SIGMA - DEFAULT_TARGET - slack <= c <= hi, f"{statistic} {NOISE[alpha]} m={m}: {c:.3f}"


# =====================================================================================
# Part 2 — end to end: public statistics against Stable32 Min/Max Sigma
# =====================================================================================


dataset = refdata.dataset


def _s32_tables():
    out = []
    for s in ("adev", "oadev", "mdev", "tdev", "hdev", "ohdev", "totdev"):
        out.append(("phasedat", f"phasedat/phase_dat_{s}_octave.txt", s))
    for s, f in (("adev", "ADEV_decade"), ("oadev", "OADEV_octave"), ("mdev", "MDEV_octave"),
                 ("tdev", "TDEV_octave"), ("hdev", "HDEV_octave"), ("ohdev", "OHDEV_octave"),
                 ("totdev", "TOTDEV_octave")):
        out.append(("gps", f"gps/stable32_{f}.txt", s))
    for s in ("adev", "oadev", "mdev", "tdev", "hdev", "ohdev", "totdev"):
        out.append(("ocxo", f"ocxo/{s}_octave.txt", s))
    # tic_adev.txt is an all-τ run printed without Min/Max Sigma
    for s in ("oadev", "mdev", "tdev", "hdev", "ohdev", "totdev"):
        out.append(("tic", f"Keysight53230A_ti_noise_floor/tic_{s}.txt", s))
    out.append(("pink", "pink_frequency/s32_oadev_octave.txt", "oadev"))
    return out


S32_TABLES = _s32_tables()
S32_IDS = [p for _, p, _ in S32_TABLES]


def _run(name: str, statistic: str, m, **kw) -> sigmatau.StabilityResult:
    data, rate, data_type = dataset(name)
    with warnings.catch_warnings():
        # the tables go past the default ⌊N/stop⌋ grid on purpose (test_reference_allan)
        warnings.simplefilter("ignore", sigmatau.RangeWarning)
        return getattr(sigmatau, statistic)(data, rate=rate, data_type=data_type, m=m, **kw)


def _interval_errors(table, dev, low, high, *, ratios: bool):
    """Relative errors of (low, high) against Min/Max Sigma, or with ``ratios`` of
    (low/dev, high/dev) against (Min/Sigma, Max/Sigma)."""
    if ratios:
        return (low / dev) / (table.min_sigma / table.sigma) - 1.0, \
               (high / dev) / (table.max_sigma / table.sigma) - 1.0
    return low / table.min_sigma - 1.0, high / table.max_sigma - 1.0


def _check_rows(name, path, table, dev, low, high, rows):
    """Assert the interval (low, high) of the deviations dev matches the table on
    ``rows`` (boolean mask).

    The ocxo *_octave tables were computed on f/1e7 = 1 + y, whose round-off moves
    Sigma itself by up to 2e-3 (test_reference_allan._OCXO_OCTAVE_ROUNDOFF): there
    the interval ratios are compared. Everywhere else the bounds themselves are.
    Rows in test_confidence.KNOWN_DEVIATIONS are held, as there, to their measured
    error (on the ratios, which is what that file measures from the table's Sigma)
    and must be wider than Stable32's.
    """
    el, eh = _interval_errors(table, dev, low, high, ratios=name == "ocxo")
    rl, rh = _interval_errors(table, dev, low, high, ratios=True)
    for i in np.flatnonzero(rows):
        m = int(table.af[i])
        known = KNOWN_DEVIATIONS.get((path, m))
        if known is None:
            err = max(abs(el[i]), abs(eh[i]))
            assert err < S32_RTOL, f"{path} m={m} alpha={table.alpha[i]}: {el[i]:.2e}, {eh[i]:.2e}"
        else:
            # FPM at T/τ < 8: Stable32's ν is above SP1065's; ours is the wider interval
            err = max(abs(rl[i]), abs(rh[i]))
            assert err == pytest.approx(known, rel=0.1), f"{path} m={m}: {err:.2e}"
            assert rl[i] < 0 < rh[i]


# Worst relative error of the interval against Min/Max Sigma (ocxo: of the interval
# ratios), measured when this file was written: rows checked with alpha forced to the
# table's value, worst error; rows where the identified alpha equals the table's (and an
# interval exists), worst error. TOTDEV WPM rows have no sigmatau EDF; the gps TOTDEV
# m = 65536 row is in KNOWN_DEVIATIONS (3.3e-3, ours wider).
#
#   table                                           forced  worst  ident  worst
#   phasedat/phase_dat_adev_octave.txt                8/ 8 3.0e-04    7 3.0e-04
#   phasedat/phase_dat_oadev_octave.txt               8/ 8 3.3e-04    7 3.3e-04
#   phasedat/phase_dat_mdev_octave.txt                8/ 8 4.0e-04    7 4.0e-04
#   phasedat/phase_dat_tdev_octave.txt                8/ 8 4.1e-04    7 4.1e-04
#   phasedat/phase_dat_hdev_octave.txt                8/ 8 3.5e-04    7 3.5e-04
#   phasedat/phase_dat_ohdev_octave.txt               8/ 8 3.6e-04    7 3.6e-04
#   phasedat/phase_dat_totdev_octave.txt              9/ 9 3.3e-04    8 3.3e-04
#   gps/stable32_ADEV_decade.txt                     15/15 4.0e-04   14 4.0e-04
#   gps/stable32_OADEV_octave.txt                    16/16 1.9e-04   15 1.3e-04
#   gps/stable32_MDEV_octave.txt                     16/16 3.5e-04   15 3.5e-04
#   gps/stable32_TDEV_octave.txt                     16/16 3.4e-04   15 3.4e-04
#   gps/stable32_HDEV_octave.txt                     16/16 4.4e-04   15 4.4e-04
#   gps/stable32_OHDEV_octave.txt                    16/16 1.6e-04   15 1.4e-04
#   gps/stable32_TOTDEV_octave.txt                    9/17 5.3e-04    9 5.3e-04  (+1 known; 7 WPM)
#   ocxo/adev_octave.txt                             12/12 3.6e-04   10 3.6e-04
#   ocxo/oadev_octave.txt                            13/13 3.1e-04   11 3.1e-04
#   ocxo/mdev_octave.txt                             13/13 3.5e-04   11 3.5e-04
#   ocxo/tdev_octave.txt                             13/13 3.8e-04   11 3.8e-04
#   ocxo/hdev_octave.txt                             12/12 2.7e-04   10 2.7e-04
#   ocxo/ohdev_octave.txt                            13/13 3.6e-04   11 3.6e-04
#   ocxo/totdev_octave.txt                           14/14 2.7e-04   11 2.7e-04
#   Keysight53230A_ti_noise_floor/tic_oadev.txt      14/14 4.4e-04   13 3.0e-04
#   Keysight53230A_ti_noise_floor/tic_mdev.txt       14/14 3.5e-04   13 3.5e-04
#   Keysight53230A_ti_noise_floor/tic_tdev.txt       14/14 3.7e-04   13 3.7e-04
#   Keysight53230A_ti_noise_floor/tic_hdev.txt       14/14 3.3e-04   13 3.3e-04
#   Keysight53230A_ti_noise_floor/tic_ohdev.txt      14/14 3.3e-04   13 3.3e-04
#   Keysight53230A_ti_noise_floor/tic_totdev.txt      4/15 3.0e-04    2 3.0e-04  (11 WPM)
#   pink_frequency/s32_oadev_octave.txt              12/12 4.0e-04   11 4.0e-04


@pytest.mark.parametrize("name, path, statistic", S32_TABLES, ids=S32_IDS)
def test_stable32_interval_forced_alpha(name, path, statistic):
    table = load_table(path)
    assert np.all(table.min_sigma > 0) and np.all(table.max_sigma > 0)
    dev, low, high = (np.full(table.af.size, np.nan) for _ in range(3))
    checked = np.zeros(table.af.size, dtype=bool)
    for a in np.unique(table.alpha):  # one call per distinct alpha
        rows = table.alpha == a
        if statistic == "totdev" and a == 2:
            # Stable32 uses the SP1065 Table 5 WPM form; sigmatau refuses it (MC: that
            # overstates ν up to 3x). test_confidence checks Stable32's numbers.
            with pytest.raises(ParameterError, match="WPM"):
                _run(name, statistic, table.af[rows], alpha=int(a))
            continue
        res = _run(name, statistic, table.af[rows], alpha=int(a))
        np.testing.assert_array_equal(res.m, table.af[rows])
        assert np.all(res.alpha == a) and np.all(np.isnan(res.alpha_estimate))
        dev[rows], low[rows], high[rows] = res.dev, res.ci_low, res.ci_high
        checked |= rows
    wpm_total = (table.alpha == 2) if statistic == "totdev" else np.zeros(table.af.size, dtype=bool)
    np.testing.assert_array_equal(checked, ~wpm_total)
    assert checked.sum() >= 4
    _check_rows(name, path, table, dev, low, high, checked)


# Rows where the identified α (equal to Stable32's) is whiter than one identified at a
# shorter τ and too few averages remain to rule the redder type out, or white PM follows
# flicker PM (attach.edf_alpha): our EDF is the smallest over those types, so our
# interval contains Stable32's. Its (low, high) relative to Stable32's Min/Max Sigma:
#   gps OADEV / OHDEV m = 32 … 512 (WPM after FPM):         −2.0e-3/+2.0e-3 … −8.6e-3/+8.9e-3
#   gps MDEV / TDEV m = 32 … 512:                            −9.5e-4/+9.9e-4 … −3.7e-3/+4.2e-3
#   gps OADEV / OHDEV m = 2048 (FPM → WPM, a GPS servo):   −1.5e-2/+1.6e-2, −1.6e-2/+1.7e-2
#   gps MDEV / TDEV m = 2048:                                −7.1e-3/+9.1e-3
#   gps TOTDEV m = 32768, 65536:                             −0.12/+0.24, −0.12/+0.34
#   ocxo OADEV m = 256 … 4096 (RWFM → FFM):                  −8.0e-3/+1.1e-2 … −4.3e-2/+0.23
#   ocxo MDEV, TDEV, OHDEV, TOTDEV m = 256 … 4096 (8192):     up to −5.0e-2/+0.43 (TOTDEV 8192)
#   pink OADEV m = 128 … 2048 (FFM → WFM):                   −1.6e-2/+2.2e-2 … −4.3e-2/+0.23
# The pink record is flicker FM by construction, so there Stable32's whiter type is a
# misidentification and the redder EDF is the right one. ADEV and HDEV rows of the same
# kind keep Stable32's interval: their EDF is smallest for the identified type.
_OCXO_REDDER = [256, 1024, 2048, 4096]
_GPS_REDDER = [32, 64, 128, 256, 512, 2048]
S32_REDDER_ROWS = {
    "gps/stable32_OADEV_octave.txt": _GPS_REDDER, "gps/stable32_MDEV_octave.txt": _GPS_REDDER,
    "gps/stable32_TDEV_octave.txt": _GPS_REDDER, "gps/stable32_OHDEV_octave.txt": _GPS_REDDER,
    "gps/stable32_TOTDEV_octave.txt": [32768, 65536],
    "ocxo/oadev_octave.txt": _OCXO_REDDER, "ocxo/mdev_octave.txt": _OCXO_REDDER,
    "ocxo/tdev_octave.txt": _OCXO_REDDER, "ocxo/ohdev_octave.txt": _OCXO_REDDER,
    "ocxo/totdev_octave.txt": _OCXO_REDDER + [8192],
    "pink_frequency/s32_oadev_octave.txt": [128, 256, 512, 1024, 2048],
}


@pytest.mark.parametrize("name, path, statistic", S32_TABLES, ids=S32_IDS)
def test_stable32_interval_identified_alpha(name, path, statistic):
    # No alpha: where sigmatau's noise identification agrees with Stable32's Alpha
    # column, the interval matches as well.
    table = load_table(path)
    res = _run(name, statistic, table.af)
    same = res.alpha == table.alpha
    assert same.sum() >= 0.75 * table.af.size, (res.alpha, table.alpha)
    wpm_total = same & (table.alpha == 2) if statistic == "totdev" else np.zeros_like(same)
    for i in np.flatnonzero(wpm_total):
        assert np.isnan(res.ci_low[i]) and np.isnan(res.ci_high[i]) and "WPM" in res.ci_reason[i]
    redder = np.array([r.startswith("EDF for alpha=") for r in res.ci_reason])
    _check_rows(name, path, table, res.dev, res.ci_low, res.ci_high, same & ~wpm_total & ~redder)
    # Rows with too few averages to rule out the redder type seen at a shorter τ
    # (attach.edf_alpha): there our interval deliberately contains Stable32's.
    el, eh = _interval_errors(table, res.dev, res.ci_low, res.ci_high, ratios=name == "ocxo")
    for i in np.flatnonzero(same & redder):
        assert el[i] < S32_RTOL and eh[i] > -S32_RTOL, (path, int(table.af[i]), el[i], eh[i])
    assert sorted(int(m) for m in table.af[same & redder]) == S32_REDDER_ROWS.get(path, [])


# --- keywords ci= and confidence= ----------------------------------------------------------

ALL_STATS = ("adev", "oadev", "mdev", "tdev", "hdev", "ohdev", "totdev", "mtotdev", "ttotdev", "htotdev")
PHASE_M = [1, 2, 4, 8, 16, 32, 64, 128]


@pytest.mark.parametrize("statistic", ALL_STATS)
def test_ci_simple_is_dev_over_sqrt_n(statistic):
    res = _run("phasedat", statistic, PHASE_M, ci="simple")
    err = res.dev / np.sqrt(res.n)
    np.testing.assert_allclose(res.ci_low, np.maximum(res.dev - err, 0.0), rtol=1e-13)
    np.testing.assert_allclose(res.ci_high, res.dev + err, rtol=1e-13)
    assert res.confidence == ONE_SIGMA
    chi2 = _run("phasedat", statistic, PHASE_M)
    np.testing.assert_array_equal(res.alpha, chi2.alpha)  # same noise identification


@pytest.mark.parametrize("statistic", ALL_STATS)
def test_ci_none_leaves_fields_empty(statistic):
    res = _run("phasedat", statistic, PHASE_M, ci=None)
    for field in ("alpha", "alpha_estimate", "edf", "ci_low", "ci_high", "confidence", "ci_reason"):
        assert getattr(res, field) is None, field
    np.testing.assert_array_equal(res.dev, _run("phasedat", statistic, PHASE_M).dev)


@pytest.mark.parametrize("statistic", ALL_STATS)
def test_confidence_95_widens_interval(statistic):
    base = _run("phasedat", statistic, PHASE_M, alpha=0)
    wide = _run("phasedat", statistic, PHASE_M, alpha=0, confidence=0.95)
    assert base.confidence == ONE_SIGMA and wide.confidence == 0.95
    np.testing.assert_array_equal(wide.edf, base.edf)
    ok = np.isfinite(base.ci_low)
    assert ok.sum() >= len(PHASE_M) - 1
    assert np.all(wide.ci_low[ok] < base.ci_low[ok]) and np.all(base.ci_low[ok] < base.dev[ok])
    assert np.all(wide.ci_high[ok] > base.ci_high[ok]) and np.all(base.ci_high[ok] > base.dev[ok])
    lo, hi = deviation_interval(base.dev[ok], base.edf[ok], 0.95)
    np.testing.assert_allclose(wide.ci_low[ok], lo, rtol=1e-12)
    np.testing.assert_allclose(wide.ci_high[ok], hi, rtol=1e-12)
