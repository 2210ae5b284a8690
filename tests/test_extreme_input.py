"""Extreme, integer and masked input at the numeric front door (issue 11, defects 6–8).

Every statistic is homogeneous of degree two in the data, var(c·x) = c²·var(x), and the driver
uses that: the kernel runs on the data scaled by an exact power of two. So data at any scale
whose variance float64 can hold give the answer of the same data at scale 1 (up to the rounding
of c·x itself, ~1e-16); data whose variance float64 cannot hold (|dev| beyond ~1e±154) are a
one-line DataError, never inf, NaN or a silent 0. Rates are limited to RATE_RANGE, where τ, τ²
and 1/τ² over any grid stay representable.

The reference is always the same data at scale 1 (or without the integer offset): a property,
not a number taken from our own output.
"""

from __future__ import annotations

import re
import time
import warnings

import numpy as np
import pytest

import sigmatau
from sigmatau import DataError, ParameterError, SigmaTauError
from sigmatau.core.validate import RATE_RANGE
from sigmatau.cli import main

from helpers import assert_one_line_error

STATISTICS = ["adev", "oadev", "mdev", "tdev", "hdev", "ohdev", "mhdev", "ldev", "pdev", "totdev", "mtotdev",
              "ttotdev", "htotdev", "mhtotdev", "theo1", "theobr", "theoh", "mtie", "tierms", "stdev", "ostdev"]
NO_INTERVAL = {"mtie", "tierms"}
RTOL = 1e-12


@pytest.fixture(scope="module")
def series():
    # 128 points: TheoBR/TheoH need 90. Fixed seed: the property holds for any data.
    return np.random.default_rng(20261124).standard_normal(128)


def _compare(result, reference, scale):
    """``result`` is ``reference`` computed on data × scale."""
    np.testing.assert_array_equal(result.m, reference.m)
    np.testing.assert_allclose(result.dev / scale, reference.dev, rtol=RTOL, atol=0.0)
    np.testing.assert_allclose(result.var / scale**2 if np.isfinite(scale**2) else
                               (result.dev / scale) ** 2, reference.var, rtol=3 * RTOL, atol=0.0)
    assert np.all(np.isfinite(result.var)) and np.all(np.isfinite(result.dev))
    for name in ("alpha", "edf"):
        a, b = getattr(result, name), getattr(reference, name)
        if b is None:
            assert a is None
        else:
            np.testing.assert_array_equal(a, b)
    for name in ("ci_low", "ci_high"):
        a, b = getattr(result, name), getattr(reference, name)
        if b is None:
            assert a is None
        else:
            np.testing.assert_allclose(a / scale, b, rtol=RTOL, atol=0.0)


def _quiet(f, *args, **kwargs):
    # Short records make some statistics warn about their range; irrelevant here.
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", sigmatau.SigmaTauWarning)
        return f(*args, **kwargs)


# --- data scale ------------------------------------------------------------------------------


@pytest.mark.parametrize("ci", [None, "chi2"])
@pytest.mark.parametrize("data_type", ["freq", "phase"])
@pytest.mark.parametrize("name", STATISTICS)
def test_representable_scales_give_the_unit_scale_answer(series, name, data_type, ci):
    # 1e±150: deviation within float64 but squares of the data near its limits (mtotdev gave
    # NaN at 1e150 before the scaling; TheoBR/TheoH refused beyond 1e±135 before they used
    # core.driver.prepare_scaled).
    f = getattr(sigmatau, name)
    reference = _quiet(f, series, data_type=data_type, ci=ci)
    for scale in (1e-150, 1e-100, 1e100, 1e150):
        _compare(_quiet(f, series * scale, data_type=data_type, ci=ci), reference, scale)


