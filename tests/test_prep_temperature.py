"""sigmatau.prep temperature fit and the simulator's environment options: a temperature ramp with
a known tempco recovered within its stated uncertainty over many seeds (binomial bounds), the
order chosen by BIC, the compensated residual's OADEV, gaps from the temperature, bad input;
the coloured-noise model of the block means (its covariances against the power-law table and the
generators, the coverage and order under flicker and random-walk bias, little change on white
data); simulate()'s new keywords add exactly what they say and leave the default output unchanged."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy import stats as sps

from sigmatau import oadev
from sigmatau.errors import DataError, ParameterError
from sigmatau.imu.simulation import simulate, temperature_profile
from sigmatau.prep import PrepWarning
from sigmatau.prep import temperature_fit

P2 = float(sps.norm.cdf(2.0) - sps.norm.cdf(-2.0))
RATE = 100.0
NOISE = dict(duration=1800.0, rate=RATE, unit="deg/s", N=0.005)  # σ = 0.05 °/s per sample
RAMP = temperature_profile(1800.0, RATE, "ramp", low=20.0, high=40.0)
TEMPCO = 0.002  # °/s per K = 7.2 °/h/°C


def binomial_bounds(trials: int, p: float = P2, alpha: float = 1e-3) -> tuple[int, int]:
    return int(sps.binom.ppf(alpha / 2, trials, p)), int(sps.binom.isf(alpha / 2, trials, p))


# -- simulate(): the new options -------------------------------------------------------------------------

def test_simulate_default_output_is_unchanged_by_the_new_options():
    base = simulate("euroc-gyro", duration=20.0, rng=7)
    same = simulate("euroc-gyro", duration=20.0, rng=7, warmup=None, temperature=None, tempco=None)
    np.testing.assert_array_equal(base, same)


def test_simulate_adds_exactly_the_warmup_and_the_temperature_term():
    base = simulate(duration=100.0, rate=10.0, N=0.01, B=0.001, rng=3)
    t = np.arange(base.size) / 10.0
    w = simulate(duration=100.0, rate=10.0, N=0.01, B=0.001, rng=3, warmup=(0.5, 12.0))
    np.testing.assert_allclose(w - base, 0.5 * np.exp(-t / 12.0), rtol=0, atol=1e-15)
    temp = temperature_profile(100.0, 10.0, "cycle", low=10.0, high=30.0, period=50.0)
    c = simulate(duration=100.0, rate=10.0, N=0.01, B=0.001, rng=3, temperature=temp, tempco=(0.01, -2e-4))
    dt = temp - temp.mean()
    np.testing.assert_allclose(c - base, 0.01 * dt - 2e-4 * dt ** 2, rtol=0, atol=1e-14)
    f = simulate(duration=100.0, rate=10.0, N=0.01, B=0.001, rng=3, temperature=lambda s: 20.0 + 0.1 * s,
                 tempco=0.01)
    np.testing.assert_allclose(f - base, 0.01 * 0.1 * (t - t.mean()), rtol=0, atol=1e-14)


def test_temperature_profile_and_simulate_option_checks():
    np.testing.assert_allclose(temperature_profile(4.0, 1.0, "cycle", low=0.0, high=2.0, period=4.0),
                               [0.0, 1.0, 2.0, 1.0], atol=1e-15)
    with pytest.raises(ParameterError, match="kind"):
        temperature_profile(4.0, 1.0, "step")
    with pytest.raises(ParameterError, match="tempco needs temperature"):
        simulate(duration=1.0, rate=10.0, N=1.0, tempco=0.1)
    with pytest.raises(ParameterError, match="shape"):
        simulate(duration=1.0, rate=10.0, N=1.0, temperature=np.ones(3), tempco=0.1)
    with pytest.raises(ParameterError, match="warmup"):
        simulate(duration=1.0, rate=10.0, N=1.0, warmup=(1.0, 0.0))
    with pytest.raises(ParameterError, match="finite"):
        simulate(duration=1.0, rate=10.0, N=1.0, temperature=np.full(10, np.nan), tempco=0.1)


# -- temperature_fit against known truth -----------------------------------------------------------------

@pytest.mark.slow
def test_tempco_of_a_ramp_is_recovered_within_its_stated_uncertainty():
    """White noise and a 20 → 40 °C ramp: ±2 SE covers the true tempco at the normal rate
    (measured with these seeds 117/120; 112/120 before the coloured-noise model) and BIC picks
    order 1 (118/120, as before)."""
    trials = 120
    covered = order1 = 0
    for seed in range(trials):
        y = simulate(**NOISE, temperature=RAMP, tempco=TEMPCO, rng=500 + seed)
        r = temperature_fit(y, RAMP, rate=RATE, unit="deg/s")
        tc = r.estimates["tempco"]
        covered += abs(tc.value - TEMPCO) < 2 * tc.stderr
        order1 += r.details["order"] == 1
    lo, hi = binomial_bounds(trials)
    assert lo <= covered <= hi, (covered, lo, hi)
    assert order1 >= binomial_bounds(trials, 0.9)[0]


def test_a_quadratic_dependence_is_found_and_its_coefficients_recovered(rng):
    y = simulate(**NOISE, temperature=RAMP, tempco=(TEMPCO, 1e-4), rng=rng)
    r = temperature_fit(y, RAMP, rate=RATE, unit="deg/s")
    assert r.details["order"] == 2
    c1, c2 = r.estimates["c1"], r.estimates["c2"]
    assert abs(c1.value - TEMPCO) < 4 * c1.stderr and abs(c2.value - 1e-4) < 4 * c2.stderr
    assert r.estimates["tempco"] == c1 and c2.unit == "deg/s/K^2"


def test_compensated_residual_loses_the_long_term_error_and_keeps_the_white_noise(rng):
    y = simulate(**NOISE, temperature=RAMP, tempco=TEMPCO, rng=rng)
    r = temperature_fit(y, RAMP, rate=RATE, unit="deg/s")
    raw = oadev(y, rate=RATE, taus="octave")
    comp = oadev(r.data, rate=RATE, taus="octave")
    # white part (τ0): the ramp adds R·τ0/√2, a relative 1e-8 here
    assert comp.dev[0] == pytest.approx(raw.dev[0], rel=1e-3)
    # long τ: the raw curve is the ramp's R·τ/√2, the compensated one back on N/√τ
    long = comp.taus >= 100.0
    assert long.any()
    assert np.all(comp.ci_high[long] < raw.ci_low[long])
    expect = 0.005 / np.sqrt(comp.taus[long])
    assert np.all((comp.ci_low[long] < 1.5 * expect) & (comp.ci_high[long] > expect / 1.5))


def test_no_dependence_gives_order_zero_and_removes_nothing(rng):
    y = simulate(**NOISE, rng=rng)
    r = temperature_fit(y, RAMP, rate=RATE)
    if r.details["order"] == 0:  # BIC may pick order 1 by chance (rarely); then the tempco is still ~0
        np.testing.assert_array_equal(r.data, y)
        assert not r.details["significant"]
    tc = r.estimates["tempco"]
    assert abs(tc.value) < 4 * tc.stderr and tc.unit == "data/K"


def test_missing_temperatures_become_gaps_and_the_input_is_not_modified(rng):
    y = simulate(**NOISE, temperature=RAMP, tempco=TEMPCO, rng=rng)
    temp = RAMP.copy()
    temp[[5, 6, 7, 9000]] = np.nan
    y[100] = np.nan
    y0, t0 = y.copy(), temp.copy()
    with pytest.warns(PrepWarning, match="4 sample"):
        r = temperature_fit(y, temp, rate=RATE)
    np.testing.assert_array_equal(y, y0)
    np.testing.assert_array_equal(temp, t0)
    assert np.isnan(r.data[[5, 6, 7, 9000, 100]]).all() and np.count_nonzero(np.isnan(r.data)) == 5
    np.testing.assert_array_equal(r.indices, [5, 6, 7, 9000])
    assert not r.data.flags.writeable and r.step == "temperature"
    json.dumps(r.to_dict(), allow_nan=False)


def test_bad_input_gets_one_clear_line():
    y = np.random.default_rng(1).standard_normal(1000)
    with pytest.raises(DataError, match="^the temperature does not vary: no temperature dependence can be fitted$"):
        temperature_fit(y, np.full(1000, 25.0), rate=1.0)
    with pytest.raises(DataError, match="temperature") as err:
        temperature_fit(y, np.full(1000, np.nan), rate=1.0)
    assert "\n" not in str(err.value)
    with pytest.raises(DataError, match="must match"):
        temperature_fit(y, np.arange(999.0), rate=1.0)
    with pytest.raises(DataError, match="too few blocks"):
        temperature_fit(y[:4], np.arange(4.0), rate=1.0)
    with pytest.raises(ParameterError, match="max_order"):
        temperature_fit(y, np.arange(1000.0), rate=1.0, max_order=9)
    with pytest.raises(ParameterError):
        temperature_fit(y, np.arange(1000.0), rate=0.0)


# -- the noise model of the block means (white + flicker + random walk) ----------------------------------

def _full_blocks(k: int, m: int, length: float = 1.0):
    from sigmatau.prep._bias_noise import BlockLayout

    start = np.arange(k) * length
    return BlockLayout(start, start + length, np.full(k, m), m, k * length)


def test_block_mean_covariances_give_each_power_law_its_allan_variance():
    """The closed-form block-mean covariances against the project's power-law table: adjacent
    blocks of length τ give AVAR(τ) = 2 ln 2·h₋₁ (flicker kernel ln(S/|τ|): h₋₁ = 1) and
    (2π²/3)·h₋₂·τ (random-walk kernel S − |τ|: π²h₋₂ = 1), whatever the block length; the
    matrices are positive definite."""
    from sigmatau.core.powerlaw import response
    from sigmatau.prep._bias_noise import flicker_covariance, random_walk_covariance

    for length in (1.0, 2.5, 40.0):
        lay = _full_blocks(50, 10, length)
        f, w = flicker_covariance(lay), random_walk_covariance(lay)
        tau = np.array([length])
        avar_f = 0.5 * (f[0, 0] + f[1, 1] - 2 * f[0, 1])
        avar_w = 0.5 * (w[0, 0] + w[1, 1] - 2 * w[0, 1])
        assert avar_f == pytest.approx(response("avar", -1, tau, 1.0)[0], rel=1e-9)
        assert avar_w == pytest.approx(response("avar", -2, tau, 1.0)[0] / np.pi ** 2, rel=1e-9)
        # the Allan variance at 2τ from the means of blocks 0–1 and 2–3: flicker's is the same
        pair = 0.25 * (f[0, 0] + f[1, 1] + 2 * f[0, 1]) + 0.25 * (f[2, 2] + f[3, 3] + 2 * f[2, 3])
        cross = 0.25 * (f[0, 2] + f[0, 3] + f[1, 2] + f[1, 3])
        assert 0.5 * (pair - 2 * cross) == pytest.approx(2 * np.log(2), rel=1e-9)
        np.linalg.cholesky(f)
        np.linalg.cholesky(w)


def test_block_mean_covariance_matches_the_generators():
    """Block means of Kasdin flicker and of a random walk (sigmatau.generate.power_law_noise): the
    mean square difference of block means d blocks apart against the model, within 4 standard
    errors of its Monte-Carlo mean (the SE from the realisations' spread)."""
    from sigmatau.generate import power_law_noise
    from sigmatau.prep._bias_noise import flicker_covariance, random_walk_covariance

    rng = np.random.default_rng(20261128)
    m, k, reps = 64, 64, 200
    lay = _full_blocks(k, m)
    lags = np.array([1, 2, 4, 8, 16])
    for alpha, cov, scale in ((-1, flicker_covariance(lay), 1.0), (-2, random_walk_covariance(lay), m * np.pi ** 2)):
        # h_α = 1 at rate 1: the flicker kernel is h₋₁·ln(S/|τ|), the random walk's π²h₋₂·(S − |τ|), τ in samples
        model = np.array([np.mean(np.diag(cov)[:-d] + np.diag(cov)[d:] - 2 * np.diagonal(cov, d)) for d in lags])
        sims = np.empty((reps, lags.size))
        for r in range(reps):
            y = power_law_noise(m * k, alpha, h=1.0, rate=1.0, rng=rng)
            means = y.reshape(k, m).mean(axis=1)
            sims[r] = [np.mean((means[d:] - means[:-d]) ** 2) for d in lags]
        got, se = sims.mean(axis=0), sims.std(axis=0, ddof=1) / np.sqrt(reps)
        np.testing.assert_array_less(np.abs(got - scale * model), 4 * se)


def test_the_noise_model_behind_the_errors_is_recorded(rng):
    temp = temperature_profile(1800.0, RATE, "cycle", low=20.0, high=40.0)
    y = simulate(**NOISE, B=0.002, temperature=temp, tempco=TEMPCO, rng=rng)
    r = temperature_fit(y, temp, rate=RATE, unit="deg/s")
    d = r.details
    assert d["noise_model"].startswith("white + flicker + random walk")
    assert set(d["noise_levels"]) == {"N", "B", "K"} and set(d["noise_probability"]) == {"flicker", "random_walk"}
    # a bias instability this strong is found (its posterior probability near 1, its level near 0.002)
    assert d["noise_probability"]["flicker"] > 0.9 and 0.5 < d["noise_levels"]["B"] / 0.002 < 2.0
    assert any("REML" in n for n in r.notes)
    json.dumps(r.to_dict(), allow_nan=False)
    # too few blocks for the coloured levels: white block means, said so
    short = temperature_fit(y[:20], temp[:20], rate=RATE)
    assert short.details["noise_model"].startswith("white (") and short.details["noise_probability"]["flicker"] == 0


@pytest.mark.slow
def test_white_data_give_nearly_the_weighted_least_squares_answer():
    """White noise on a cycle: the result changes little from the former weighted least squares on
    the block means (computed here): the tempco within 0.1 of its standard error of the WLS value,
    the standard error from 0.95 to 1.5 times the WLS one (the posterior keeps some weight on
    flicker and random walk at levels the record cannot rule out), 1.25 times at most in the
    median record."""
    temp = temperature_profile(1800.0, RATE, "cycle", low=20.0, high=40.0)
    ratios, shifts = [], []
    for seed in range(12):
        y = simulate(**NOISE, temperature=temp, tempco=TEMPCO, rng=np.random.default_rng([31, seed]))
        r = temperature_fit(y, temp, rate=RATE)
        m = y.size // 200
        yb, tb = y.reshape(-1, m).mean(axis=1), temp.reshape(-1, m).mean(axis=1) - temp.mean()
        tb2 = (temp - temp.mean()).reshape(-1, m)
        powers = [(tb2 ** j).mean(axis=1) for j in range(2, r.details["order"] + 1)]
        x = np.column_stack([np.ones(tb.size), tb] + powers)
        beta, rss = np.linalg.lstsq(x, yb, rcond=None)[:2]
        se = np.sqrt(rss[0] / (yb.size - x.shape[1]) * np.linalg.inv(x.T @ x)[1, 1])
        tc = r.estimates["tempco"]
        shifts.append(abs(tc.value - beta[1]) / se)
        ratios.append(tc.stderr / se)
    assert max(shifts) < 0.1, shifts
    assert 0.95 < min(ratios) and max(ratios) < 1.5 and np.median(ratios) < 1.25, ratios


def _coverage(kind: str, noise: dict, trials: int, seed: int) -> tuple[int, int, list[int]]:
    temp = temperature_profile(1800.0, RATE, kind, low=20.0, high=40.0)
    covered1 = covered2 = 0
    orders = [0, 0, 0, 0]
    for s in range(trials):
        y = simulate(**NOISE, **noise, temperature=temp, tempco=TEMPCO, rng=np.random.default_rng([seed, s]))
        r = temperature_fit(y, temp, rate=RATE, unit="deg/s")
        tc = r.estimates["tempco"]
        covered1 += abs(tc.value - TEMPCO) < tc.stderr
        covered2 += abs(tc.value - TEMPCO) < 2 * tc.stderr
        orders[r.details["order"]] += 1
    return covered1, covered2, orders


@pytest.mark.slow
@pytest.mark.parametrize("kind, noise", [("cycle", dict(B=0.002)), ("ramp", dict(B=0.002, K=1e-4))],
                         ids=["flicker-cycle", "flicker+random-walk-ramp"])
def test_tempco_coverage_under_flicker_and_random_walk_bias(kind, noise):
    """Coloured bias noise at an IMU-like level (bias instability B = 0.002 °/s = 7.2 °/h against
    white N = 0.005 °/s/√Hz: flicker dominates the block-mean scatter beyond ~15 s; random walk
    K = 1e-4 °/s/√s beyond ~90 s): ±2 SE covers the true tempco at the nominal rate (within 3
    binomial standard errors) and ±1 SE at no less than its nominal rate less 3 SE (the errors
    may be conservative: on a ramp, a random walk the record cannot rule out is counted); BIC
    chooses the true order 1 in ≥ 90 % (binomial bound). Measured with these seeds: ±2 SE 78/80
    and 77/80, ±1 SE 67/80 and 63/80, order 1 in 80/80 and 76/80; with independent block means
    assumed (the former errors) ±2 SE covered 23/80 and 11/80 and order 1 was chosen in 33/80
    and 20/80."""
    trials = 80
    c1, c2, orders = _coverage(kind, noise, trials, 20261128)
    p1 = float(sps.norm.cdf(1.0) - sps.norm.cdf(-1.0))
    for covered, p, upper in ((c2, P2, True), (c1, p1, False)):
        se = np.sqrt(p * (1 - p) / trials)
        assert covered / trials >= p - 3 * se, (covered, p, orders)
        if upper:
            assert covered / trials <= p + 3 * se, (covered, p, orders)
    assert orders[1] >= binomial_bounds(trials, 0.9)[0], orders
