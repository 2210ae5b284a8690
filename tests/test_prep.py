"""sigmatau.prep: each step against known truth, purity, gaps, bad input, and the drift
standard errors' coverage over many independent draws (binomial bounds, not tuned tolerances)."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest
from scipy import stats as sps

from helpers import assert_printed
from sigmatau.datasets import nbs1000
from sigmatau.errors import DataError, ParameterError
from sigmatau.prep import (DRIFT_MODELS, NOMINAL_NOISE, PrepResult, PrepWarning, average, drift, fill,
                           frequency_offset, gap_runs, outliers, part)

P2 = float(sps.norm.cdf(2.0) - sps.norm.cdf(-2.0))  # 0.9545: coverage of ±2σ for a normal estimate


def binomial_bounds(trials: int, p: float = P2, alpha: float = 1e-3) -> tuple[int, int]:
    """The two-sided (1 − alpha) acceptance range of covered counts out of ``trials``."""
    return int(sps.binom.ppf(alpha / 2, trials, p)), int(sps.binom.isf(alpha / 2, trials, p))


# -- noise of known type, with a known drift ------------------------------------------------------------

def noise(rng: np.random.Generator, kind: str, n: int, data_type: str, tau0: float, level: float) -> np.ndarray:
    """Power-law noise of ``kind`` (wpm, wfm, rwfm) as phase or frequency, ``n`` samples."""
    if kind == "wpm":
        x = level * rng.standard_normal(n + (data_type == "freq"))
        return x if data_type == "phase" else np.diff(x) / tau0
    if kind == "wfm":
        y = level * rng.standard_normal(n)
    else:
        y = np.cumsum(level * rng.standard_normal(n))
    if data_type == "freq":
        return y
    return np.concatenate(([0.0], np.cumsum(y[:-1]) * tau0))


def with_drift(v: np.ndarray, data_type: str, tau0: float, d: float) -> np.ndarray:
    """Add an offset, a frequency offset and a drift d (per second) to phase or frequency noise."""
    t = np.arange(v.size) * tau0
    if data_type == "phase":
        return v + 3e-6 + 2e-7 * t + 0.5 * d * t ** 2
    return v + 2e-7 + d * t


# -- the drift models: exact on noise-free data, equal to their written definitions -----------------------

@pytest.mark.parametrize("model", DRIFT_MODELS["phase"])
@pytest.mark.parametrize("gaps", [False, True])
def test_every_phase_model_is_exact_on_a_noise_free_quadratic(model, gaps):
    tau0, d = 0.5, 3.7e-9
    x = with_drift(np.zeros(301), "phase", tau0, d)
    if gaps:
        x[[0, 7, 8, 150, 151, 299]] = np.nan
    r = drift(x, data_type="phase", rate=1 / tau0, model=model)
    np.testing.assert_allclose(r.estimates["drift"].value, d, rtol=1e-7)
    np.testing.assert_allclose(r.estimates["drift_per_day"].value, d * 86400, rtol=1e-7)


@pytest.mark.parametrize("model", ["linear", "bisection"])
@pytest.mark.parametrize("gaps", [False, True])
def test_every_linear_frequency_model_is_exact_on_a_noise_free_line(model, gaps):
    y = with_drift(np.zeros(300), "freq", 2.0, 4.2e-10)
    if gaps:
        y[[0, 10, 11, 200, 299]] = np.nan
    r = drift(y, data_type="freq", rate=0.5, model=model)
    np.testing.assert_allclose(r.estimates["drift"].value, 4.2e-10, rtol=1e-9)
    assert np.nanmax(np.abs(r.data - np.nanmean(r.data))) < 1e-15


def test_models_equal_their_written_definitions(rng):
    """Each estimator against the formula printed in SP1065 / Greenhall (1997), without gaps."""
    tau0 = 2.0
    x = np.cumsum(rng.standard_normal(1001)) * 1e-9  # odd N: the 3-point middle is exact
    n = x.size
    got = {m: drift(x, data_type="phase", rate=1 / tau0, model=m).estimates["drift"].value
           for m in DRIFT_MODELS["phase"]}
    t = np.arange(n) * tau0
    np.testing.assert_allclose(got["quadratic"], 2 * np.polyfit(t, x, 2)[0], rtol=1e-8)
    np.testing.assert_allclose(got["diff2"], np.mean(np.diff(x, 2)) / tau0 ** 2, rtol=1e-10)
    np.testing.assert_allclose(got["3point"], 4 * (x[-1] - 2 * x[n // 2] + x[0]) / ((n - 1) * tau0) ** 2,
                               rtol=1e-10)
    # Greenhall: D = 6/(N³τ0² r(1−r))·[w(N) − (w(N−n1) − w(n1))/(1 − 2r)], w(k) = Σ_{i<k} x_i.
    w = np.concatenate(([0.0], np.cumsum(x)))
    n1 = n // 10
    r1 = n1 / n
    greenhall = 6 / (n ** 3 * tau0 ** 2 * r1 * (1 - r1)) * (w[n] - (w[n - n1] - w[n1]) / (1 - 2 * r1))
    np.testing.assert_allclose(got["greenhall"], greenhall, rtol=1e-9)
    y = rng.standard_normal(1000)
    lin = drift(y, data_type="freq", rate=1 / tau0, model="linear").estimates["drift"].value
    np.testing.assert_allclose(lin, np.polyfit(np.arange(1000) * tau0, y, 1)[0], rtol=1e-9)
    bis = drift(y, data_type="freq", rate=1 / tau0, model="bisection").estimates["drift"].value
    np.testing.assert_allclose(bis, 2 * (y[500:].mean() - y[:500].mean()) / (1000 * tau0), rtol=1e-10)


def _generator(kind: str, data_type: str, n: int, tau0: float) -> np.ndarray:
    """G with v = G·e, e independent unit normals: the noise model of sigmatau.prep._common written out."""
    strict = np.tril(np.ones((n, n)), -1)  # [i, j] = 1 for j < i
    if data_type == "phase":
        if kind == "wpm":
            return np.eye(n)
        if kind == "wfm":
            return tau0 * strict[:, : n - 1]  # x_i = τ0 Σ_{j<i} y_j
        walk = np.tril(np.ones((n - 1, n - 2)), -1)  # y_j = Σ_{1≤l≤j} w_l, then integrated
        return tau0 * strict[:, : n - 1] @ walk
    if kind == "wpm":
        return (np.eye(n, n + 1, 1) - np.eye(n, n + 1)) / tau0  # y_j = (x_{j+1} − x_j)/τ0
    if kind == "wfm":
        return np.eye(n)
    return np.tril(np.ones((n, n - 1)), -1)  # y_j = Σ_{1≤l≤j} w_l


@pytest.mark.parametrize("data_type", ["phase", "freq"])
@pytest.mark.parametrize("kind", ["wpm", "wfm", "rwfm"])
def test_functional_variance_equals_the_written_out_covariance(rng, data_type, kind):
    from sigmatau.prep._common import functional_variance
    n, tau0 = 23, 0.3
    c = rng.standard_normal(n)
    c[[4, 11]] = 0.0  # gaps carry no weight; the initial state is held fixed, so any weights do
    g = _generator(kind, data_type, n, tau0)
    np.testing.assert_allclose(functional_variance(c, data_type, kind, 2.5, tau0), 2.5 * c @ g @ g.T @ c,
                               rtol=1e-12)


def test_nbs1000_linear_slope_and_intercept_match_the_printed_digits():
    """NBS 1000-point set (SP1065 Table 31 summary rows, numerics.md §7.1): linear slope
    6.490910e-06 per sample and intercept 4.865323e-01 at the first sample, τ0 = 1 s."""
    r = drift(nbs1000(), data_type="freq", rate=1.0, model="linear")
    assert_printed(r.estimates["drift"].value, "6.490910e-06")
    assert_printed(r.estimates["b"].value, "6.490910e-06")
    assert_printed(r.estimates["a"].value, "4.865323e-01")
    # The mean of the set (same table): 4.897745e-01.
    assert_printed(frequency_offset(nbs1000(), data_type="freq", rate=1.0)
                   .estimates["frequency_offset"].value, "4.897745e-01")


# -- coverage of the stated uncertainty over many independent draws -----------------------------------

def _coverage(rng, model, data_type, kind, trials=1000, n=256, noise_arg=None, gap_share=0.0):
    tau0, d = 0.5, 2e-9
    z = []
    for _ in range(trials):
        v = with_drift(noise(rng, kind, n, data_type, tau0, 1e-9), data_type, tau0, d)
        if gap_share:
            v[rng.random(n) < gap_share] = np.nan
        e = drift(v, data_type=data_type, rate=1 / tau0, model=model, noise=noise_arg).estimates["drift"]
        z.append((e.value - d) / e.stderr)
    return np.asarray(z)


CASES = [  # model, data type, noise simulated, noise= given (None: the model's nominal one)
    ("quadratic", "phase", "wpm", None),
    ("diff2", "phase", "rwfm", None),
    ("3point", "phase", "wfm", None),
    ("greenhall", "phase", "wfm", None),
    ("linear", "freq", "wfm", None),
    ("bisection", "freq", "wfm", None),
    ("greenhall", "phase", "rwfm", "rwfm"),
    ("quadratic", "phase", "wfm", "wfm"),
    ("bisection", "freq", "rwfm", "rwfm"),
    ("linear", "freq", "wpm", "wpm"),
]


@pytest.mark.slow
@pytest.mark.parametrize("model,data_type,kind,noise_arg", CASES)
def test_drift_is_recovered_within_its_standard_error(rng, model, data_type, kind, noise_arg):
    assert noise_arg is not None or NOMINAL_NOISE[model] == kind
    z = _coverage(rng, model, data_type, kind, noise_arg=noise_arg)
    lo, hi = binomial_bounds(z.size)
    covered = int(np.sum(np.abs(z) <= 2.0))
    assert lo <= covered <= hi, (covered, lo, hi)
    # No bias either: the mean z of unbiased, calibrated estimates is N(0, 1/trials).
    assert abs(z.mean()) < 4.0 / np.sqrt(z.size)


@pytest.mark.parametrize("model,data_type,kind", [("quadratic", "phase", "wpm"), ("greenhall", "phase", "wfm"),
                                                   ("linear", "freq", "wfm"), ("diff2", "phase", "rwfm")])
def test_coverage_holds_with_gaps(rng, model, data_type, kind):
    z = _coverage(rng, model, data_type, kind, trials=500, gap_share=0.05)
    lo, hi = binomial_bounds(z.size)
    assert lo <= int(np.sum(np.abs(z) <= 2.0)) <= hi


def _nonlinear_truth(model: str, t: np.ndarray) -> tuple[np.ndarray, float]:
    span = t[-1]
    if model == "log":
        a, b, c = 1e-8, 20.0 / span, 3e-9
        return a * np.log1p(b * t) + c, a * b / (b * span + 1)
    a, b, c = 2e-9, 1e-8 / np.sqrt(span), 0.05 * span
    return a + b * np.sqrt(t + c), b / (2 * np.sqrt(span + c))


@pytest.mark.slow
@pytest.mark.parametrize("model", ["log", "diffusion"])
def test_nonlinear_models_recover_the_slope_within_their_standard_error(rng, model):
    t = np.arange(400) * 10.0
    curve, slope = _nonlinear_truth(model, t)
    z = []
    for _ in range(300):
        y = curve + 1e-10 * rng.standard_normal(t.size)
        e = drift(y, data_type="freq", rate=0.1, model=model).estimates["drift"]
        z.append((e.value - slope) / e.stderr)
    z = np.asarray(z)
    lo, hi = binomial_bounds(z.size)
    assert lo <= int(np.sum(np.abs(z) <= 2.0)) <= hi
    assert abs(z.mean()) < 4.0 / np.sqrt(z.size)


def test_nonlinear_fit_returns_parameters_and_residual(rng):
    t = np.arange(400) * 10.0
    curve, _ = _nonlinear_truth("log", t)
    y = curve + 1e-10 * rng.standard_normal(t.size)
    y[[5, 100]] = np.nan
    r = drift(y, data_type="freq", rate=0.1, model="log")
    for name, true in (("a", 1e-8), ("b", 20.0 / t[-1]), ("c", 3e-9)):
        e = r.estimates[name]
        assert abs(e.value - true) < 5 * e.stderr, (name, e, true)
    assert np.isnan(r.data[[5, 100]]).all()
    assert np.nanstd(r.data) < 2e-10


def test_a_poorly_determined_curve_is_warned_about_at_the_callers_line(rng):
    y = 1e-9 * np.arange(300.0) + 1e-8 * rng.standard_normal(300)  # straight: no log curvature
    with pytest.warns(PrepWarning, match="poorly determined") as record:
        drift(y, data_type="freq", rate=1.0, model="log")
    assert record[0].filename == __file__


def test_blocks_sit_on_the_valid_span_so_leading_and_trailing_gaps_are_fine():
    x = 0.5 * 1e-9 * (np.arange(500.0) * 2.0) ** 2
    x[:60] = np.nan
    x[-30:] = np.nan
    for model in ("greenhall", "3point", "diff2", "quadratic"):
        r = drift(x, data_type="phase", rate=0.5, model=model)
        np.testing.assert_allclose(r.estimates["drift"].value, 1e-9, rtol=1e-7)
    r = drift(x, data_type="phase", rate=0.5, model="greenhall")
    assert r.details["blocks"][0][0] == 60 and r.details["blocks"][-1][1] == 470


# -- frequency offset -------------------------------------------------------------------------------------

@pytest.mark.parametrize("data_type,kind", [("freq", "wfm"), ("phase", "wpm")])
def test_frequency_offset_is_recovered_within_its_standard_error(rng, data_type, kind):
    tau0, f = 0.25, 3e-8
    z = []
    for _ in range(1000):
        v = noise(rng, kind, 200, data_type, tau0, 1e-9)
        v = v + (f * np.arange(v.size) * tau0 if data_type == "phase" else f)
        v[rng.random(v.size) < 0.03] = np.nan
        e = frequency_offset(v, data_type=data_type, rate=1 / tau0).estimates["frequency_offset"]
        z.append((e.value - f) / e.stderr)
    lo, hi = binomial_bounds(len(z))
    assert lo <= int(np.sum(np.abs(np.asarray(z)) <= 2.0)) <= hi


def test_frequency_offset_removes_the_line_from_phase():
    x = 5.0 + 2e-6 * np.arange(50.0)
    r = frequency_offset(x, data_type="phase", rate=1.0)
    np.testing.assert_allclose(r.estimates["frequency_offset"].value, 2e-6, rtol=1e-10)
    np.testing.assert_allclose(r.estimates["phase_offset"].value, 5.0, rtol=1e-12)
    assert np.max(np.abs(r.data)) < 1e-12


# -- outliers ----------------------------------------------------------------------------------------------

def test_outliers_finds_exactly_the_planted_ones(rng):
    y = rng.standard_normal(2000)
    planted = np.array([3, 500, 501, 1200, 1999])
    y[planted] += np.array([12.0, -15.0, 11.0, 20.0, -9.0])
    y[[50, 51]] = np.nan
    r = outliers(y, k=5.0)
    assert r.indices.tolist() == planted.tolist()
    np.testing.assert_array_equal(r.details["values"], y[planted])
    np.testing.assert_array_equal(r.data, y)  # "report" changes nothing
    g = outliers(y, k=5.0, action="gap")
    assert np.isnan(g.data[planted]).all() and np.count_nonzero(np.isnan(g.data)) == 7
    assert abs(r.estimates["sigma_mad"].value - 1.0) < 4 * r.estimates["sigma_mad"].stderr


def test_outliers_on_phase_maps_spikes_and_steps_to_phase_indices(rng):
    x = np.cumsum(rng.standard_normal(1000))
    x[300] += 40.0          # a spike: differences 299 and 300 outlying, opposite signs
    x[700:] += 50.0         # a step between 699 and 700
    x[0] -= 60.0            # the first sample
    r = outliers(x, data_type="phase", action="gap")
    assert r.indices.tolist() == [0, 300, 700]
    assert r.details["steps"] == [700]
    assert np.isnan(r.data[[0, 300, 700]]).all()


# -- fill, part, average -----------------------------------------------------------------------------------

def test_fill_interpolates_linearly_and_reports_positions():
    v = np.array([np.nan, 1.0, np.nan, np.nan, 4.0, 5.0, np.nan, 9.0, np.nan])
    with pytest.warns(PrepWarning, match="ends of the record"):
        r = fill(v)
    np.testing.assert_array_equal(r.data[1:8], [1.0, 2.0, 3.0, 4.0, 5.0, 7.0, 9.0])
    assert np.isnan(r.data[[0, 8]]).all()
    assert r.indices.tolist() == [2, 3, 6]
    assert r.details["gaps"] == [[0, 1], [2, 4], [6, 7], [8, 9]] == gap_runs(v)
    assert "biased low" in r.notes[0]


def test_part_by_samples_and_by_seconds():
    v = np.arange(10.0)
    assert part(v, start=2, stop=5).data.tolist() == [2.0, 3.0, 4.0]
    assert part(v, start=0.3, stop=0.5, rate=10.0, unit="seconds").data.tolist() == [3.0, 4.0]
    assert part(v, start=0.25, rate=10.0, unit="seconds").data.tolist() == [3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]
    r = part(v, start=8, stop=20)
    assert r.data.tolist() == [8.0, 9.0] and "beyond the end" in r.notes[1]
    assert r.details["range"] == [8, 10]


def test_average_frequency_blocks_gaps_and_partial_block():
    y = np.arange(11.0)
    y[4] = np.nan
    with pytest.warns(PrepWarning, match="left out") as record:
        r = average(y, factor=3, data_type="freq")
    assert record[0].filename == __file__
    np.testing.assert_array_equal(r.data, [1.0, np.nan, 7.0])
    assert r.details["blocks_made_gaps"] == 1
    assert r.details["left_out"] == [9, 11] and r.indices.tolist() == [9, 10]


def test_average_phase_subsamples_and_agrees_with_frequency_blocks(rng):
    y = rng.standard_normal(120)
    x = np.concatenate(([0.0], np.cumsum(y)))  # 121 phase points, τ0 = 1
    xa = average(x, factor=4, data_type="phase").data
    ya = average(y, factor=4, data_type="freq").data
    np.testing.assert_allclose(np.diff(xa) / 4, ya, rtol=1e-12, atol=1e-12)
    assert average(x, factor=1, data_type="phase").data.tolist() == x.tolist()
    x[[1, 2, 3, 5]] = np.nan  # gaps among the skipped phase points lose nothing
    np.testing.assert_array_equal(average(x, factor=4, data_type="phase").data, xa)


# -- purity, gaps, JSON ----------------------------------------------------------------------------------

def _every_step(v: np.ndarray, data_type: str):
    yield frequency_offset(v, data_type=data_type, rate=2.0)
    for m in DRIFT_MODELS[data_type]:
        yield drift(v, data_type=data_type, rate=2.0, model=m)
    yield outliers(v, data_type=data_type, action="gap")
    yield fill(v)
    yield part(v, start=10, stop=200)
    yield average(v, factor=4, data_type=data_type)


@pytest.mark.parametrize("data_type", ["freq", "phase"])
def test_every_step_is_pure_tolerates_gaps_and_records_json_safely(rng, data_type):
    v = with_drift(noise(rng, "wfm", 400, data_type, 0.5, 1e-9), data_type, 0.5, 1e-9)
    v[[0, 17, 18, 19, 250]] = np.nan
    before = v.copy()
    v.flags.writeable = False  # a read-only input is fine
    with warnings.catch_warnings():
        # Expected here: a log or √t curve fitted to a straight drift is poorly determined, a gap at
        # the start cannot be filled, the phase record does not end on a whole block.
        warnings.simplefilter("ignore", PrepWarning)
        results = list(_every_step(v, data_type))
    assert len(results) == 9
    for r in results:
        assert isinstance(r, PrepResult)
        np.testing.assert_array_equal(v, before)
        assert r.data is not v and not np.shares_memory(r.data, v)
        assert not r.data.flags.writeable
        text = json.dumps(r.to_dict(), allow_nan=False)
        assert json.loads(text)["step"] == r.step
        assert repr(r).startswith("PrepResult(")


def test_to_dict_turns_nan_and_inf_into_null():
    y = np.full(20, 1.0)
    y[::2] = 2.0
    y[5] = np.nan
    d = average(y, factor=4, data_type="freq").to_dict()  # a gap block, and no estimates
    assert d["gaps"] == 1 and d["details"]["left_out"] is None
    from sigmatau.prep._result import Estimate
    assert Estimate(float("nan"), float("inf")).to_dict() == {"value": None, "stderr": None, "unit": ""}


# -- bad input: one clear line each ----------------------------------------------------------------------

NAN4 = np.full(4, np.nan)
BAD = [
    (lambda: drift(NAN4, data_type="freq", rate=1.0), DataError, "every one of its .* samples is missing"),
    (lambda: frequency_offset(NAN4, data_type="phase", rate=1.0), DataError, "every one of its .* samples is missing"),
    (lambda: outliers(NAN4), DataError, "every one of its .* samples is missing"),
    (lambda: fill(NAN4), DataError, "every one of its .* samples is missing"),
    (lambda: part(NAN4, start=1), DataError, "every one of its .* samples is missing"),
    (lambda: average(NAN4, factor=2, data_type="freq"), DataError, "every one of its .* samples is missing"),
    (lambda: drift([1.0, 2.0, 3.0], data_type="phase", rate=1.0), DataError,
     "'quadratic' needs at least 4 valid samples, got 3"),
    (lambda: drift(np.arange(9.0), data_type="phase", rate=1.0, model="greenhall"), DataError, "at least 10"),
    (lambda: drift([1.0, np.nan, 2.0, np.nan, 3.0], data_type="freq", rate=1.0, model="log"), DataError,
     "'log' needs at least 5"),
    (lambda: drift(np.arange(9.0), data_type="phase", rate=1.0, model="cubic"), ParameterError, "model='cubic'"),
    (lambda: drift(np.arange(9.0), data_type="phase", rate=1.0, model="linear"), ParameterError,
     "'linear' is a freq model"),
    (lambda: drift(np.arange(9.0), data_type="freq", rate=1.0, noise="pink"), ParameterError, "noise='pink'"),
    (lambda: drift(np.arange(9.0), data_type="freq", rate=0.0), ParameterError, "rate=0.0"),
    (lambda: drift(np.arange(9.0), data_type="frequency", rate=1.0), ParameterError, "data_type='frequency'"),
    (lambda: outliers(np.arange(9.0), k=0), ParameterError, "k=0 must be a positive"),
    (lambda: outliers(np.arange(9.0), k=-1.5), ParameterError, "k=-1.5"),
    (lambda: outliers(np.arange(9.0), action="drop"), ParameterError, "action='drop'"),
    (lambda: outliers(np.ones(9)), DataError, "median absolute deviation"),
    (lambda: average(np.arange(9.0), factor=0, data_type="freq"), ParameterError, "factor=0 must be ≥ 1"),
    (lambda: average(np.arange(9.0), factor=2.5, data_type="freq"), ParameterError, "factor=2.5"),
    (lambda: average(np.arange(3.0), factor=4, data_type="freq"), DataError, "do not fill one block"),
    (lambda: part(np.arange(9.0), start=5, stop=5), ParameterError, "empty or inverted"),
    (lambda: part(np.arange(9.0), start=6, stop=2), ParameterError, "empty or inverted"),
    (lambda: part(np.arange(9.0), start=12), ParameterError, "beyond the record"),
    (lambda: part(np.arange(9.0), start=1.0, unit="seconds"), ParameterError, "rate is required"),
    (lambda: part(np.arange(9.0), start=-1), ParameterError, "start=-1 must not be negative"),
    (lambda: part(np.array([1.0, np.nan, np.nan]), start=1), DataError, "holds no valid sample"),
    (lambda: fill(np.arange(3.0), method="cubic"), ParameterError, "method='cubic'"),
    (lambda: fill(np.array([1.0, np.inf])), DataError, "infinite"),
    (lambda: fill(np.ones((3, 3))), DataError, "1-D"),
    (lambda: fill([]), DataError, "empty"),
]


@pytest.mark.parametrize("call,error,match", BAD)
def test_bad_input_gets_one_clear_line(call, error, match):
    with pytest.raises(error, match=match) as info:
        call()
    assert "\n" not in str(info.value)