@pytest.mark.parametrize("ci", [None, "chi2"])
@pytest.mark.parametrize("data_type", ["freq", "phase"])
@pytest.mark.parametrize("name", STATISTICS)
@pytest.mark.parametrize("scale", [1e-300, 1e-170, 1e170, 1e300])
def test_unrepresentable_variance_is_a_one_line_data_error(series, name, data_type, ci, scale):
    # The variance of these data is 1e±340 or 1e±600: no float64 holds it. Before: inf,
    # a silent 0 (1e-170), NaN (mtotdev) or a builtin OverflowError (mtie).
    f = getattr(sigmatau, name)
    with pytest.raises(DataError) as exc_info:
        _quiet(f, series * scale, data_type=data_type, ci=ci)
    msg = str(exc_info.value)
    assert "\n" not in msg and msg.startswith(name), msg
    assert re.search(r"outside float64's range|outside the range this statistic computes", msg), msg


def test_theobr_kappa_is_scale_free(series):
    # κ is a ratio of variances; it was refused beyond a phase of 2**±450 (≈ 1e±135).
    reference = sigmatau.theobr_kappa(series)
    for scale in (1e-150, 1e150):
        k = sigmatau.theobr_kappa(series * scale)
        assert k.n == reference.n
        np.testing.assert_allclose(k.kappa, reference.kappa, rtol=RTOL, atol=0.0)


def test_finish_refuses_an_overflowed_variance():
    # A kernel outside the driver (stats/theo.py) that overflowed must not reach the user as inf.
    from sigmatau.stats.engine import finish
    from sigmatau.core.result import StabilityResult

    r = StabilityResult(statistic="theobr", taus=np.array([1.5]), m=np.array([2]), var=np.array([np.inf]),
                        dev=np.array([np.inf]), n=np.array([10]), rate=1.0, data_type="freq", n_points=129)
    with pytest.raises(DataError, match=r"theobr: .*outside float64's range"):
        finish(r, np.ones(128), "freq")


# --- rate ------------------------------------------------------------------------------------


@pytest.mark.parametrize("rate", [1e100, 1e200, 1e308, 1e-200, 1e-308, 5e-324])
def test_rate_outside_range_is_a_parameter_error(series, rate):
    for name in STATISTICS:
        with pytest.raises(ParameterError) as exc_info:
            getattr(sigmatau, name)(series, rate=rate)
        msg = str(exc_info.value)
        assert "\n" not in msg
        assert f"rate={rate!r}" in msg and "1e-24" in msg and "1e+24" in msg, msg


@pytest.mark.parametrize("data_type", ["freq", "phase"])
def test_rate_at_the_range_ends_scales_exactly(series, data_type):
    # With m fixed, τ = m/rate; a deviation of frequency data does not depend on the rate,
    # of phase data it is proportional to it; TDEV/TTOT/LDEV/MTIE/TIE rms (phase units) are
    # proportional to 1/rate for frequency data and independent of it for phase data.
    phase_units = {"tdev", "ttotdev", "ldev", "mtie", "tierms"}
    for name in STATISTICS:
        f = getattr(sigmatau, name)
        ref = _quiet(f, series, data_type=data_type, rate=1.0, ci=None)
        for rate in RATE_RANGE:
            r = _quiet(f, series, data_type=data_type, rate=rate, ci=None)
            power = (-1 if name in phase_units else 0) + (1 if data_type == "phase" else 0)
            np.testing.assert_allclose(r.taus * rate, ref.taus, rtol=RTOL)
            np.testing.assert_allclose(r.dev, ref.dev * rate**power, rtol=RTOL, atol=0.0, err_msg=name)


# --- integers ----------------------------------------------------------------------------------


@pytest.mark.parametrize("name", STATISTICS)
def test_int64_unix_ns_phase_keeps_its_noise(name, rng):
    # Unix-epoch nanoseconds: 1.7e18 is beyond 2**53, where float64 steps by 256 ns. Before:
    # every value rounded on its own, OADEV 0 for noise of a few ns.
    noise = rng.integers(-5, 6, 200)
    offset = 1_700_000_000_000_000_000
    f = getattr(sigmatau, name)
    got = _quiet(f, np.int64(offset) + noise.astype(np.int64), data_type="phase", rate=1e9)
    expected = _quiet(f, noise.astype(np.float64), data_type="phase", rate=1e9)
    assert np.all(expected.dev > 0)
    np.testing.assert_allclose(got.dev, expected.dev, rtol=RTOL, atol=0.0)
    np.testing.assert_array_equal(got.alpha, expected.alpha)


