"""Bad input to any statistic gives a one-line DataError/ParameterError naming the problem.

Style guide §5–6: every public function validates first; the message names the
parameter, shows the value and says what is allowed; the errors are SigmaTauError
and ValueError at once.
"""

from __future__ import annotations

import inspect
import re
import warnings

import numpy as np
import pytest

import sigmatau
from sigmatau import DataError, ParameterError, SigmaTauError

# Every public statistic function. Extend this list when a statistic is added;
# test_statistics_list_is_complete fails until then.
STATISTICS = ["adev", "oadev", "mdev", "tdev", "hdev", "ohdev", "mhdev", "ldev", "pdev", "stdev", "ostdev",
              "totdev", "mtotdev", "ttotdev", "htotdev", "mhtotdev", "theo1", "theobr", "theoh", "mtie", "tierms"]
#: Functions with the statistic keywords that take more than one record, with input tests of their own
#: (tests/test_compare.py): the Groslambert covariance of two series and the cornered hat of N ≥ 3.
SEVERAL_RECORDS = {"gcodev", "cornered_hat"}


def _statistic(name):
    # getattr, not a skip: a name listed here must exist.
    return getattr(sigmatau, name)


@pytest.fixture(params=STATISTICS)
def stat(request):
    return _statistic(request.param)


def _random(size=200, seed=0):
    return np.random.default_rng(seed).standard_normal(size)


def _check(exc_info, kind, *patterns):
    exc = exc_info.value
    assert type(exc) is kind
    assert isinstance(exc, ValueError) and isinstance(exc, SigmaTauError)
    msg = str(exc)
    assert "\n" not in msg and "\r" not in msg, msg
    for pattern in patterns:
        assert re.search(pattern, msg, flags=re.IGNORECASE), f"{pattern!r} not in {msg!r}"


def test_statistics_list_is_complete():
    for name in STATISTICS:
        assert name in sigmatau.__all__
        assert callable(_statistic(name))
    # Any public function with the statistic signature must be in STATISTICS, except those that
    # need more than the record (sigmatau.dynamic: a statistic over sliding windows, with its own
    # input tests in tests/test_dynamic.py).
    found = []
    for name in sigmatau.__all__:
        obj = getattr(sigmatau, name)
        if inspect.isfunction(obj):
            params = inspect.signature(obj).parameters
            required = [p for p in params.values() if p.kind is p.KEYWORD_ONLY and p.default is p.empty]
            if {"rate", "data_type", "taus", "m"} <= set(params) and not required and name not in SEVERAL_RECORDS:
                found.append(name)
    assert sorted(found) == sorted(STATISTICS)
    assert "dynamic" in sigmatau.__all__


# --- data ---------------------------------------------------------------------------------

DATA_CASES = [
    # id, data, patterns the message must match (problem, value)
    # NaN marks a missing sample (tests/test_gaps.py); a record of nothing but gaps is refused
    ("all-nan", [np.nan] * 6, [r"every one of its 6 samples is missing", r"NaN"]),
    ("inf", [1.0, 2.0, -np.inf, 3.0, 4.0, 5.0], [r"1 infinite", r"-inf", r"index 2"]),
    ("inf-beside-gap", [1.0, np.nan, np.inf, 3.0, 4.0, 5.0], [r"1 infinite", r"inf", r"index 2"]),
    ("empty-list", [], [r"empty"]),
    ("empty-array", np.empty(0), [r"empty"]),
    ("strings", ["a", "b", "c", "d", "e"], [r"numeric", r"dtype"]),
    ("numeric-strings", ["1", "2", "3", "4", "5"], [r"numeric", r"dtype"]),
    ("object-array", np.array([1.0, 2.0, 3.0, 4.0, 5.0], dtype=object), [r"numeric", r"object"]),
    ("none-inside", [1.0, None, 3.0, 4.0, 5.0], [r"numeric", r"object"]),
    ("ragged", [[1.0, 2.0], [3.0], [4.0, 5.0, 6.0]], [r"numeric"]),
    ("2d", np.ones((20, 3)), [r"1-D", r"\(20, 3\)"]),
    ("2d-wide", np.ones((3, 20)), [r"1-D", r"\(3, 20\)"]),
    ("3d", np.ones((20, 1, 1)), [r"1-D", r"\(20, 1, 1\)"]),
    ("scalar", 5.0, [r"1-D", r"\(\)"]),
    ("complex", _random(50) + 1j, [r"real", r"complex"]),
    ("complex-zero-imag", _random(50).astype(complex), [r"real", r"complex"]),
    ("all-masked", np.ma.masked_array(_random(50), mask=True), [r"every one of its 50 samples is missing"]),
]


@pytest.mark.parametrize("data_type", ["freq", "phase"])
@pytest.mark.parametrize(("data", "patterns"), [c[1:] for c in DATA_CASES], ids=[c[0] for c in DATA_CASES])
def test_bad_data(stat, data, patterns, data_type):
    with pytest.raises(DataError) as exc_info:
        stat(data, data_type=data_type)
    _check(exc_info, DataError, *patterns)


