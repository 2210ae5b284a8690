"""sigmatau.prep warm-up: a known exponential transient recovered within its stated uncertainty
over many seeds (coverage against binomial bounds, not tuned tolerances), the false-alarm rate
of the test on stationary records, the end rule, gaps, purity and bad input."""

from __future__ import annotations

import json
import math
import warnings

import numpy as np
import pytest
from scipy import stats as sps

from sigmatau.errors import DataError, ParameterError
from sigmatau.imu.simulation import simulate
from sigmatau.prep import PrepResult, PrepWarning, part
from sigmatau.prep import drop_warmup, warmup

P2 = float(sps.norm.cdf(2.0) - sps.norm.cdf(-2.0))  # 0.9545: coverage of ±2σ for a normal estimate
RATE = 100.0
NOISE = dict(duration=600.0, rate=RATE, unit="deg/s", N=0.005)  # σ = 0.05 °/s per sample
A_TRUE, T_TRUE = 0.02, 30.0


def binomial_bounds(trials: int, p: float, alpha: float = 1e-3) -> tuple[int, int]:
    """The two-sided (1 − alpha) acceptance range of counts out of ``trials`` at probability p."""
    return int(sps.binom.ppf(alpha / 2, trials, p)), int(sps.binom.isf(alpha / 2, trials, p))


@pytest.mark.slow
def test_time_constant_and_amplitude_are_recovered_within_their_stated_uncertainty():
    """White gyro noise plus A·exp(−t/T) (A = 0.4 σ per sample): ±2 SE covers the truth at the
    normal rate. Measured with these seeds: 80/80 detected, coverage 78/80 (A) and 78/80 (T)."""
    trials = 80
    cover_a = cover_t = detected = 0
    for seed in range(trials):
        y = simulate(**NOISE, warmup=(A_TRUE, T_TRUE), rng=1000 + seed)
        r = warmup(y, rate=RATE, alpha=0.05)
        a, t = r.estimates["amplitude"], r.estimates["time_constant"]
        detected += r.details["detected"]
        cover_a += abs(a.value - A_TRUE) < 2 * a.stderr
        cover_t += abs(t.value - T_TRUE) < 2 * t.stderr
    lo, hi = binomial_bounds(trials, P2)
    assert detected == trials
    assert lo <= cover_a <= hi, (cover_a, lo, hi)
    assert lo <= cover_t <= hi, (cover_t, lo, hi)


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["white", "white+flicker"])
def test_a_stationary_record_reports_no_warmup_at_about_the_false_alarm_rate(kind):
    """Davies' bound makes the test conservative but close: with these seeds 8/200 (white) and
    7/100 (white + flicker B = 0.002 °/s) at alpha = 0.05; 7/100 on the euroc-gyro preset."""
    trials, alpha = (200, 0.05) if kind == "white" else (100, 0.05)
    extra = {"B": 0.002} if kind == "white+flicker" else {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PrepWarning)  # a false alarm may come with a fit-at-bound warning
        alarms = sum(warmup(simulate(**NOISE, **extra, rng=5000 + s), rate=RATE, alpha=alpha).details["detected"]
                     for s in range(trials))
    _, hi = binomial_bounds(trials, alpha)
    assert alarms <= hi, (alarms, hi)
    assert alarms >= 1  # not blind: a bound far too loose would give none


def test_stationary_white_record_is_kept_whole(rng):
    y = simulate(**NOISE, rng=rng)
    r = warmup(y, rate=RATE)
    assert not r.details["detected"] and r.details["end_index"] == 0
    np.testing.assert_array_equal(r.data, y)
    assert r.indices.size == 0 and r.details["p_value"] >= 0.01


def test_end_follows_the_documented_rule_and_the_cut_is_exact(rng):
    y = simulate(**NOISE, warmup=(0.2, 20.0), rng=rng)
    before = y.copy()
    r = warmup(y, rate=RATE)
    np.testing.assert_array_equal(y, before)  # the input is not modified
    e = r.estimates
    t_end = e["time_constant"].value * math.log(abs(e["amplitude"].value) / e["settled_bias"].stderr)
    assert e["end"].value == pytest.approx(t_end, rel=1e-12)
    k = math.ceil(t_end * RATE - 1e-9)
    assert r.details["end_index"] == k and r.details["end_time"] == pytest.approx(k / RATE)
    np.testing.assert_array_equal(r.data, y[k:])
    np.testing.assert_array_equal(r.indices, np.arange(k))
    assert not r.data.flags.writeable and isinstance(r, PrepResult) and r.step == "warmup"
    # the transient left at the cut is below the settled bias' standard error
    assert abs(e["amplitude"].value) * math.exp(-k / RATE / e["time_constant"].value) <= e["settled_bias"].stderr
    d = r.to_dict()
    json.dumps(d, allow_nan=False)
    assert d["details"]["detected"] is True and "end_rule" in d["details"]


def test_gaps_are_tolerated(rng):
    y = simulate(**NOISE, warmup=(0.1, 30.0), rng=rng)
    y[rng.choice(y.size, y.size // 20, replace=False)] = np.nan
    y[1000:1500] = np.nan  # a burst inside the transient
    y[:3] = np.nan  # and at the very start
    r = warmup(y, rate=RATE)
    t = r.estimates["time_constant"]
    assert r.details["detected"]
    assert abs(t.value - 30.0) < 4 * t.stderr
    np.testing.assert_array_equal(r.data, y[r.details["end_index"]:])


def test_a_transient_that_does_not_settle_is_warned_about_and_nothing_is_cut(rng):
    y = simulate(**NOISE, warmup=(1.0, 2000.0), rng=rng)
    with pytest.warns(PrepWarning, match="does not settle|as slow as the record"):
        r = warmup(y, rate=RATE)
    assert r.details["detected"] and r.data.size == y.size and r.indices.size == 0


def test_bad_input_gets_one_clear_line():
    with pytest.raises(DataError, match="too short") as err:
        warmup(np.ones(20), rate=1.0)
    assert "\n" not in str(err.value)
    with pytest.raises(DataError, match="NaN"):
        warmup(np.full(1000, np.nan), rate=1.0)
    with pytest.raises(DataError, match="1-D"):
        warmup(np.ones((30, 30)), rate=1.0)
    with pytest.raises(ParameterError, match="alpha"):
        warmup(np.ones(1000), rate=1.0, alpha=1.5)
    with pytest.raises(ParameterError):
        warmup(np.ones(1000), rate=-1.0)


def test_a_constant_record_has_no_warmup():
    r = warmup(np.full(1000, 3.0), rate=10.0)
    assert not r.details["detected"] and r.data.size == 1000


def test_drop_warmup_cuts_the_given_duration_like_part(rng):
    y = rng.standard_normal(500)
    r = drop_warmup(y, rate=10.0, seconds=12.34)
    np.testing.assert_array_equal(r.data, part(y, start=12.34, rate=10.0, unit="seconds").data)
    assert r.step == "warmup" and r.details["mode"] == "given" and r.details["end_index"] == 124
    np.testing.assert_array_equal(r.indices, np.arange(124))
    assert drop_warmup(y, rate=10.0, seconds=0).data.size == 500
    for bad in (-1.0, 50.0, float("nan"), "10"):
        with pytest.raises(ParameterError, match="seconds"):
            drop_warmup(y, rate=10.0, seconds=bad)
