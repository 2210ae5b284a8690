"""Theo1, TheoBR and TheoH (sigmatau.stats.theo).

Sources (numerics.md, tests/data/allantools/README.md):

* NBS 1000-point set, numerics.md §7.2: Theo1 at m = 10, 100, 1000 are Stable32
  values quoted by allantools (4-5 digits) that numerics.md reproduced to 7
  digits; κ = 1.085666 (n = 30) and the three TheoBR values were computed
  independently (no published reference). Held to half a unit in the last
  printed digit.
* Stable32 Theo1 tables on PHASE.DAT with "Alpha = 0" (raw Theo1): five
  significant digits, so the deviation is held to a relative 1e-4 and the
  "Thêo1 #" column, (N−m)·m/2 printed with five digits, must be our count
  rounded to those digits.
* phasedat/phase_dat_theo1.txt (header "Alpha = 1"): every value is raw Theo1
  × 0.7764 (variance × 0.602787, constant in m to the printed digits), which
  numerics.md §3/§8 item 13 left unexplained. It is not the published FPM
  bias (Howe & Tasset's ratio falls from 0.588 at m = 10 to 0.253 at m = 998):
  it is TheoBR's κ averaged over Stable32's "Run" span n = ⌊N/6⌋ − 3 = 163
  (κ = 0.6027870), and Alpha = 1 is the noise type of that κ. Held to 1e-4
  through ``theobr(kappa="run")``; nothing is fitted.
* Theo1 bias table (Howe & Tasset 2004 Table 1 as numerics.md §3 gives it):
  (a, b, c) typed from the table, the ratio a + b/t^c evaluated here.

The fast Theo1 sums (lag sums over segments, and the incremental pass used for
many factors) are held to the plain double sum of numerics.md §1.12, written
below as the oracle.
"""

from __future__ import annotations

import math
import warnings
from decimal import Decimal

import numpy as np
import pytest

import refdata
import sigmatau
from sigmatau.stats import theo, theo_sums
from sigmatau.stats.allan import oadev
from sigmatau.datasets import nbs1000
from sigmatau.errors import DataError, ParameterError, RangeWarning

STABLE32_RTOL = 1e-4
# Agreement required between any computation path and the plain sum.
ORACLE_RTOL = 1e-9


def assert_printed(value: float, printed: str) -> None:
    """``value`` rounds to ``printed`` at the digits shown there."""
    ref = float(printed)
    half = 0.5 * 10.0 ** Decimal(printed).as_tuple().exponent
    np.testing.assert_allclose(value, ref, rtol=half / abs(ref), atol=0.0)


# --- the oracle: numerics.md §1.12, 0-based ---------------------------------------------


def theo1_sum_plain(x: np.ndarray, m: int) -> float:
    """Σ_{i=0}^{N-m-1} Σ_{δ=0}^{m/2-1} [(x_i − x_{i−δ+m/2}) + (x_{i+m} − x_{i+δ+m/2})]² / (m/2 − δ).

    Vectorised over i only.
    """
    N = x.size
    h = m // 2
    i = np.arange(N - m)
    total = 0.0
    for delta in range(h):
        t = (x[i] - x[i - delta + h]) + (x[i + m] - x[i + delta + h])
        total += float(np.sum(t * t)) / (h - delta)
    return total


def theo1_var_plain(x: np.ndarray, m: int, tau0: float = 1.0) -> float:
    return theo1_sum_plain(x, m) / (0.75 * (x.size - m) * (m * tau0) ** 2)


def test_oracle_matches_scalar_loops():
    # The oracle itself against the formula with both sums as Python loops.
    x = np.random.default_rng(0).standard_normal(13)
    for m in (2, 4, 6, 12):
        h = m // 2
        ref = 0.0
        for i in range(x.size - m):
            for d in range(h):
                ref += ((x[i] - x[i - d + h]) + (x[i + m] - x[i + d + h])) ** 2 / (h - d)
        assert theo1_sum_plain(x, m) == pytest.approx(ref, rel=1e-14)


# --- test series: phase data of four characters ------------------------------------------