@pytest.mark.parametrize("data_type", ["freq", "phase"])
def test_too_short(stat, data_type):
    # Find the shortest accepted series; every shorter one must be a DataError that says
    # how many samples are needed and how many were given.
    rng = np.random.default_rng(1)
    for size in range(1, 101):
        data = rng.standard_normal(size)
        try:
            result = stat(data, data_type=data_type)
        except DataError as exc:
            msg = str(exc)
            assert "\n" not in msg
            assert "at least" in msg and re.search(rf"\b{size}\b", msg), msg
            continue
        break
    else:
        pytest.fail("no length up to 100 accepted")
    assert size >= 2
    assert len(result) >= 1
    assert np.all(np.isfinite(result.dev)) and np.all(result.n >= 1)


def test_single_sample_rejected(stat):
    with pytest.raises(DataError) as exc_info:
        stat([1.0])
    _check(exc_info, DataError, r"at least", r"\b1\b")


def test_column_vector_accepted(stat):
    y = _random()
    expected = stat(y)
    for shaped in (y[:, None], y[:, None].tolist()):
        result = stat(shaped)
        np.testing.assert_array_equal(result.m, expected.m)
        np.testing.assert_array_equal(result.dev, expected.dev)


def test_row_vector_accepted(stat):
    # A (1, N) row is unambiguous too and is read as the N samples.
    y = _random()
    np.testing.assert_array_equal(stat(y[None, :]).dev, stat(y).dev)


@pytest.mark.parametrize("data_type", ["freq", "phase"])
@pytest.mark.parametrize("value", [0.0, 3.7, -1e-9, 1e12])
def test_constant_data_gives_zeros(stat, data_type, value):
    # Constant phase and constant frequency (a pure phase ramp) have no instability.
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        result = stat(np.full(300, value), data_type=data_type, taus="all")
    assert len(result) > 0
    if stat.__name__ in ("mtie", "tierms") and data_type == "freq":
        # Time-error statistics see the phase ramp of a constant frequency: |c|·m·τ0.
        np.testing.assert_allclose(result.dev, abs(value) * result.m, rtol=1e-12)
        return
    np.testing.assert_array_equal(result.dev, 0.0)
    np.testing.assert_array_equal(result.var, 0.0)


@pytest.mark.parametrize("dtype", [np.float32, np.float16])
def test_low_precision_floats_computed_in_float64(stat, dtype):
    y = _random().astype(dtype)
    result = stat(y, taus="all")
    expected = stat(y.astype(np.float64), taus="all")
    for field in ("taus", "var", "dev"):
        assert getattr(result, field).dtype == np.float64
    np.testing.assert_array_equal(result.dev, expected.dev)


@pytest.mark.parametrize("dtype", [np.int8, np.uint8, np.int16, np.int32, np.int64, np.uint64])
def test_integers_computed_in_float64(stat, dtype):
    # Values near the type's limits: any difference taken in the integer type would
    # overflow or wrap around.
    info = np.iinfo(dtype)
    values = np.array([info.max, info.min, info.max, info.min + 1, info.max - 3, info.min] * 20, dtype=dtype)
    result = stat(values, taus="all")
    expected = stat(values.astype(np.float64), taus="all")
    assert result.dev.dtype == np.float64
    np.testing.assert_array_equal(result.dev, expected.dev)


@pytest.mark.parametrize("data_type", ["freq", "phase"])
def test_input_not_modified(stat, data_type):
    y = _random()
    before = y.copy()
    stat(y, data_type=data_type, taus="all")
    np.testing.assert_array_equal(y, before)


def test_plain_int_list(stat):
    y = [int(v) for v in np.random.default_rng(5).integers(600, 900, 120)]  # TheoBR needs 89
    np.testing.assert_array_equal(stat(y, m=2).dev, stat([float(v) for v in y], m=2).dev)


def test_bool_data_read_as_zero_one(stat):
    # Decision: booleans are numbers 0/1 for numpy, and a 0/1 stream is a legitimate
    # signal, so a bool array is accepted and computed as float64 0.0/1.0.
    bits = np.random.default_rng(3).random(200) > 0.5
    result = stat(bits)
    np.testing.assert_array_equal(result.dev, stat(bits.astype(np.float64)).dev)


# --- rate, data_type ----------------------------------------------------------------------

RATE_CASES = [
    ("zero", 0, r"rate=0\b"),
    ("zero-float", 0.0, r"rate=0\.0"),
    ("negative", -1.0, r"rate=-1\.0"),
    ("nan", float("nan"), r"rate=nan"),
    ("inf", float("inf"), r"rate=inf"),
    ("minus-inf", -float("inf"), r"rate=-inf"),
    ("string", "fast", r"rate='fast'"),
    ("numeric-string", "1", r"rate='1'"),
    ("none", None, r"rate=None"),
    ("list", [1.0], r"rate=\[1\.0\]"),
    # Beyond 1e-24 … 1e24 Hz, τ² or 1/τ² over the grid could leave float64 (issue 11).
    ("huge", 1e100, r"rate=1e\+100 .*1e-24 … 1e\+24 Hz"),
    ("tiny", 1e-200, r"rate=1e-200 .*1e-24 … 1e\+24 Hz"),
]