def test_uint64_and_full_range_int64_phase_are_exact_differences(rng):
    # Any integer range, even one spanning all of int64 or uint64: each difference from the
    # first value is correctly rounded once (Python integers give the exact difference).
    for values in (np.uint64(2**63) + rng.integers(0, 1000, 200).astype(np.uint64),
                   np.where(rng.random(200) > 0.5, np.iinfo(np.int64).max, np.iinfo(np.int64).min + 7)):
        exact = np.array([float(int(v) - int(values[0])) for v in values])
        np.testing.assert_array_equal(sigmatau.oadev(values, data_type="phase", taus="all").dev,
                                      sigmatau.oadev(exact, data_type="phase", taus="all").dev)


def test_int64_frequency_offset_kept_where_it_matters(rng):
    # MTIE of frequency data sees the offset (integrated phase ramp): not removed there.
    y = np.int64(2**60) + rng.integers(-3, 4, 100)
    r = sigmatau.mtie(y, m=[1, 10])
    np.testing.assert_allclose(r.dev, [2.0**60, 10 * 2.0**60], rtol=1e-12)
    # OADEV ignores it, and now keeps the integer noise under it.
    np.testing.assert_allclose(sigmatau.oadev(y, m=[1, 2]).dev,
                               sigmatau.oadev((y - y[0]).astype(float), m=[1, 2]).dev, rtol=RTOL)


# --- masked arrays -------------------------------------------------------------------------------


@pytest.mark.parametrize("name", STATISTICS)
def test_masked_values_are_gaps(series, name):
    # A masked value is a missing sample: never read (the 1e30 behind the mask leaves no trace),
    # exactly as the same record with NaN there.
    data = series.copy()
    data[7] = 1e30
    masked = np.ma.masked_array(data, mask=np.arange(data.size) == 7)
    with_nan = series.copy()
    with_nan[7] = np.nan
    f = getattr(sigmatau, name)
    got, want = _quiet(f, masked), _quiet(f, with_nan)
    np.testing.assert_array_equal(got.dev, want.dev)
    assert got.n_missing == 1 and np.all(got.dev < 1e10)


@pytest.mark.parametrize("name", STATISTICS)
def test_masked_array_without_masked_values_is_accepted(series, name):
    f = getattr(sigmatau, name)
    for masked in (np.ma.masked_array(series), np.ma.masked_array(series, mask=np.zeros(series.size, bool))):
        np.testing.assert_array_equal(_quiet(f, masked).dev, _quiet(f, series).dev)


# --- anything else: only SigmaTauError or a correct result ---------------------------------------


def _bad_inputs(y):
    big = np.iinfo(np.int64)
    return {
        "nan": np.r_[y[:5], np.nan, y[6:]], "inf": np.r_[y[:5], -np.inf, y[6:]], "empty": np.empty(0),
        "one": np.array([1.0]), "constant": np.full(y.size, 3.0), "huge": y * 1e300, "tiny": y * 1e-300,
        "float-max": np.r_[np.full(64, 1.7e308), np.full(64, -1.7e308)], "subnormal": y * 5e-324,
        "int8": (y * 50).astype(np.int8), "uint64": np.arange(y.size, dtype=np.uint64) * np.uint64(2**57),
        "int64-span": np.where(y > 0, big.max, big.min), "bool": y > 0, "complex": y + 1j,
        "object": y.astype(object), "str": y.astype(str), "2d": np.ones((8, 16)), "list-none": [1.0, None] * 64,
        "masked": np.ma.masked_array(y, mask=y > 2),
    }


@pytest.mark.parametrize("data_type", ["freq", "phase"])
@pytest.mark.parametrize("name", STATISTICS)
def test_bad_input_sweep(series, name, data_type):
    f = getattr(sigmatau, name)
    for case, data in _bad_inputs(series).items():
        for ci in (None, "chi2"):
            try:
                r = _quiet(f, data, data_type=data_type, ci=ci)
            except SigmaTauError as exc:
                assert isinstance(exc, ValueError) and "\n" not in str(exc), (case, str(exc))
                continue
            assert np.all(np.isfinite(r.var)) and np.all(r.var >= 0), (case, r.var)
            np.testing.assert_array_equal(r.dev, np.sqrt(r.var))