def phase_series(kind: str, n: int, rng: np.random.Generator) -> np.ndarray:
    """Phase of white PM, white FM (cumsum), random-walk FM (cumsum²) and blue PM (diff)."""
    w = rng.standard_normal(n + 1)
    if kind == "white":
        return w[:n]
    if kind == "cumsum":
        return np.cumsum(w)[:n]
    if kind == "cumsum2":
        return np.cumsum(np.cumsum(w))[:n]
    if kind == "diff":
        return np.diff(w)
    raise ValueError(kind)


KINDS = ("white", "cumsum", "cumsum2", "diff")
SIZES = (101, 256, 1009)  # odd prime, power of two, larger prime


def factors(n: int) -> list[int]:
    top = n - 1 if (n - 1) % 2 == 0 else n - 2
    return sorted({m for m in (2, 4, 10, 16, 64, 100, 256, 500, n // 2 * 2 - 10, top) if 2 <= m <= top})


@pytest.fixture(scope="module")
def oracle_cases():
    rng = np.random.default_rng(20240611)
    cases = []
    for n in SIZES:
        for kind in KINDS:
            x = phase_series(kind, n, rng)
            x = x - np.linspace(x[0], x[-1], n)  # what the driver hands to the kernel
            ms = factors(n)
            cases.append((kind, n, x, np.array(ms), np.array([theo1_sum_plain(x, m) for m in ms])))
    return cases


def test_direct_sum_matches_oracle(oracle_cases):
    for kind, n, x, ms, ref in oracle_cases:
        got = np.array([theo_sums.theo1_sum_direct(x, int(m)) for m in ms])
        np.testing.assert_allclose(got, ref, rtol=1e-12, err_msg=f"{kind} N={n}")


def test_fast_sum_matches_oracle(oracle_cases):
    # The lag-sum form on its own (forced, even where the plain sum would be used):
    # within ORACLE_RTOL on every kind, and within its own rounding-error estimate
    # (the estimate that decides when theo1 falls back to the plain sum).
    # Observed: ≤ 5e-13 (random-walk FM phase), ≤ 2e-14 otherwise.
    for kind, n, x, ms, ref in oracle_cases:
        for m, r in zip(ms, ref):
            got, err = theo_sums.theo1_sum_fast(x, int(m))
            rel = abs(got - r) / r
            assert rel <= ORACLE_RTOL, f"{kind} N={n} m={m}: {rel:.2e}"
            assert rel <= max(err, 1e-13), f"{kind} N={n} m={m}: {rel:.2e} > estimate {err:.2e}"


@pytest.mark.slow
@pytest.mark.parametrize("uncached_fft", [1, 1 << 30])
def test_fast_sum_in_small_pieces_matches_oracle(oracle_cases, monkeypatch, uncached_fft):
    # The memory-bounding pieces of the lag-sum form, forced at small N: lag sums
    # read in chunks of 7 (odd, so chunks straddle every boundary), triangle blocks
    # and segments in groups of a few, and every transform through numpy.fft (the
    # path of long transforms, ≥ 2^18 points) or through scipy.fft.
    monkeypatch.setattr(theo_sums, "CHUNK", 7)
    monkeypatch.setattr(theo_sums, "_BATCH_ELEMENTS", 64)
    monkeypatch.setattr(theo_sums, "_UNCACHED_FFT", uncached_fft)
    for kind, n, x, ms, ref in oracle_cases:
        for m, r in zip(ms, ref):
            got, err = theo_sums.theo1_sum_fast(x, int(m))
            rel = abs(got - r) / r
            assert rel <= ORACLE_RTOL, f"{kind} N={n} m={m}: {rel:.2e}"
            assert rel <= max(err, 1e-13), f"{kind} N={n} m={m}: {rel:.2e} > estimate {err:.2e}"


def test_incremental_sums_match_oracle(oracle_cases):
    # One pass over the record with global lag sums: digits are lost to cancellation
    # on smooth phase at small m (up to 1e-7 here on random-walk FM); the error
    # estimate flags those factors and the dispatcher recomputes them.
    for kind, n, x, ms, ref in oracle_cases:
        got, err = theo_sums.theo1_sums_incremental(x, ms)
        rel = np.abs(got - ref) / ref
        assert np.all(rel <= np.maximum(err, 1e-13)), f"{kind} N={n}"
        assert np.all(rel[err <= theo_sums.FAST_RTOL] <= ORACLE_RTOL)


def test_dispatched_sums_match_oracle(oracle_cases):
    # What theo1 uses: per factor (plain or lag sums), or one incremental pass, with
    # the plain sum wherever the fast forms could lose digits.
    for kind, n, x, ms, ref in oracle_cases:
        np.testing.assert_allclose(theo_sums.theo1_sums(x, ms), ref, rtol=ORACLE_RTOL, err_msg=f"{kind} N={n}")
        every = np.arange(2, n, 2)  # many factors: the incremental pass
        ref_all = np.array([theo1_sum_plain(x, int(m)) for m in every[::7]])
        np.testing.assert_allclose(theo_sums.theo1_sums(x, every)[::7], ref_all, rtol=ORACLE_RTOL)


def test_fast_paths_at_larger_n():
    # Segmented lag sums (many segments) and a long incremental pass, N = 4099 (prime).
    rng = np.random.default_rng(7)
    for kind in KINDS:
        x = phase_series(kind, 4099, rng)
        x = x - np.linspace(x[0], x[-1], x.size)
        for m in (300, 1024, 2000, 4098):
            got, err = theo_sums.theo1_sum_fast(x, m)
            assert err <= theo_sums.FAST_RTOL
            assert got == pytest.approx(theo1_sum_plain(x, m), rel=ORACLE_RTOL)
        ms = 12 + 4 * np.arange(4099 // 30 - 2)  # TheoBR's κ factors
        got = theo_sums.theo1_sums(x, ms)
        for k in (0, 40, ms.size - 1):
            assert got[k] == pytest.approx(theo1_sum_plain(x, int(ms[k])), rel=ORACLE_RTOL)


@pytest.mark.parametrize("kind", KINDS)
def test_public_theo1_with_large_trend(kind):
    # theo1 on phase with a large offset and frequency offset against the oracle on
    # the noise alone: Theo1 ignores a + b·i.
    rng = np.random.default_rng(11)
    n = 1009
    x0 = phase_series(kind, n, rng)
    scale = np.std(np.diff(x0))
    trended = x0 + 1e3 * scale + 100.0 * scale * np.arange(n)
    ms = np.array(factors(n))
    r = theo.theo1(trended, data_type="phase", m=ms, rate=4.0)
    ref = np.array([theo1_var_plain(x0, int(m), tau0=0.25) for m in ms])
    np.testing.assert_allclose(r.var, ref, rtol=ORACLE_RTOL)
    np.testing.assert_array_equal(r.n, (n - ms) * ms // 2)
    np.testing.assert_allclose(r.taus, 0.75 * ms * 0.25)


# --- NBS 1000-point set (numerics.md §7.2) --------------------------------------------------


def test_nbs_theo1():
    r = theo.theo1(nbs1000(), m=[10, 100, 1000])
    for dev, printed in zip(r.dev, ("1.075740e-01", "3.178931e-02", "5.052400e-03")):
        assert_printed(dev, printed)
    np.testing.assert_array_equal(r.taus, [7.5, 75.0, 750.0])
    np.testing.assert_array_equal(r.n, [4955, 45050, 500])


def test_nbs_theobr():
    k = theo.theobr_kappa(nbs1000())
    assert_printed(k.kappa, "1.085666")
    assert (k.n, k.n_points) == (30, 1001)
    r = theo.theobr(nbs1000(), m=[10, 100, 1000])
    for dev, printed in zip(r.dev, ("1.120871e-01", "3.312297e-02", "5.264364e-03")):
        assert_printed(dev, printed)
    assert r.statistic == "theobr"
    assert r.bias == "theobr kappa=1.085666 (n=30)"
    np.testing.assert_allclose(r.bias_factor, 1.0 / k.kappa)
    np.testing.assert_allclose(r.var, k.kappa * theo.theo1(nbs1000(), m=[10, 100, 1000]).var, rtol=1e-15)


def test_kappa_from_its_definition():
    # κ = mean over i = 0…n of OAVAR(9+3i)/Theo1(12+4i), with the plain Theo1 sum.
    y = np.random.default_rng(3).standard_normal(200)
    x = np.concatenate(([0.0], np.cumsum(y)))
    n = x.size // 30 - 3
    i = np.arange(n + 1)
    ratios = oadev(x, data_type="phase", m=9 + 3 * i).var / [theo1_var_plain(x, int(m)) for m in 12 + 4 * i]
    k = theo.theobr_kappa(x, data_type="phase")
    assert k.n == n == 3
    assert k.kappa == pytest.approx(float(np.mean(ratios)), rel=1e-12)
    # The same κ from frequency data, at any rate.
    assert theo.theobr_kappa(y, rate=50.0).kappa == pytest.approx(k.kappa, rel=1e-12)


# --- Stable32 tables on PHASE.DAT ------------------------------------------------------------


def _rounds_to(count: np.ndarray, printed: np.ndarray) -> np.ndarray:
    """Whether each integer rounds to the 5-significant-digit value printed by Stable32."""
    half = 0.5 * 10.0 ** (np.floor(np.log10(count)) - 4)
    return np.abs(count - printed) <= half


@pytest.mark.parametrize("table", ["phase_dat_theo1_alpha0.txt", "phase_dat_theo1_alpha0_decade.txt"])
def test_stable32_theo1(table):
    t = refdata.load_table(f"phasedat/{table}")
    r = theo.theo1(refdata.phase_dat(), data_type="phase", m=t.af)
    np.testing.assert_allclose(r.dev, t.sigma, rtol=STABLE32_RTOL)
    np.testing.assert_allclose(r.taus, t.tau, rtol=1e-12)
    assert np.all(_rounds_to(r.n, t.n)), r.n[~_rounds_to(r.n, t.n)]


def test_stable32_theo1_alpha0_is_published_wfm_bias():
    # Stable32 with Alpha forced to 0: the published WFM ratio is 1, so raw = corrected.
    t = refdata.load_table("phasedat/phase_dat_theo1_alpha0.txt")
    r = theo.theo1(refdata.phase_dat(), data_type="phase", m=t.af, bias="published", alpha=0)
    np.testing.assert_allclose(r.dev, t.sigma, rtol=STABLE32_RTOL)
    np.testing.assert_array_equal(r.bias_factor, 1.0)
    assert r.bias == "published alpha=0"


def test_stable32_theo1_auto_table_is_theobr_with_run_kappa():
    t = refdata.load_table("phasedat/phase_dat_theo1.txt")
    x = refdata.phase_dat()
    r = theo.theobr(x, data_type="phase", m=t.af, kappa="run")
    np.testing.assert_allclose(r.dev, t.sigma, rtol=STABLE32_RTOL)  # measured 4.0e-5
    assert np.all(_rounds_to(r.n, t.n))
    k = theo.theobr_kappa(x, data_type="phase", method="run")
    assert k.n == 1001 // 6 - 3 == 163 and round(k.kappa, 6) == 0.602787
    assert r.bias == "theobr kappa=0.602787 (n=163, run span N/6)"
    # The constant ratio is not the published FPM bias, which varies with m.
    raw = theo.theo1(x, data_type="phase", m=t.af, ci=None)
    ratio = (t.sigma / raw.dev) ** 2
    assert ratio.std() < 5e-5
    fpm = theo.theo1(x, data_type="phase", m=t.af, bias="published", alpha=1, ci=None)
    assert abs(fpm.dev[0] / t.sigma[0] - 1) > 1e-2
    assert np.ptp(fpm.var / raw.var) > 0.3
    # Stable32's Alpha column is the type of that one κ on every row (fixed nominal ratios).
    assert np.array_equal(r.alpha, t.alpha)


# (alpha, m) -> AVAR/Theo1 = a + b/(0.75 m)^c, Howe & Tasset 2004 Table 1.
THEO1_TABLE = {2: (0.09, 0.74, 0.40), 1: (0.14, 0.82, 0.30), 0: (1.0, 0.0, 0.0),
               -1: (1.87, -1.05, 0.79), -2: (2.70, -1.53, 0.85)}


@pytest.mark.parametrize("alpha", sorted(THEO1_TABLE))
def test_theo1_published_bias(alpha):
    y = nbs1000()
    ms = np.array([10, 100, 500])
    raw = theo.theo1(y, m=ms, alpha=alpha)
    r = theo.theo1(y, m=ms, alpha=alpha, bias="published")
    a, b, c = THEO1_TABLE[alpha]
    expected = np.array([a + b / (0.75 * m) ** c for m in ms])
    np.testing.assert_allclose(r.var / raw.var, expected, rtol=1e-12)
    np.testing.assert_allclose(r.bias_factor, 1.0 / expected, rtol=1e-12)
    np.testing.assert_allclose(r.ci_low / r.dev, raw.ci_low / raw.dev, rtol=1e-12)
    np.testing.assert_allclose(r.ci_high / r.dev, raw.ci_high / raw.dev, rtol=1e-12)
    assert r.bias == f"published alpha={alpha}" and raw.bias == "none" and raw.bias_factor is None
    np.testing.assert_array_equal(r.n, raw.n)
    bare = theo.theo1(y, m=ms, alpha=alpha, bias="published", ci=None)
    np.testing.assert_array_equal(bare.var, r.var)
    assert bare.ci_low is None and bare.edf is None


def test_theo1_auto_bias_uses_identified_alpha():
    y = nbs1000()
    ms = [10, 100]
    auto = theo.theo1(y, m=ms, bias="auto")
    assert auto.bias == "published at the alpha identified per tau"
    for k, a in enumerate(auto.alpha):
        forced = theo.theo1(y, m=ms[k], bias="published", alpha=int(a))
        assert auto.var[k] == pytest.approx(forced.var[0], rel=1e-12)


@pytest.mark.parametrize("kw, match", [
    (dict(bias="kappa"), "bias='kappa' must be one of"),
    (dict(bias=None), "bias=None must be one of"),
    (dict(bias="published", alpha=-3), "no published bias factor for alpha=-3"),
    (dict(bias="auto", alpha=-4), "no published bias factor for alpha=-4"),
])
def test_theo1_bias_errors(kw, match):
    with pytest.raises(ParameterError, match=match):
        theo.theo1(nbs1000(), m=10, **kw)


def test_theobr_kappa_run_span_is_capped():
    # n = ⌊N/6⌋ − 3 would need OAVAR at m = N/2 (no term) when 6 divides N.
    rng = np.random.default_rng(11)
    for n_phase in (90, 1002, 1003):
        k = theo.theobr_kappa(rng.standard_normal(n_phase), data_type="phase", method="run")
        assert n_phase - 2 * (9 + 3 * k.n) >= 1
        assert k.n == min(n_phase // 6 - 3, ((n_phase - 1) // 2 - 9) // 3)
    with pytest.raises(ParameterError, match="kappa='wide'"):
        theo.theobr(nbs1000(), kappa="wide")


@pytest.mark.parametrize("alpha", [2, 1])
def test_theo1_published_bias_monte_carlo(alpha):
    # Corrected Theo1 at m = 4j estimates AVAR at τ = 3j (numerics.md §3 checked the table
    # the same way). 150 seeded records of 513 phase points: the mean ratio of OAVAR to
    # corrected Theo1 has a standard error under 1 % (ν ≈ 250-400 per record), bound 4 %.
    from sigmatau.generate import power_law_noise

    rng = np.random.default_rng(20261124)
    ms = np.array([12, 40, 100])
    ratios = []
    for _ in range(150):
        x = power_law_noise(513, alpha, data_type="phase", rng=rng)
        th = theo.theo1(x, data_type="phase", m=ms, alpha=alpha, bias="published", ci=None).var
        av = oadev(x, data_type="phase", m=(3 * ms) // 4, ci=None).var
        ratios.append(av / th)
    mean = np.mean(ratios, axis=0)
    assert np.all(np.abs(mean - 1) < 0.04), mean


# --- properties -----------------------------------------------------------------------------


def test_frequency_and_phase_input_agree():
    y = np.random.default_rng(5).standard_normal(300)
    x = np.concatenate(([0.0], np.cumsum(y))) / 8.0
    a = theo.theo1(y, rate=8.0, taus="all")
    b = theo.theo1(x, rate=8.0, data_type="phase", taus="all")
    np.testing.assert_allclose(a.var, b.var, rtol=1e-10)
    np.testing.assert_array_equal(a.m, np.arange(2, 301, 2))


def test_scaling():
    y = np.random.default_rng(6).standard_normal(500)
    a = theo.theo1(y)
    b = theo.theo1(1e-6 * y)
    np.testing.assert_allclose(b.var, 1e-12 * a.var, rtol=1e-12)


def test_grids():
    r = theo.theo1(nbs1000())
    np.testing.assert_array_equal(r.m, [2, 4, 8, 16, 32, 64, 128, 256, 512])
    r = theo.theo1(nbs1000(), taus="decade")
    np.testing.assert_array_equal(r.m, [2, 4, 10, 20, 40, 100, 200, 400, 1000])
    # τ in seconds are rounded to multiples of 1.5 τ0.
    r = theo.theo1(nbs1000(), taus=[7.5, 75.0])
    np.testing.assert_array_equal(r.m, [10, 100])


def test_constant_data():
    r = theo.theo1(np.full(200, 3.0))
    assert np.all(r.var == 0.0)


# --- errors ----------------------------------------------------------------------------------


def test_odd_factor_rejected():
    with pytest.raises(ParameterError, match="even"):
        theo.theo1(nbs1000(), m=[10, 11])
    with pytest.raises(ParameterError, match="even"):
        theo.theobr(nbs1000(), m=5)


def test_factor_range():
    with pytest.raises(ParameterError, match="outside"):
        theo.theo1(np.ones(20), m=22)  # N = 21 phase points: m ≤ 20
    with pytest.raises(ParameterError, match="outside"):
        theo.theo1(np.ones(20), m=0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        theo.theo1(np.random.default_rng(1).standard_normal(20), m=20)


def test_theobr_needs_90_phase_points():
    rng = np.random.default_rng(2)
    with pytest.raises(DataError, match="at least 90 phase points"):
        theo.theobr(rng.standard_normal(88))  # 89 phase points
    with pytest.raises(DataError, match="at least 90 phase points"):
        theo.theobr_kappa(rng.standard_normal(89), data_type="phase")
    with pytest.raises(DataError, match="at least 90 phase points"):
        theo.theoh(rng.standard_normal(50))
    k = theo.theobr_kappa(rng.standard_normal(89))  # 90 phase points: n = 0
    assert k.n == 0


def test_theobr_constant_data():
    # Constant frequency: every variance is zero, so TheoBR is zero whatever κ.
    for f in (theo.theobr, theo.theoh):
        r = f(np.full(120, 2.0))
        np.testing.assert_array_equal(r.dev, 0.0)
    assert theo.theobr_kappa(np.full(120, 2.0)).kappa == 1.0


def test_theoh_factor_errors():
    with pytest.raises(ParameterError, match="between"):
        theo.theoh(nbs1000(), m=[10, 120])  # 120: past AVAR (m < 100), below TheoBR (m ≥ 134)
    with pytest.raises(ParameterError, match="even"):
        theo.theoh(nbs1000(), m=[10, 135])
    with pytest.raises(ParameterError, match="not both"):
        theo.theoh(nbs1000(), m=[10], taus="decade")


# --- TheoH ------------------------------------------------------------------------------------


def test_theoh_split():
    assert theo.theoh_split(1001) == (100, 134)
    assert theo.theoh_split(90) == (8, 12)
    for n in range(90, 400):
        k, m_lo = theo.theoh_split(n)
        assert m_lo % 2 == 0 and 0.75 * m_lo >= k > 0.75 * (m_lo - 2)


def test_theoh_nbs(monkeypatch):
    calls = []
    original = theo._kappa
    monkeypatch.setattr(theo, "_kappa", lambda x, *a: calls.append(1) or original(x, *a))
    y = nbs1000()
    r = theo.theoh(y)
    assert len(calls) == 1  # κ once for the whole record
    assert r.statistic == "theoh"
    np.testing.assert_array_equal(r.m, [1, 2, 4, 8, 16, 32, 64, 170, 342, 682])
    np.testing.assert_allclose(r.taus, [1, 2, 4, 8, 16, 32, 64, 127.5, 256.5, 511.5])
    assert np.all(np.diff(r.taus) > 0)
    avar = r.taus < 100.0
    a = oadev(y, m=r.m[avar])
    b = theo.theobr(y, m=r.m[~avar])
    np.testing.assert_allclose(r.var[avar], a.var, rtol=1e-14)
    np.testing.assert_allclose(r.var[~avar], b.var, rtol=1e-14)
    np.testing.assert_array_equal(r.n, np.concatenate((a.n, b.n)))
    np.testing.assert_allclose(r.bias_factor, np.where(avar, 1.0, 1.0 / 1.085666), rtol=1e-6)
    assert r.bias.startswith("theoh: oavar for tau < 100 s (m < 100); theobr kappa=1.085666 (n=30)")


def test_theoh_explicit_factors_and_taus():
    y = nbs1000()
    r = theo.theoh(y, m=[1, 10, 99, 134, 1000])
    np.testing.assert_allclose(r.taus, [1, 10, 99, 100.5, 750])
    r2 = theo.theoh(y, taus=[1.0, 10.0, 99.0, 100.5, 750.0])
    np.testing.assert_array_equal(r2.m, r.m)
    np.testing.assert_allclose(r2.var, r.var, rtol=1e-15)
    with pytest.warns(RangeWarning, match="rounded"):
        r3 = theo.theoh(y, taus=[100.0, 300.0])  # TheoBR τ are multiples of 1.5 s
    np.testing.assert_array_equal(r3.m, [134, 400])
    # rate: τ in seconds, factors unchanged
    r4 = theo.theoh(y, rate=10.0, m=[1, 10, 99, 134, 1000])
    np.testing.assert_allclose(r4.taus, r.taus / 10.0)


def test_timing_octave_is_fast():
    # A budget, not a benchmark: 10^4 points, octave grid.
    import time

    y = np.random.default_rng(9).standard_normal(10_000)
    t = time.perf_counter()
    theo.theo1(y)
    assert time.perf_counter() - t < 10.0


# --- Fast TheoBR: κ of the block-averaged record ---------------------------------------------


def kappa_plain(x: np.ndarray) -> tuple[float, int]:
    """κ by its definition (numerics.md §1.13) with the plain Theo1 and SP1065 OAVAR sums."""
    N = x.size
    n = N // 30 - 3
    ratios = []
    for i in range(n + 1):
        m = 9 + 3 * i
        d2 = x[2 * m :] - 2 * x[m:-m] + x[: -2 * m]
        ratios.append(float(np.sum(d2 * d2)) / (2 * m * m * d2.size) / theo1_var_plain(x, 12 + 4 * i))
    return float(np.mean(ratios)), n


@pytest.mark.parametrize("noise", ["WPM", "FPM", "WFM", "FFM", "RWFM", "FWFM", "RRFM"])
def test_fast_kappa_is_the_definition_on_block_averages(noise, monkeypatch):
    # Threshold lowered so that the plain sums stay cheap: 1501 phase points, blocks of 6.
    from _noise import NOISES

    monkeypatch.setattr(theo, "KAPPA_FAST_POINTS", 300)
    y = NOISES[noise](1500, np.random.default_rng([4, len(noise)]))
    x = np.concatenate(([0.0], np.cumsum(y)))
    b = -(-x.size // 300)
    k = x.size // b
    averaged = x[: k * b].reshape(k, b).mean(axis=1)
    want, n = kappa_plain(averaged - np.polyval(np.polyfit(np.arange(k), averaged, 1), np.arange(k)))
    if noise in ("WPM", "FPM"):  # fast κ is biased for phase noise, and says so
        with pytest.warns(RangeWarning, match="phase noise"):
            fast = theo.theobr_kappa(y)
    else:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            fast = theo.theobr_kappa(y)
    assert (fast.block, fast.n, fast.n_points) == (b, n, x.size) == (6, 5, 1501)
    assert fast.kappa == pytest.approx(want, rel=ORACLE_RTOL)
    exact = theo.theobr_kappa(y, method="exact")
    want_exact, n_exact = kappa_plain(x)
    assert (exact.block, exact.n) == (1, n_exact)
    assert exact.kappa == pytest.approx(want_exact, rel=ORACLE_RTOL)


def test_fast_kappa_reaches_theobr_and_theoh(monkeypatch):
    monkeypatch.setattr(theo, "KAPPA_FAST_POINTS", 300)
    y = np.random.default_rng(8).standard_normal(1500)
    fast, exact = theo.theobr_kappa(y), theo.theobr_kappa(y, method="exact")
    assert fast.kappa != exact.kappa
    raw = theo.theo1(y, m=[10, 100]).var
    r = theo.theobr(y, m=[10, 100])
    assert r.bias == f"theobr kappa={fast.kappa:.6f} (n=5, fast: blocks of 6 points)"
    np.testing.assert_allclose(r.var, fast.kappa * raw, rtol=1e-14)
    r = theo.theobr(y, m=[10, 100], kappa="exact")
    assert r.bias == f"theobr kappa={exact.kappa:.6f} (n=47)"
    np.testing.assert_allclose(r.var, exact.kappa * raw, rtol=1e-14)
    h = theo.theoh(y, kappa="exact")
    np.testing.assert_allclose(h.bias_factor[h.m >= theo.theoh_split(1501)[1]], 1.0 / exact.kappa)
    assert "fast: blocks of 6" in theo.theoh(y).bias
    # Up to KAPPA_FAST_POINTS phase points the fast κ is the published one.
    monkeypatch.setattr(theo, "KAPPA_FAST_POINTS", 1501)
    assert theo.theobr_kappa(y) == exact
    for bad in ("slow", None, 1.0):
        with pytest.raises(ParameterError, match="kappa"):
            theo.theobr(y, kappa=bad)
        with pytest.raises(ParameterError, match="kappa"):
            theo.theoh(y, kappa=bad)
        with pytest.raises(ParameterError, match="method"):
            theo.theobr_kappa(y, method=bad)


# --- Fast TheoBR rows of TheoH (method="fast", the main job's default) ---------------------------


def test_theoh_fast_is_exact_up_to_the_block_threshold():
    y = sigmatau.power_law_noise(theo.THEOH_FAST_POINTS - 1, alpha=0, rng=21)  # N = THEOH_FAST_POINTS
    fast, exact = sigmatau.theoh(y, method="fast"), sigmatau.theoh(y)
    for f in ("m", "taus", "var", "n", "alpha", "edf", "ci_low", "ci_high"):
        np.testing.assert_array_equal(getattr(fast, f), getattr(exact, f), err_msg=f)
    assert fast.bias == exact.bias


@pytest.mark.slow
@pytest.mark.parametrize("alpha", [0, -1, -2])
def test_theoh_fast_agrees_with_the_definition_for_fm_noise(alpha):
    # docs/theoh-fast.md: at N = 2**20 the TheoBR rows differ by ≤ 4.6e-4 (WFM), 5.9e-5 (FFM),
    # 5.4e-5 (RWFM); here N = 2**18 (blocks of 5) at the very same factors, held to 2e-3.
    y = sigmatau.power_law_noise(1 << 18, alpha=alpha, rng=30 + alpha)
    fast = sigmatau.theoh(y, method="fast", ci=None)
    high = fast.bias_factor != 1.0
    block = -(-((1 << 18) + 1) // theo.THEOH_FAST_POINTS)
    assert "fast theobr on blocks of 5 points" in fast.bias and block == 5
    assert np.all(fast.m[high] % (2 * block) == 0) and high.sum() >= 3
    exact = sigmatau.theoh(y, m=fast.m, ci=None)
    np.testing.assert_array_equal(fast.var[~high], exact.var[~high])  # the AVAR rows are the same
    assert np.max(np.abs(fast.dev[high] / exact.dev[high] - 1)) < 2e-3
    np.testing.assert_allclose(fast.taus, 0.75 * fast.m * 1.0 * np.where(high, 1, 4 / 3))


@pytest.mark.parametrize("alpha", [2, 1])
def test_theoh_fast_declines_phase_noise(alpha):
    # Block averages remove white and flicker PM (Fast TheoBR reads them 24-79 % low): κ says PM,
    # so the exact rows are computed and the bias says why.
    y = sigmatau.power_law_noise(100_000, alpha=alpha, rng=40 + alpha)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RangeWarning)  # Fast κ on phase noise (its own warning)
        fast, exact = sigmatau.theoh(y, method="fast", ci=None), sigmatau.theoh(y, ci=None)
    assert "exact theobr (kappa indicates phase noise" in fast.bias
    np.testing.assert_array_equal(fast.var, exact.var)
    np.testing.assert_array_equal(fast.m, exact.m)


def test_theoh_method_is_checked():
    with pytest.raises(ParameterError, match="method='quick' must be one of"):
        sigmatau.theoh(np.random.default_rng(1).standard_normal(500), method="quick")
