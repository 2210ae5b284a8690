"""Invariances every Allan/Hadamard-family estimator must keep (property tests).

For the eight statistics ``stdev, ostdev, adev, oadev, mdev, tdev, hdev, ohdev``:

* scaling the data by c scales the deviation by |c|;
* a constant added to frequency data changes nothing;
* frequency data y and its phase ``cumsum(y)/rate`` give the same result;
* a linear trend added to phase data (a frequency offset) changes nothing;
* constant data gives exact zeros, not NaN;
* float32 and integer input give the result of the same values as float64.

The tolerances are round-off bounds: a relative 1e-9 plus an absolute term
proportional to the size of the numbers the estimator handles (the spread of
the data, the offset, the phase excursion) times a generous multiple of the
float64 epsilon. A wrong index or normalisation is off by far more.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

import sigmatau

from _noise import NOISES

NAMES = ("stdev", "ostdev", "adev", "oadev", "mdev", "tdev", "hdev", "ohdev")
MIN_FREQ = {name: 2 for name in NAMES} | {"hdev": 3, "ohdev": 3}  # fewest frequency samples

SETTINGS = settings(
    max_examples=15,
    deadline=None,
    database=None,
    suppress_health_check=[HealthCheck.too_slow],
)

RATES = st.sampled_from([1.0, 0.1, 3.0, 104.0])


@st.composite
def freq_records(draw: st.DrawFn, min_size: int = 3) -> np.ndarray:
    """Frequency data: seeded noise of a random type and scale, or raw values on
    a coarse grid (steps, spikes, repeated values; no subnormals)."""
    n = draw(st.integers(min_size, 300))
    if draw(st.booleans()):
        noise = draw(st.sampled_from(sorted(NOISES)))
        seed = draw(st.integers(0, 2**32 - 1))
        scale = draw(st.sampled_from([1e-9, 1e-3, 1.0, 1e4]))
        return scale * NOISES[noise](n, np.random.default_rng(seed))
    raw = draw(arrays(np.int64, n, elements=st.integers(-1000, 1000)))
    return raw / 8.0


def spread(y: np.ndarray) -> float:
    """Size of the fluctuations of frequency data (0 for constant data)."""
    return float(np.max(np.abs(y - y.mean())))


def atol_for(result: sigmatau.StabilityResult, size: float) -> np.ndarray:
    """Absolute round-off allowance for a deviation whose inputs are of ``size``
    (frequency units); TDEV carries an extra factor τ."""
    unit = result.taus if result.statistic == "tdev" else np.ones(len(result))
    return 1e-11 * result.n_points * size * unit


def assert_same(a: sigmatau.StabilityResult, b: sigmatau.StabilityResult, atol: np.ndarray) -> None:
    np.testing.assert_array_equal(a.m, b.m)
    np.testing.assert_allclose(a.taus, b.taus, rtol=1e-15)
    assert np.all(np.isfinite(a.dev)) and np.all(np.isfinite(b.dev))
    assert np.all(np.abs(a.dev - b.dev) <= 1e-9 * np.abs(b.dev) + atol), (a.dev, b.dev, atol)


@pytest.mark.parametrize("name", NAMES)
@SETTINGS
@given(
    data=st.data(),
    c=st.floats(1e-6, 1e6) | st.floats(-1e6, -1e-6),
    rate=RATES,
)
def test_scaling(name: str, data: st.DataObject, c: float, rate: float) -> None:
    y = data.draw(freq_records(MIN_FREQ[name]))
    func = getattr(sigmatau, name)
    base = func(y, rate=rate)
    scaled = func(c * y, rate=rate)
    expected = abs(c) * base.dev
    tol = 1e-9 * expected + abs(c) * atol_for(base, float(np.max(np.abs(y))))
    np.testing.assert_array_equal(scaled.m, base.m)
    assert np.all(np.abs(scaled.dev - expected) <= tol), (scaled.dev, expected)


@pytest.mark.parametrize("name", NAMES)
@SETTINGS
@given(data=st.data(), offset=st.floats(-1e3, 1e3), rate=RATES)
def test_frequency_offset(name: str, data: st.DataObject, offset: float, rate: float) -> None:
    y = data.draw(freq_records(MIN_FREQ[name]))
    func = getattr(sigmatau, name)
    c = offset * max(spread(y), 1.0)
    base = func(y, rate=rate)
    shifted = func(y + c, rate=rate)
    assert_same(shifted, base, atol_for(base, spread(y) + abs(c) + float(np.max(np.abs(y)))))


@pytest.mark.parametrize("name", NAMES)
@SETTINGS
@given(data=st.data(), rate=RATES)
def test_phase_frequency_round_trip(name: str, data: st.DataObject, rate: float) -> None:
    y = data.draw(freq_records(MIN_FREQ[name]))
    func = getattr(sigmatau, name)
    from_freq = func(y, rate=rate, data_type="freq")
    from_phase = func(sigmatau.frequency_to_phase(y, rate=rate), rate=rate, data_type="phase")
    assert from_freq.n_points == from_phase.n_points == y.size + 1
    size = float(np.max(np.abs(y)))  # the phase keeps the mean frequency
    assert_same(from_phase, from_freq, atol_for(from_freq, size))


@pytest.mark.parametrize("name", NAMES)
@SETTINGS
@given(
    data=st.data(),
    start=st.floats(-1e3, 1e3),
    slope=st.floats(-1e3, 1e3),
    rate=RATES,
)
def test_linear_phase_trend(name: str, data: st.DataObject, start: float, slope: float, rate: float) -> None:
    y = data.draw(freq_records(MIN_FREQ[name]))
    func = getattr(sigmatau, name)
    x = sigmatau.frequency_to_phase(y, rate=rate)
    scale = spread(y) or 1.0
    a, b = start * scale / rate, slope * scale  # phase offset, frequency offset
    x_trend = x + a + b * np.arange(x.size) / rate
    base = func(x, rate=rate, data_type="phase")
    trended = func(x_trend, rate=rate, data_type="phase")
    # Phase values of size P carry round-off ~eps·P, i.e. P·rate in frequency units.
    phase_size = float(np.max(np.abs(x))) + abs(a) + abs(b) * x.size / rate
    assert_same(trended, base, atol_for(base, phase_size * rate))


@pytest.mark.parametrize("name", NAMES)
@SETTINGS
@given(
    value=st.floats(-1e9, 1e9, allow_subnormal=False),
    n=st.integers(0, 200),
    rate=RATES,
    data_type=st.sampled_from(["freq", "phase"]),
)
def test_constant_data_gives_zero(name: str, value: float, n: int, rate: float, data_type: str) -> None:
    """Zero to round-off, never NaN or negative.

    Exact zeros are not promised: the mean of n copies of a value can differ
    from it in the last bit, and that residue, integrated, leaves a deviation
    of order eps²·|value|.
    """
    func = getattr(sigmatau, name)
    size = MIN_FREQ[name] + (data_type == "phase") + n
    result = func(np.full(size, value), rate=rate, data_type=data_type)
    assert len(result) > 0
    assert np.all(np.isfinite(result.var)) and np.all(result.var >= 0.0)
    unit = result.taus if name == "tdev" else 1.0
    if data_type == "phase":
        unit = unit * rate
    assert np.all(result.dev <= 1e-20 * abs(value) * unit), result.dev
    if value == 0.0 or data_type == "phase":
        np.testing.assert_array_equal(result.dev, 0.0)


@pytest.mark.slow
@pytest.mark.parametrize("name", NAMES)
@SETTINGS
@given(data=st.data(), rate=RATES, data_type=st.sampled_from(["freq", "phase"]))
def test_float32_and_integer_input(name: str, data: st.DataObject, rate: float, data_type: str) -> None:
    y = data.draw(freq_records(MIN_FREQ[name] + 1))
    func = getattr(sigmatau, name)
    single = y.astype(np.float32)
    np.testing.assert_array_equal(
        func(single, rate=rate, data_type=data_type).dev,
        func(single.astype(np.float64), rate=rate, data_type=data_type).dev,
    )
    integers = 3000.0 + np.round((y - y.mean()) / (spread(y) or 1.0) * 1000.0)  # 2000 … 4000
    for dtype in (np.int64, np.int16, np.uint16):
        values = integers.astype(dtype)
        expected = func(values.astype(np.float64), rate=rate, data_type=data_type).dev
        np.testing.assert_array_equal(func(values, rate=rate, data_type=data_type).dev, expected)
    as_list = integers.astype(np.int64).tolist()
    np.testing.assert_array_equal(
        func(as_list, rate=rate, data_type=data_type).dev,
        func(np.asarray(as_list, dtype=np.float64), rate=rate, data_type=data_type).dev,
    )