def test_hypothesis_arrays_only_sigmatau_errors():
    hypothesis = pytest.importorskip("hypothesis")
    from hypothesis import given, strategies as st
    from hypothesis.extra import numpy as hnp

    floats = st.floats(allow_nan=True, allow_infinity=True, allow_subnormal=True)
    arrays = hnp.arrays(np.float64, st.integers(0, 40), elements=floats)

    @hypothesis.settings(max_examples=60)
    @given(arrays, st.sampled_from(STATISTICS), st.sampled_from(["freq", "phase"]))
    def check(data, name, data_type):
        try:
            r = _quiet(getattr(sigmatau, name), data, data_type=data_type, m=[1])
        except SigmaTauError:
            return
        assert np.all(np.isfinite(r.var)) and np.all(r.var >= 0)

    check()


# --- command line ----------------------------------------------------------------------------------


@pytest.fixture
def csv_at(tmp_path):
    def write(scale, n=600):
        y = np.random.default_rng(11).standard_normal(n) * scale
        path = tmp_path / f"log_{scale:g}.csv"
        path.write_text("gyro_x\n" + "".join(f"{float(v)!r}\n" for v in y))
        return path, y
    return write


def _cli(argv, capsys):
    t0 = time.perf_counter()
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    assert time.perf_counter() - t0 < 30.0
    return code, out, err


@pytest.mark.parametrize("command", ["stats", "analyze"])
@pytest.mark.parametrize("scale", [1e200, 1e-170])
def test_cli_unrepresentable_samples_one_line(csv_at, tmp_path, capsys, command, scale):
    path, _ = csv_at(scale)
    extra = ["--out", tmp_path / "out", "--no-figures"] if command == "analyze" else []
    code, _, err = _cli([command, path, "--rate", "100", *extra], capsys)
    assert_one_line_error((code, err), code=1, match=r"outside float64's range")
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("command", ["stats", "analyze"])
@pytest.mark.parametrize("rate", ["1e100", "1e-200", "1e308"])
def test_cli_extreme_rate_one_line(csv_at, tmp_path, capsys, command, rate):
    path, _ = csv_at(1.0)
    extra = ["--out", tmp_path / "out", "--no-figures"] if command == "analyze" else []
    code, _, err = _cli([command, path, "--rate", rate, *extra], capsys)
    assert_one_line_error((code, err), code=2, match=r"rate=.*1e-24 … 1e\+24 Hz")


def test_cli_stats_at_1e140_is_the_scaled_answer(csv_at, capsys):
    # Rows "AF Tau # Alpha MinSigma Sigma MaxSigma", printed to 5 significant digits.
    path, y = csv_at(1e140)
    code, out, err = _cli(["stats", path, "--rate", "100", "--stat", "oadev"], capsys)
    assert code == 0, err
    expected = sigmatau.oadev(y / 1e140, rate=100.0)
    rows = [ln.split() for ln in out.splitlines() if re.match(r"\s*\d+\s+\d\.\d+e[-+]\d+\s", ln)]
    assert [int(r[0]) for r in rows] == expected.m.tolist()
    for row, low, dev, high in zip(rows, expected.ci_low, expected.dev, expected.ci_high):
        got = np.array([float(v) for v in row[4:7]]) / 1e140
        np.testing.assert_allclose(got, [low, dev, high], rtol=5e-5)


