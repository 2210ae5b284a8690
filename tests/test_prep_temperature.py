"""sigmatau.prep temperature fit and the simulator's environment options: a temperature ramp with
a known tempco recovered within its stated uncertainty over many seeds (binomial bounds), the
order chosen by BIC, the compensated residual's OADEV, gaps from the temperature, bad input;
simulate()'s new keywords add exactly what they say and leave the default output unchanged."""

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

def test_tempco_of_a_ramp_is_recovered_within_its_stated_uncertainty():
    """White noise and a 20 → 40 °C ramp: ±2 SE covers the true tempco at the normal rate
    (measured with these seeds 112/120) and BIC picks order 1 (118/120)."""
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