@pytest.mark.parametrize(("rate", "pattern"), [c[1:] for c in RATE_CASES], ids=[c[0] for c in RATE_CASES])
def test_bad_rate(stat, rate, pattern):
    with pytest.raises(ParameterError) as exc_info:
        stat(_random(), rate=rate)
    _check(exc_info, ParameterError, pattern, r"positive")


def test_bool_rate_rejected(stat):
    # True is not a sample rate, even though float(True) == 1.0 (m=True is rejected too).
    with pytest.raises(ParameterError) as exc_info:
        stat(_random(), rate=True)
    _check(exc_info, ParameterError, r"rate=True")


def test_numpy_scalar_rate_accepted(stat):
    y = _random()
    expected = stat(y, rate=2.0)
    for rate in (np.float64(2.0), np.int64(2), np.float32(2.0), 2):
        result = stat(y, rate=rate)
        np.testing.assert_array_equal(result.taus, expected.taus)
        np.testing.assert_array_equal(result.dev, expected.dev)


@pytest.mark.parametrize("data_type", ["frequency", "Phase", "", None, 1, ["freq"]])
def test_bad_data_type(stat, data_type):
    with pytest.raises(ParameterError) as exc_info:
        stat(_random(), data_type=data_type)
    _check(exc_info, ParameterError, re.escape(f"data_type={data_type!r}"), r"'freq'", r"'phase'")


# --- taus and m ---------------------------------------------------------------------------

TAUS_CASES = [
    ("unknown-keyword", "octaves", r"taus='octaves'"),
    ("keyword-case", "Octave", r"taus='Octave'"),
    ("negative", [1.0, -2.0], r"taus=.*-2\.0"),
    ("zero", [0.0, 2.0], r"taus=.*\b0\.0"),
    ("nan", [np.nan], r"taus=.*nan"),
    ("inf", [1.0, np.inf], r"taus=.*inf"),
    ("empty", [], r"taus=\[\]"),
    ("strings", ["a"], r"taus=\['a'\]"),
    ("2d", [[1.0, 2.0]], r"taus=\[\[1\.0, 2\.0\]\]"),
]


@pytest.mark.parametrize(("taus", "pattern"), [c[1:] for c in TAUS_CASES], ids=[c[0] for c in TAUS_CASES])
def test_bad_taus(stat, taus, pattern):
    with pytest.raises(ParameterError) as exc_info:
        stat(_random(), taus=taus)
    _check(exc_info, ParameterError, pattern, r"octave")


M_CASES = [
    ("zero", 0, r"m=\[?0\b"),
    ("negative", -1, r"m=\[?-1\b"),
    ("zero-in-list", [2, 0, 4], r"m=\[?.*\b0\b"),
    ("non-integer", 2.5, r"m=2\.5"),
    ("non-integer-in-list", [1, 2.5], r"m=\[1, 2\.5\]"),
    ("nan", np.nan, r"m=nan"),
    ("string", "2", r"m='2'"),
    ("bool", True, r"m=True"),
    ("empty", [], r"m=\[\]"),
    ("2d", [[1, 2]], r"m=\[\[1, 2\]\]"),
]


@pytest.mark.parametrize(("m", "pattern"), [c[1:] for c in M_CASES], ids=[c[0] for c in M_CASES])
def test_bad_m(stat, m, pattern):
    with pytest.raises(ParameterError) as exc_info:
        stat(_random(), m=m)
    _check(exc_info, ParameterError, pattern)


def test_m_above_mathematical_limit(stat):
    y = _random(200)
    with pytest.raises(ParameterError) as exc_info:
        stat(y, m=[2, 2000])
    _check(exc_info, ParameterError, r"m=\[?2000\b", r"allowed|range")


def test_whole_float_m_accepted(stat):
    y = _random()
    np.testing.assert_array_equal(stat(y, m=[2.0, 4.0]).dev, stat(y, m=[2, 4]).dev)


# taus="octave" is the default, so m given with it is taken as overriding the default grid
# (documented in sigmatau.core.taus); every other taus together with m is an error.
@pytest.mark.parametrize("taus", ["decade", "all", "log", [1.0, 2.0], 4.0])
def test_taus_and_m_together(stat, taus):
    with pytest.raises(ParameterError) as exc_info:
        stat(_random(), taus=taus, m=[1, 2])
    _check(exc_info, ParameterError, r"taus", r"\bm\b", r"both|either")


def test_bad_points_per_decade(stat):
    with pytest.raises(ParameterError) as exc_info:
        stat(_random(), taus="log", points_per_decade=0)
    _check(exc_info, ParameterError, r"points_per_decade=0")