def test_cli_analyze_at_1e_minus_100_completes(csv_at, tmp_path, capsys):
    # Before: exit 3 (LinAlgError from the IMU fit). The statistics are the scale-1 answer
    # × 1e-100; the model is either fitted or skipped with the reason (never a crash).
    import json

    path, y = csv_at(1e-100)
    out = tmp_path / "out"
    code, _, err = _cli(["analyze", path, "--rate", "100", "--no-figures", "--out", out], capsys)
    assert code == 0, err
    channel = json.loads((out / "results.json").read_text())["channels"][0]
    got = channel["statistics"]["oadev"]
    expected = sigmatau.oadev(y * 1e100, rate=100.0, confidence=got["confidence"])
    np.testing.assert_allclose(np.array(got["dev"]) * 1e100, expected.dev, rtol=1e-12)
    np.testing.assert_allclose(np.array(got["ci_high"]) * 1e100, expected.ci_high, rtol=1e-12)
    # Deviations near 1e-103 rad/s are outside the range the IMU fit carries: skipped, saying why.
    assert channel["model"] is None and "fitted for deviations within" in channel["model_note"]


def test_nothing_computed_names_each_reason_once(capsys, csv_at):
    path, _ = csv_at(1e300)
    code, _, err = _cli(["stats", path, "--rate", "100", "--stat", "oadev,mdev,adev"], capsys)
    line = assert_one_line_error((code, err), code=1, match=r"no statistic could be computed for channel 'gyro_x'")
    assert "oadev, mdev, adev: the variance" in line and line.count("outside float64's range") == 1


@pytest.mark.parametrize(("func", "data", "rate", "index"), [
    ("frequency_to_phase", np.full(10, 1e308), 1.0, 2),            # the running sum overflows
    ("frequency_to_phase", np.array([1e-300, 2e-300]), 1e20, 1),   # 1e-320: subnormal, digits lost
    ("phase_to_frequency", np.array([1.7e308, -1.7e308, 1.0]), 1.0, 0),
    ("phase_to_frequency", np.array([0.0, 1e-300, 3e-300]), 1e-20, 0),
])
def test_conversions_refuse_unrepresentable_output(func, data, rate, index):
    # Before: inf or a subnormal with a RuntimeWarning (an error under this test house).
    with pytest.raises(DataError) as exc_info:
        getattr(sigmatau, func)(data, rate=rate)
    msg = str(exc_info.value)
    assert "\n" not in msg and msg.startswith(func) and f"index {index}" in msg, msg


def test_conversions_keep_negligible_subnormals():
    # A value 1e-300 below the largest one is lost at double precision anyway: not an error.
    x = sigmatau.frequency_to_phase([1e-300, 1.0, 2.0], rate=1e20)
    np.testing.assert_allclose(x[2:], [1e-20, 3e-20], rtol=1e-15)  # τ0 = 1/rate is rounded
    np.testing.assert_array_equal(sigmatau.phase_to_frequency([0.0, 1.0, 3.0], rate=2.0), [2.0, 4.0])


def test_prepare_scaled_gives_the_run_answer(series):
    # The helper for kernels called outside run(): kernel on the scaled phase, then unscale.
    from sigmatau.core.driver import prepare, prepare_scaled
    from sigmatau.core.validate import unscale_variance
    from sigmatau.stats.theo import THEO1

    ms = np.array([2, 4, 16])
    for scale in (1e-150, 1.0, 1e150):
        for data_type in ("freq", "phase"):
            p = prepare_scaled(THEO1, series * scale, 100.0, data_type)
            if scale == 1.0:  # the same phase as prepare(), up to the exact power of two
                np.testing.assert_array_equal(np.ldexp(p.phase, p.exponent),
                                              prepare(THEO1, series, 100.0, data_type)[0])
            var, _ = THEO1.compute(p.phase, ms, 1.0 / p.rate)
            expected = sigmatau.theo1(series * scale, rate=100.0, data_type=data_type, m=ms, ci=None).var
            np.testing.assert_allclose(unscale_variance(var, p.exponent, "theo1"), expected, rtol=RTOL, atol=0.0)


@pytest.mark.parametrize("name", ["oadev", "totdev"])
def test_chunked_overflow_is_a_data_error(series, name):
    # sigmatau.chunked streams unscaled data; an overflowed variance was returned as inf.
    from sigmatau import chunked

    with pytest.raises(DataError, match=rf"^{name}: .*outside float64's range"):
        _quiet(getattr(sigmatau, name), chunked.from_array(series * 1e170), ci=None)
