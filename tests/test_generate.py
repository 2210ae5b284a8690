"""Tests of sigmatau.generate: shapes, seeding, conventions, and the level of every noise type.

Sources of the expected numbers:

* exact discrete expectations (numerics.md §6.1), checked here against
  ``scipy.integrate.quad`` and against time-domain sums of squared filter taps;
* the ratio table of numerics.md §6.1 and the constants of §6.3 (three to seven
  printed digits; tolerances follow them);
* numerics.md §6.2 for the octave-sum generator.

Monte-Carlo bounds. A variance estimate with ν equivalent degrees of freedom
has relative standard deviation sqrt(2/ν), so the mean of R independent runs
has relative standard error sqrt(2/(νR)). We estimate ν from the spread of the
runs themselves (ν̂ = 2·mean²/s², which makes the bound 4·s/√R): closed forms
(numerics.md §2.2, Table 5) exist only for OAVAR, assume the noise type and are
approximate at small m (§8 item 4). ``test_empirical_edf_agrees_with_table_5``
checks that the two agree. Every check uses ±4 standard errors; all runs are
seeded, so the outcome is deterministic.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest
from scipy import integrate, special

import sigmatau
from sigmatau import ParameterError, frequency_to_phase
from sigmatau.generate import (
    expected_avar,
    expected_oavar_discrete,
    expected_variance,
    expected_variance_discrete,
    mixed_noise,
    octave_flicker,
    power_law_noise,
)
from sigmatau.noise.generate import _kasdin_filter

ALPHAS = [2, 1, 0, -1, -2, -3, -4]
METHODS = ["kasdin", "tip"]
NAMES = {"wpm": 2, "fpm": 1, "wfm": 0, "ffm": -1, "rwfm": -2, "fwfm": -3, "rrfm": -4,
         "white_pm": 2, "flicker_pm": 1, "white": 0, "flicker": -1, "random_walk": -2,
         "flicker_walk": -3, "random_run": -4}

# Monte-Carlo set-up shared by the level tests.
RUNS, N, RATE, LEVEL = 30, 2**14, 50.0, 3e-3
MS = [1, 4, 16, 64]
SIGMAS = 4.0
# (α, statistic) pairs whose variance converges: AVAR and MVAR need α ≥ −2.
CONVERGENT = [(a, s) for s in ("oadev", "mdev", "ohdev") for a in ALPHAS if s == "ohdev" or a >= -2]


# --- shapes, arguments, seeding ----------------------------------------------------


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("data_type", ["freq", "phase"])
@pytest.mark.parametrize("alpha", ALPHAS)
def test_length_is_exact_for_any_n(alpha, data_type, method):
    for n in (2, 3, 17, 1009, 1024, 1025):
        out = power_law_noise(n, alpha, data_type=data_type, method=method, rng=n)
        assert out.shape == (n,)
        assert out.dtype == np.float64
        assert np.all(np.isfinite(out))


@pytest.mark.parametrize("n", [0, 1, -5, 2.5, 10.0, "10", True, None])
def test_n_must_be_an_integer_of_at_least_two(n):
    with pytest.raises(ParameterError, match="n="):
        power_law_noise(n, 0)
    with pytest.raises(ParameterError):
        mixed_noise(n, {0: 1.0})


def test_names_are_aliases_of_alpha():
    for name, alpha in NAMES.items():
        for spelling in (name, name.upper(), name.replace("_", "-"), name.replace("_", " ")):
            np.testing.assert_array_equal(
                power_law_noise(64, spelling, rng=1), power_law_noise(64, alpha, rng=1)
            )
    np.testing.assert_array_equal(power_law_noise(64, np.int64(-2), rng=1),
                                  power_law_noise(64, -2.0, rng=1))


@pytest.mark.parametrize("alpha", [3, -5, 0.5, "pink", "", True, None, [0]])
def test_unknown_noise_type_is_a_one_line_parameter_error(alpha):
    with pytest.raises(ParameterError) as info:
        power_law_noise(100, alpha)
    message = str(info.value)
    assert "\n" not in message
    assert f"alpha={alpha!r}" in message
    assert isinstance(info.value, ValueError)


@pytest.mark.parametrize(
    "kwargs, name",
    [
        ({"h": -1.0}, "h="), ({"h": math.nan}, "h="), ({"h": "big"}, "h="),
        ({"rate": 0.0}, "rate="), ({"rate": -2.0}, "rate="),
        ({"data_type": "time"}, "data_type="), ({"method": "voss"}, "method="),
        ({"rng": "seed"}, "rng="),
    ],
)
def test_invalid_options_are_parameter_errors(kwargs, name):
    with pytest.raises(ParameterError, match=name):
        power_law_noise(100, 0, **kwargs)


def test_octave_flicker_arguments():
    assert octave_flicker(1, rng=0).shape == (1,)
    for bad in ({"rows": 0}, {"rows": 61}, {"rows": 2.0}, {"start": -1}, {"sigma": -1.0}):
        with pytest.raises(ParameterError):
            octave_flicker(10, **bad)


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("alpha", ALPHAS)
def test_same_seed_same_series_and_generators_advance(alpha, method):
    a = power_law_noise(500, alpha, rng=42, method=method)
    b = power_law_noise(500, alpha, rng=np.random.default_rng(42), method=method)
    c = power_law_noise(500, alpha, rng=np.random.SeedSequence(42), method=method)
    np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(a, c)
    gen = np.random.default_rng(42)
    first = power_law_noise(500, alpha, rng=gen, method=method)
    second = power_law_noise(500, alpha, rng=gen, method=method)
    np.testing.assert_array_equal(first, a)
    assert not np.array_equal(first, second)


def test_different_seeds_give_independent_series():
    n = 20_000
    for method in METHODS:
        for alpha in (2, 0):  # white series, where sample correlation has sd 1/√n
            a = power_law_noise(n, alpha, data_type="phase" if alpha == 2 else "freq",
                                rng=1, method=method)
            b = power_law_noise(n, alpha, data_type="phase" if alpha == 2 else "freq",
                                rng=2, method=method)
            assert abs(np.corrcoef(a, b)[0, 1]) < SIGMAS / math.sqrt(n)


# --- conventions and exact properties ------------------------------------------------


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("alpha", ALPHAS)
def test_phase_is_integrated_frequency_of_the_same_draws(alpha, method):
    n, rate = 257, 20.0
    x = power_law_noise(n, alpha, rate=rate, data_type="phase", rng=7, method=method)
    y = power_law_noise(n - 1, alpha, rate=rate, data_type="freq", rng=7, method=method)
    if alpha <= 0:  # generated as frequency: exact, x_0 = 0
        assert x[0] == 0.0
        np.testing.assert_array_equal(x, frequency_to_phase(y, rate=rate))
    else:  # generated as phase and differenced: equal up to x_0 and rounding
        np.testing.assert_allclose(x - x[0], frequency_to_phase(y, rate=rate),
                                   rtol=0, atol=1e-12 * np.abs(x).max())


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("alpha", ALPHAS)
def test_level_and_rate_scale_as_the_spectrum_says(alpha, method):
    base = power_law_noise(300, alpha, rng=3, method=method)
    np.testing.assert_allclose(power_law_noise(300, alpha, h=4.0, rng=3, method=method),
                               2.0 * base, rtol=1e-12, atol=0)
    # S_y = h f^α at any rate: the samples scale as rate^{(α+1)/2}.
    fast = power_law_noise(300, alpha, rate=16.0, rng=3, method=method)
    np.testing.assert_allclose(fast, 16.0 ** ((alpha + 1) / 2) * base, rtol=1e-9,
                               atol=1e-9 * np.abs(fast).max())


@pytest.mark.parametrize("alpha", [2, 0, -2, -4])
def test_tip_and_kasdin_agree_where_the_constructions_coincide(alpha):
    # randn, cumsum, cumsum∘cumsum and diff(white) are the Kasdin filter for β = 0, −2, −4.
    for data_type in ("freq", "phase"):
        np.testing.assert_array_equal(
            power_law_noise(1000, alpha, h=2.5, rate=3.0, data_type=data_type, rng=9, method="tip"),
            power_law_noise(1000, alpha, h=2.5, rate=3.0, data_type=data_type, rng=9),
        )


def _plain_kasdin_taps(beta: float, n: int) -> list[float]:
    taps = [1.0]
    for k in range(1, n):
        taps.append(taps[-1] * (k - 1 - beta / 2) / k)
    return taps


@pytest.mark.parametrize("beta", [0, -1, -2, -3, -4])
def test_kasdin_filter_equals_the_plain_convolution(beta):
    n = 333
    w = np.random.default_rng(0).standard_normal(n)
    taps = np.array(_plain_kasdin_taps(beta, n))
    expected = np.convolve(w, taps)[:n]
    np.testing.assert_allclose(_kasdin_filter(w, beta), expected, rtol=0,
                               atol=1e-12 * np.abs(expected).max())


def test_kasdin_taps_have_their_closed_forms():
    k = np.arange(50)
    np.testing.assert_allclose(_plain_kasdin_taps(-2, 50), np.ones(50))
    np.testing.assert_allclose(_plain_kasdin_taps(-4, 50), k + 1.0)
    # (1 − z⁻¹)^{−1/2}: h_k = Γ(k + 1/2) / (Γ(1/2) k!)
    np.testing.assert_allclose(_plain_kasdin_taps(-1, 50),
                               np.exp(special.gammaln(k + 0.5) - special.gammaln(0.5)
                                      - special.gammaln(k + 1.0)), rtol=1e-12)


def _listing_octave(n: int, rows: int, start: int, sigma: float, seed: int) -> np.ndarray:
    """The design tip's loop, one sample at a time, drawing in the library's order.

    The tip's listing draws the bank and then one value per redraw as it goes;
    here the number of redraws per row is counted first so that the same
    random numbers can be handed out in the library's order (white term, then
    row 0's values, row 1's …). The extra term is Gaussian (see octave_flicker).
    """

    def trailing_zeros(c: int) -> int:
        t = 0
        while c % 2 == 0 and t < rows:  # a counter divisible by 2^rows redraws no row
            t += 1
            c //= 2
        return t

    counts = [1] * rows
    for i in range(1, n):
        t = trailing_zeros(start + i)
        if t < rows:
            counts[t] += 1
    gen = np.random.default_rng(seed)
    white = sigma * gen.standard_normal(n)
    draws = [sigma * gen.standard_normal(c) for c in counts]
    used = [0] * rows
    bank = [d[0] for d in draws]
    out = np.empty(n)
    for i in range(n):
        if i > 0:
            t = trailing_zeros(start + i)
            if t < rows:
                used[t] += 1
                bank[t] = draws[t][used[t]]
        out[i] = sum(bank) + white[i]
    return out


def test_vectorised_octave_generator_equals_the_tips_loop():
    for n in (1, 2, 3, 17, 100, 257):
        for rows in sorted({1, 3, n.bit_length(), n.bit_length() + 3}):
            for start in (0, 1, 2, 7, 8, 1000, 2**20 - 3):
                np.testing.assert_allclose(
                    octave_flicker(n, rows=rows, start=start, sigma=0.7, rng=5),
                    _listing_octave(n, rows, start, 0.7, 5), rtol=0, atol=1e-12)


def test_octave_default_bank_is_the_tips():
    n = 1000  # ⌊log2 1000⌋ + 1 = 10 generators
    np.testing.assert_array_equal(octave_flicker(n, start=1, rng=2),
                                  octave_flicker(n, rows=10, start=1, rng=2))


# --- expected values ---------------------------------------------------------------


def _quad_oracle(beta: int, m: int, d: int, smooth: int) -> float:
    def f(w):
        s, t = 2 * np.sin(w / 2), 2 * np.sin(m * w / 2)
        return s**beta * t ** (2 * d) * (t / s) ** (2 * smooth)

    return integrate.quad(f, 0, np.pi, limit=400, epsabs=0, epsrel=1e-12)[0] / np.pi


def _norm(statistic: str, m: int, tau0: float) -> float:
    return {"oadev": 2 * m**2 * tau0**2, "ohdev": 6 * m**2 * tau0**2,
            "mdev": 2 * m**4 * tau0**2}[statistic]


@pytest.mark.parametrize("alpha, statistic", CONVERGENT)
def test_discrete_expectation_matches_quad(alpha, statistic):
    d, smooth = (3, 0) if statistic == "ohdev" else (2, int(statistic == "mdev"))
    rate = 50.0
    tau0 = 1 / rate
    qx = LEVEL / (2 * (2 * math.pi) ** alpha * tau0 ** (alpha - 1))
    for m in (1, 2, 3, 4, 16):
        expected = qx * _quad_oracle(alpha - 2, m, d, smooth) / _norm(statistic, m, tau0)
        got = expected_variance_discrete(alpha, LEVEL, m, statistic=statistic, rate=rate)[0]
        assert got == pytest.approx(expected, rel=1e-10)


@pytest.mark.parametrize("alpha, statistic", [c for c in CONVERGENT if c[0] in (2, 0, -2, -4)])
def test_discrete_expectation_matches_time_domain_sums(alpha, statistic):
    """For WPM, WFM, RWFM, RRFM the statistic is a finite filter of white noise.

    Δ^d_m x = τ0·√Q_y·[(1 − z^{−m})^d / (1 − z^{−1})^j] w with j = 1 − α/2
    integrations (j = 0 and Q_x for WPM), and MVAR adds the moving sum S_m;
    the expectation is Q times the sum of the squared taps.
    """
    rate = 8.0
    tau0 = 1 / rate
    d = 3 if statistic == "ohdev" else 2
    j = 0 if alpha == 2 else 1 - alpha // 2
    if alpha == 2:
        scale = LEVEL / (2 * (2 * math.pi) ** 2 * tau0)  # Q_x
    else:
        scale = tau0**2 * LEVEL / (2 * (2 * math.pi) ** alpha * tau0 ** (alpha + 1))  # τ0² Q_y
    for m in (1, 2, 3, 7, 64, 300):
        diff = np.zeros(m + 1)
        diff[0], diff[m] = 1.0, -1.0
        sum_m = np.ones(m)
        taps = np.array([1.0])
        for _ in range(d - j):
            taps = np.convolve(taps, diff)
        for _ in range(j + (statistic == "mdev")):
            taps = np.convolve(taps, sum_m)
        expected = scale * np.dot(taps, taps) / _norm(statistic, m, tau0)
        got = expected_variance_discrete(alpha, LEVEL, m, statistic=statistic, rate=rate)[0]
        assert got == pytest.approx(expected, rel=1e-11)


def test_discrete_to_continuous_ratios_of_numerics_6_1():
    table = {  # numerics.md §6.1, m = 1, 4, 16, 64, 256, three decimals
        2: [1.000, 1.000, 1.000, 1.000, 1.000],
        1: [1.193, 1.085, 1.057, 1.043, 1.034],
        0: [1.000, 1.000, 1.000, 1.000, 1.000],
        -1: [1.443, 1.050, 1.005, 1.000, 1.000],
        -2: [1.500, 1.031, 1.002, 1.000, 1.000],
    }
    ms = [1, 4, 16, 64, 256]
    for alpha, row in table.items():
        ratio = expected_oavar_discrete(alpha, 1.0, ms) / expected_avar(alpha, 1.0, ms)
        tol = np.full(5, 5e-4)
        if alpha == 1:
            # Exact 1.19242: the table's 1.193 follows from the continuous FPM
            # constant rounded to 1.038 (SP1065) instead of 3γ − ln 2 = 1.03850.
            tol[0] = 1e-3
        np.testing.assert_array_less(np.abs(ratio - row), tol)
    # Exact values: RWFM 1 + 1/(2m²); FFM at m = 1 has E[(Δ²x)²] = 4Q_x/π, i.e.
    # OAVAR = 2h against 2 ln 2·h, a ratio of 1/ln 2.
    np.testing.assert_allclose(
        expected_oavar_discrete(-2, 1.0, ms) / expected_avar(-2, 1.0, ms),
        1 + 1 / (2 * np.array(ms, float) ** 2), rtol=1e-12)
    assert (expected_oavar_discrete(-1, 1.0, 1) / expected_avar(-1, 1.0, 1.0))[0] == pytest.approx(
        1 / math.log(2.0), rel=1e-12)


def test_discrete_ohvar_ratios_match_the_monte_carlo_of_numerics_6_3():
    # numerics.md §6.3: mean OHVAR / HVAR formula at m = 4 over 60 runs × 32768
    # points (statistical error about ±1 %).
    mc = {-1: 1.068, -2: 1.062, -3: 1.052, -4: 1.028}
    for alpha, value in mc.items():
        ratio = (expected_variance_discrete(alpha, 1.0, 4, statistic="ohdev")
                 / expected_variance(alpha, 1.0, 4.0, statistic="hdev"))
        assert ratio[0] == pytest.approx(value, abs=0.01)


@pytest.mark.parametrize("statistic", ["oadev", "mdev", "ohdev"])
def test_discrete_expectation_tends_to_the_continuous_one(statistic):
    alphas = [2, 0, -1, -2] + ([-3, -4] if statistic == "ohdev" else [])
    for alpha in alphas:
        ratio = (expected_variance_discrete(alpha, 1.0, 1024, statistic=statistic)
                 / expected_variance(alpha, 1.0, 1024.0, statistic=statistic))
        assert ratio[0] == pytest.approx(1.0, abs=1e-5)
    # FPM MVAR does not depend on the cut-off, so it converges too.
    ratio = (expected_variance_discrete(1, 1.0, 1024, statistic="mdev")
             / expected_variance(1, 1.0, 1024.0, statistic="mdev"))
    assert ratio[0] == pytest.approx(1.0, abs=1e-4)


def test_continuous_constants_of_numerics_6_3():
    # τ = 1 and rate = 1/π make 2π f_h τ = 1, so the FPM log terms vanish.
    pi2 = math.pi**2
    fpm = {s: expected_variance(1, 1.0, 1.0, statistic=s, rate=1 / math.pi)[0]
           for s in ("adev", "mdev", "tdev", "hdev")}
    assert fpm["adev"] * 4 * pi2 == pytest.approx(1.0385, abs=5e-5)
    assert fpm["mdev"] == pytest.approx(0.085465, abs=5e-7)
    assert fpm["tdev"] == pytest.approx(0.028488, abs=5e-7)
    assert fpm["hdev"] * 12 * pi2 == pytest.approx(2.7119, abs=5e-5)
    constants = {  # (alpha, statistic): printed value at τ = 1
        (-1, "adev"): 1.386294, (-1, "mdev"): 0.935228, (-1, "tdev"): 0.311743,
        (-1, "hdev"): 1.124670, (-2, "adev"): 6.579736, (-2, "mdev"): 5.428282,
        (-2, "hdev"): 3.289868, (-3, "hdev"): 12.307104, (-4, "hdev"): 71.433333,
        (0, "adev"): 0.5, (0, "mdev"): 0.25, (0, "hdev"): 0.5,
    }
    for (alpha, statistic), value in constants.items():
        assert expected_variance(alpha, 1.0, 1.0, statistic=statistic)[0] == pytest.approx(
            value, abs=5e-7)
    # τ-dependence: WFM 1/τ, RWFM τ, FWFM τ², RRFM τ³, TVAR = τ²/3·MVAR.
    taus = np.array([0.5, 2.0, 8.0])
    np.testing.assert_allclose(expected_avar(0, 2.0, taus), 1.0 / taus)
    np.testing.assert_allclose(expected_variance(-3, 1.0, taus, statistic="hdev"), 12.307104 * taus**2,
                               rtol=1e-7)
    np.testing.assert_allclose(expected_variance(-4, 1.0, taus, statistic="hdev"), 71.433333 * taus**3,
                               rtol=1e-7)
    np.testing.assert_allclose(expected_variance(-2, 1.0, taus, statistic="tdev"),
                               expected_variance(-2, 1.0, taus, statistic="mdev") * taus**2 / 3)


def test_expected_values_reject_diverging_statistics():
    for statistic in ("adev", "oadev", "mdev", "tdev"):
        for alpha in (-3, "rrfm"):
            with pytest.raises(ParameterError, match="diverges"):
                expected_variance(alpha, 1.0, 1.0, statistic=statistic)
            with pytest.raises(ParameterError, match="diverges"):
                expected_variance_discrete(alpha, 1.0, 1, statistic=statistic)
    with pytest.raises(ParameterError, match="m="):
        expected_oavar_discrete(0, 1.0, [1, 2.5])
    with pytest.raises(ParameterError, match="statistic="):
        expected_variance(0, 1.0, 1.0, statistic="totdev")


# --- Monte-Carlo levels ------------------------------------------------------------


@functools.lru_cache(maxsize=None)
def _all_runs(alpha: int, method: str) -> dict[str, np.ndarray]:
    """OAVAR, MVAR and OHVAR of the same RUNS series (all three share each series)."""
    gen = np.random.default_rng([2024, alpha + 10, METHODS.index(method)])
    stats = ("oadev", "mdev", "ohdev") if alpha >= -2 else ("ohdev",)
    out: dict[str, list] = {s: [] for s in stats}
    for _ in range(RUNS):
        y = power_law_noise(N, alpha, h=LEVEL, rate=RATE, rng=gen, method=method)
        for s in stats:
            out[s].append(getattr(sigmatau, s)(y, rate=RATE, m=MS).var)
    return {s: np.array(v) for s, v in out.items()}


def _assert_mean_matches(values: np.ndarray, expected: np.ndarray, what: str) -> None:
    mean = values.mean(axis=0)
    se = values.std(axis=0, ddof=1) / math.sqrt(values.shape[0])
    z = (mean - expected) / se
    assert np.all(np.abs(z) < SIGMAS), f"{what}: mean/expected {mean / expected}, z {z}"


@pytest.mark.parametrize("alpha, statistic", CONVERGENT)
def test_kasdin_mean_variance_matches_discrete_expectation(alpha, statistic):
    values = _all_runs(alpha, "kasdin")[statistic]
    expected = expected_variance_discrete(alpha, LEVEL, MS, statistic=statistic, rate=RATE)
    _assert_mean_matches(values, expected, f"alpha={alpha} {statistic}")
    # The bound has power: ±4 standard errors stay within ±25 % of the level.
    rel_se = values.std(axis=0, ddof=1) / values.mean(axis=0) / math.sqrt(RUNS)
    assert np.all(SIGMAS * rel_se < 0.25)


def test_empirical_edf_agrees_with_table_5():
    # numerics.md §2.2 Table 5 (SP1065), N phase points. For FFM at m = 1 the
    # formula is 2(N−2)²/(2.3N − 4.9); the square is missing in numerics.md.
    n = N + 1

    def table5(alpha: int, m: int) -> float:
        if alpha == 2:
            return (n + 1) * (n - 2 * m) / (2 * (n - m))
        if alpha == 0:
            return (3 * (n - 1) / (2 * m) - 2 * (n - 2) / n) * 4 * m**2 / (4 * m**2 + 5)
        if alpha == -1:
            return 2 * (n - 2) ** 2 / (2.3 * n - 4.9) if m == 1 else 5 * n**2 / (4 * m * (n + 3 * m))
        return (n - 2) / (m * (n - 3) ** 2) * ((n - 1) ** 2 - 3 * m * (n - 1) + 4 * m**2)

    for alpha in (2, 0, -1, -2):
        values = _all_runs(alpha, "kasdin")["oadev"]
        nu_hat = 2 * values.mean(axis=0) ** 2 / values.var(axis=0, ddof=1)
        nu = np.array([table5(alpha, m) for m in MS])
        # With 30 runs ν̂ has a relative spread of about sqrt(2/29) = 26 %.
        np.testing.assert_array_less(np.abs(np.log(nu_hat / nu)), math.log(2.0))


def test_mixed_noise_adds_the_component_variances():
    h = {"wpm": 4e-7, 0: 1e-4, "ffm": 2e-6, -2: 1e-7}
    gen = np.random.default_rng(77)
    values = np.array([
        sigmatau.oadev(mixed_noise(N, h, rate=RATE, rng=gen), rate=RATE, m=MS).var for _ in range(RUNS)
    ])
    expected = sum(expected_oavar_discrete(a, level, MS, rate=RATE) for a, level in h.items())
    _assert_mean_matches(values, expected, "mixed")


def test_mixed_noise_is_independent_of_the_order_of_h():
    a = mixed_noise(100, {0: 1.0, -2: 2.0, "wpm": 3.0}, rng=4, data_type="phase")
    b = mixed_noise(100, {"wpm": 3.0, -2: 2.0, 0: 1.0}, rng=4, data_type="phase")
    np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(mixed_noise(100, {"rwfm": 2.0}, rng=4),
                                  power_law_noise(100, -2, h=2.0, rng=4))


def test_mixed_noise_rejects_bad_mappings():
    for h in ({}, [(0, 1.0)], {0: 1.0, "wfm": 2.0}, {0: -1.0}, {5: 1.0}):
        with pytest.raises(ParameterError):
            mixed_noise(100, h)


# --- the design tip's generators -----------------------------------------------------


def _octave_avar(m: int, rows: int, white: float = 1.0) -> float:
    """Exact E[AVAR(m)]/σ² of the octave sum with a random start, from its autocovariance.

    C(k)/σ² = white·δ_k0 + Σ_r max(0, 1 − |k|/2^{r+1}); the difference of two
    adjacent m-sums has lag weights c(k) = 2m − 3|k| (|k| ≤ m), |k| − 2m
    (m ≤ |k| ≤ 2m).
    """
    k = np.arange(-2 * m, 2 * m + 1)
    a = np.abs(k)
    c = np.where(a <= m, 2 * m - 3 * a, a - 2 * m).astype(float)
    cov = white * (k == 0) + sum(np.maximum(0.0, 1.0 - a / 2.0 ** (r + 1)) for r in range(rows))
    return float(np.dot(c, cov)) / (2 * m * m)


def test_octave_expectations_reproduce_numerics_6_2():
    # numerics.md §6.2 describes rows holding 2^r samples (r = 0 … K−1) plus a
    # white row: that is this bank with K − 1 rows and a white term of 2σ².
    assert _octave_avar(1, 15, white=2.0) == pytest.approx(3.0, abs=1e-4)
    assert _octave_avar(4, 15, white=2.0) == pytest.approx(2.125, abs=1e-4)
    # The tip's bank (hold 2^{r+1}, white σ²): 2σ² at m = 1, then the plateau.
    assert _octave_avar(1, 16) == pytest.approx(2.0, abs=1e-4)
    assert _octave_avar(4, 16) == pytest.approx(1.875, abs=1e-4)
    for m in (128, 256, 512, 1024):
        assert _octave_avar(m, 16) == pytest.approx(2.0, rel=0.006)


def test_tip_flicker_fm_recovers_h_on_the_plateau():
    gen = np.random.default_rng(5150)
    ms = [1, 4, 16, 64, 256, N // 16, N // 4]
    values = np.array([
        sigmatau.oadev(power_law_noise(N, "ffm", h=LEVEL, rate=RATE, rng=gen, method="tip"),
                       rate=RATE, m=ms).var for _ in range(RUNS)
    ])
    rows = N.bit_length() + 4  # the bank power_law_noise uses
    sigma2 = LEVEL * math.log(2.0)
    exact = np.array([_octave_avar(m, rows) for m in ms]) * sigma2
    _assert_mean_matches(values, exact, "tip FFM vs its exact expectation")
    # Plateau: from m = 16 to N/4 the construction is within 3 % of 2 ln 2·h.
    plateau = exact[2:] / expected_avar("ffm", LEVEL, 1.0)
    np.testing.assert_array_less(np.abs(plateau - 1.0), 0.03)
    # h recovered from the simulated plateau, m = 16 … 256 (the best-determined points).
    h_hat = values[:, 2:5].mean(axis=0) / (2 * math.log(2.0))
    se = values[:, 2:5].std(axis=0, ddof=1) / math.sqrt(RUNS) / (2 * math.log(2.0))
    np.testing.assert_array_less(np.abs(h_hat - LEVEL), 0.03 * LEVEL + SIGMAS * se)


def test_octave_flicker_sigma_sets_the_plateau():
    gen = np.random.default_rng(8)
    n, sigma = 2**14, 0.3
    values = np.array([
        sigmatau.oadev(octave_flicker(n, sigma=sigma, rows=n.bit_length() + 4, rng=gen), m=[64, 256]).var
        for _ in range(RUNS)
    ])
    exact = np.array([_octave_avar(m, n.bit_length() + 4) for m in (64, 256)]) * sigma**2
    _assert_mean_matches(values, exact, "octave_flicker")
    np.testing.assert_allclose(exact, 2 * sigma**2, rtol=0.02)


def _slope(values: np.ndarray, m_lo: int, m_hi: int, ms: list[int]) -> float:
    mean = values.mean(axis=0)
    return math.log(mean[ms.index(m_hi)] / mean[ms.index(m_lo)]) / math.log(m_hi / m_lo)


def test_tip_constructions_have_the_tips_slopes():
    # Variance slopes (numerics.md §5.1): AVAR WFM −1, RWFM +1; HVAR RRFM +3,
    # FWFM +2; MVAR FPM −2, FFM 0. The means of 30 runs fix a slope over
    # m = 4 … 64 to about ±0.05.
    cases = [(0, "oadev", -1.0), (-2, "oadev", 1.0), (-4, "ohdev", 3.0), (-3, "ohdev", 2.0),
             (1, "mdev", -2.0), (-1, "mdev", 0.0), (2, "mdev", -3.0)]
    for alpha, statistic, slope in cases:
        values = _all_runs(alpha, "tip")[statistic]
        assert _slope(values, 4, 64, MS) == pytest.approx(slope, abs=0.12), (alpha, statistic)


def test_tip_flicker_levels_are_close_to_the_continuous_formulas():
    # FWFM = cumsum(flicker FM) and FPM = diff(flicker) inherit the octave
    # approximation: within 5 % of the continuous formulas for m ≥ 16 (the FPM
    # check uses MVAR, which does not depend on the high cut-off).
    for alpha, statistic, continuous in ((-3, "ohdev", "hdev"), (1, "mdev", "mdev"), (-1, "oadev", "adev")):
        values = _all_runs(alpha, "tip")[statistic]
        mean = values.mean(axis=0)[2:]
        se = values.std(axis=0, ddof=1)[2:] / math.sqrt(RUNS)
        formula = expected_variance(alpha, LEVEL, np.array(MS[2:]) / RATE, statistic=continuous, rate=RATE)
        np.testing.assert_array_less(np.abs(mean - formula), 0.05 * formula + SIGMAS * se)
