"""Streaming statistics (sigmatau.stream.Stream) against the batch functions.

The reference is the public batch function on every sample given so far. Rows, term counts,
noise types (α), EDF and the reasons of each row must be identical; α̂ within 1e-9 (it agrees
to about 1e-12: the lag-1 sums are accumulated in another order); the variance within 1e-12
relative. Where the batch's own round-off is larger than that, the stream is held to the exact
variance instead (:func:`_exact_var`, in integers): on phase data with a drift or a random-walk
character the batch subtracts the line through the first and last points (which no stream can
know) and loses up to 3e-10 on these data, while the stream, which differences the samples
first, stays within 1e-15 of the exact value. White phase noise's longest MDEV rows are the
stream's weak spot: the window sums weigh each frequency sample by up to m, so one rounding
per sample moves them by about 5e-13 (the batch's own frequency path shows the same), and the
stream stays within 2e-12 of the exact value there.
"""

from __future__ import annotations

import gc
import tracemalloc
from fractions import Fraction

import numpy as np
import pytest

import sigmatau
from sigmatau.errors import DataError, ParameterError
from sigmatau.noise.generate import power_law_noise
from sigmatau.stream import STREAMABLE, Stream

ALPHAS = {"WPM": 2, "FPM": 1, "WFM": 0, "FFM": -1, "RWFM": -2, "FWFM": -3, "RRFM": -4}
RATE = 50.0
RTOL = 1e-12
#: Tolerance to the exact variance where the batch's own round-off exceeds RTOL.
EXACT_RTOL = 2e-12


# ------------------------------------------------------------------ the exact oracle


def _as_integers(v: np.ndarray) -> tuple[np.ndarray, int]:
    """``(k, e)`` with ``v = k·2**e`` exactly, k Python integers."""
    nz = v[v != 0]
    if nz.size == 0:
        return np.zeros(v.size, dtype=object), 0
    e_min = int(np.min(np.frexp(nz)[1])) - 53
    mant, exp = np.frexp(v)
    ints = (mant * 2.0**53).astype(np.int64)
    out = [int(a) << int(s - 53 - e_min) if a else 0 for a, s in zip(ints.tolist(), exp.tolist())]
    return np.array(out, dtype=object), e_min


def _exact_var(name: str, data: np.ndarray, data_type: str, ms: np.ndarray) -> np.ndarray:
    """The variance of ``name`` at ``ms`` computed exactly from the float64 samples (the plain
    SP1065 sums on the integer phase), rounded once at the end."""
    k, e = _as_integers(np.asarray(data, dtype=np.float64))
    x = k if data_type == "phase" else np.concatenate(([0], np.cumsum(k))).astype(object)
    n_pts = x.size
    out = []
    for m in ms.tolist():
        if name in ("oadev", "totdev", "mdev", "tdev"):
            d = x[2 * m :] - 2 * x[m:-m] + x[: -2 * m]
        if name == "oadev":
            num, den = int(np.dot(d, d)), 2 * m * m * d.size
        elif name == "ohdev":
            d = x[3 * m :] - 3 * x[2 * m : -m] + 3 * x[m : -2 * m] - x[: -3 * m]
            num, den = int(np.dot(d, d)), 6 * m * m * d.size
        elif name in ("mdev", "tdev"):
            c = np.concatenate(([0], np.cumsum(d))).astype(object)
            s = c[m:] - c[:-m]
            num, den = int(np.dot(s, s)), 2 * m**4 * s.size
        elif name in ("adev", "hdev"):
            xs = x[: ((n_pts - 1) // m) * m + 1 : m]
            d = xs[2:] - 2 * xs[1:-1] + xs[:-2] if name == "adev" else xs[3:] - 3 * xs[2:-1] + 3 * xs[1:-2] - xs[:-3]
            num, den = int(np.dot(d, d)), (2 if name == "adev" else 6) * m * m * d.size
        else:  # totdev: the doubly reflected record
            inner = x[n_pts - 2 : 0 : -1]
            ext = np.concatenate((2 * x[0] - inner, x, 2 * x[-1] - inner))
            i = np.arange(1, n_pts - 1) + n_pts - 2
            d = ext[i - m] - 2 * ext[i] + ext[i + m]
            num, den = int(np.dot(d, d)), 2 * m * m * (n_pts - 2)
        v = Fraction(num, den) * Fraction(2) ** (2 * e)
        if data_type == "phase":
            v *= Fraction(RATE) ** 2  # phase differences over τ0², τ0 = 1/RATE
        if name == "tdev":
            v *= Fraction(m) ** 2 / Fraction(RATE) ** 2 / 3
        out.append(float(v))
    return np.array(out)


# ------------------------------------------------------------------ comparing


def _assert_same(got: sigmatau.StabilityResult, ref: sigmatau.StabilityResult, data: np.ndarray) -> None:
    """The stream's result is the batch's (see the module docstring for the variance)."""
    assert (got.statistic, got.data_type, got.rate, got.n_points) == (ref.statistic, ref.data_type, ref.rate,
                                                                       ref.n_points)
    np.testing.assert_array_equal(got.m, ref.m)
    np.testing.assert_array_equal(got.taus, ref.taus)
    np.testing.assert_array_equal(got.n, ref.n)
    np.testing.assert_array_equal(got.alpha, ref.alpha)
    np.testing.assert_array_equal(got.edf, ref.edf)
    assert got.ci_reason == ref.ci_reason and got.confidence == ref.confidence
    np.testing.assert_allclose(got.alpha_estimate, ref.alpha_estimate, rtol=0, atol=1e-9, equal_nan=True)
    rel = np.abs(got.var - ref.var) / ref.var
    if np.all(rel <= RTOL):
        target, rtol = ref.var, RTOL
    else:  # the batch's own round-off: hold both to the exact value
        target, rtol = _exact_var(got.statistic, data, got.data_type, got.m), EXACT_RTOL
        assert np.max(np.abs(ref.var - target) / target) > RTOL or np.max(rel) <= EXACT_RTOL
    np.testing.assert_allclose(got.var, target, rtol=rtol, atol=0)
    # the interval scales with the deviation: the same relative agreement
    scale = np.sqrt(target / ref.var)
    np.testing.assert_allclose(got.ci_low, ref.ci_low * scale, rtol=rtol, atol=0, equal_nan=True)
    np.testing.assert_allclose(got.ci_high, ref.ci_high * scale, rtol=rtol, atol=0, equal_nan=True)


def _chunk_sizes(rng: np.random.Generator, n: int) -> list[int]:
    """Random chunk sizes adding up to n: single samples (a run of them too), small and large."""
    sizes: list[int] = [1] * 150
    while sum(sizes) < n:
        sizes.append(int(rng.choice([1, 2, 3, 17, 100, 511, 1000, 2500])))
    sizes[-1] -= sum(sizes) - n
    return sizes


# ------------------------------------------------------------------ equality with the batch


@pytest.mark.slow
@pytest.mark.parametrize("data_type", ["freq", "phase"])
@pytest.mark.parametrize("noise", list(ALPHAS))
def test_equals_batch_on_power_law_noise(noise, data_type, rng):
    n = 6000
    data = power_law_noise(n, ALPHAS[noise], data_type=data_type, rate=RATE, rng=rng)
    block = 256 if data_type == "phase" else 1024  # levels longer than the block, rings that wrap
    stream = Stream(RATE, statistics=STREAMABLE, data_type=data_type, max_m=2**16, block=block)
    checkpoints = {37, 700, 2900, n}
    pos = 0
    for size in _chunk_sizes(rng, n):
        for cut in sorted(c for c in checkpoints if pos < c < pos + size) + [pos + size]:
            stream.update(data[pos:cut])
            pos = cut
            if pos in checkpoints:
                assert stream.n == pos
                for name in STREAMABLE:
                    ref = getattr(sigmatau, name)(data[:pos], rate=RATE, data_type=data_type)
                    _assert_same(stream.result(name), ref, data[:pos])


def test_frequency_offset_phase_is_exact(rng):
    # A clock's phase: a frequency offset 250 times the noise. The batch subtracts the line
    # through the end points and loses ~1e-11; the stream differences first and stays within
    # 1e-13 of the exact value.
    y = rng.standard_normal(20_000) * 1e-9 + 2.5e-7
    x = np.cumsum(y) * 0.01 + 3.0
    stream = Stream(RATE, statistics=("oadev", "ohdev", "mdev", "totdev"), data_type="phase")
    for chunk in np.array_split(x, 9):
        stream.update(chunk)
    for name in stream.statistics:
        got = stream.result(name)
        exact = _exact_var(name, x, "phase", got.m)
        np.testing.assert_allclose(got.var, exact, rtol=1e-13, atol=0)
        _assert_same(got, getattr(sigmatau, name)(x, rate=RATE, data_type="phase"), x)


def test_grid_stops_at_max_m(rng):
    y = rng.standard_normal(9000)
    stream = Stream(RATE, statistics=("oadev", "totdev"), max_m=100)
    stream.update(y)
    for name in ("oadev", "totdev"):
        got, ref = stream.result(name), getattr(sigmatau, name)(y, rate=RATE)
        assert got.m.tolist() == [m for m in ref.m.tolist() if m <= 100] and got.m[-1] == 64
        rows = slice(0, len(got))
        np.testing.assert_allclose(got.var, ref.var[rows], rtol=RTOL, atol=0)
        np.testing.assert_array_equal(got.alpha, ref.alpha[rows])
        np.testing.assert_array_equal(got.edf, ref.edf[rows])


def test_several_channels_are_each_the_batch(rng):
    data = np.column_stack([power_law_noise(3000, a, rng=rng) for a in (0, -1, -2)])
    stream = Stream(RATE, statistics=("adev", "ohdev", "mdev"))
    for chunk in np.array_split(data, 11):
        stream.update(chunk)
    assert stream.channels == 3 and stream.n == 3000
    for ch in range(3):
        for name, got in stream.results(channel=ch).items():
            _assert_same(got, getattr(sigmatau, name)(data[:, ch], rate=RATE), data[:, ch])


@pytest.mark.parametrize("options", [{"ci": "simple"}, {"ci": None}, {"confidence": 0.95}])
def test_uncertainty_options_are_the_batch(options, rng):
    y = rng.standard_normal(4000)
    stream = Stream(RATE, statistics=("oadev", "totdev"), **options)
    stream.update(y)
    for name in ("oadev", "totdev"):
        got, ref = stream.result(name), getattr(sigmatau, name)(y, rate=RATE, **options)
        np.testing.assert_allclose(got.var, ref.var, rtol=RTOL, atol=0)
        for field in ("alpha", "edf", "ci_low", "ci_high"):
            a, b = getattr(got, field), getattr(ref, field)
            assert (a is None) == (b is None)
            if a is not None:
                np.testing.assert_allclose(a, b, rtol=RTOL, atol=0, equal_nan=True)
        assert got.ci_reason == ref.ci_reason


def test_unidentified_noise_has_the_batch_reason():
    stream = Stream(RATE, statistics=("oadev",))
    stream.update(np.ones(500))
    got, ref = stream.result("oadev"), sigmatau.oadev(np.ones(500), rate=RATE)
    assert np.all(np.isnan(got.alpha)) and got.ci_reason == ref.ci_reason


def test_integer_input(rng):
    counts = rng.integers(-5000, 5000, 4000)
    stream = Stream(RATE, statistics=("oadev",))
    stream.update(counts[:1234])
    stream.update(counts[1234:])
    _assert_same(stream.result("oadev"), sigmatau.oadev(counts, rate=RATE), counts.astype(float))


@pytest.mark.filterwarnings("ignore::sigmatau.imu.ImuWarning")  # a minute of data resolves no K
def test_imu_model_is_analyze_of_the_streamed_curve(rng):
    y = sigmatau.imu.simulate("lsm6dsl-gyro", duration=60.0, rate=100.0, rng=rng)
    stream = Stream(100.0, statistics=("oadev",))
    for chunk in np.array_split(y, 5):
        stream.update(chunk)
    got = stream.imu_model(unit="rad/s")
    ref = sigmatau.imu.analyze(sigmatau.oadev(y, rate=100.0), unit="rad/s")
    assert str(got) == str(ref)
    with pytest.raises(ParameterError, match="rate samples"):
        Stream(100.0, data_type="phase").imu_model(unit="rad/s")


# ------------------------------------------------------------------ memory


@pytest.mark.slow
def test_state_does_not_grow_with_the_record(rng):
    stream = Stream(1000.0, max_m=2**10)
    chunk = rng.standard_normal(10_000)
    stream.update(chunk)
    stream.results()
    fixed = stream.nbytes
    gc.collect()
    tracemalloc.start()
    try:
        for _ in range(10):
            stream.update(chunk)
        stream.results()
        gc.collect()
        before = tracemalloc.get_traced_memory()[0]
        for _ in range(90):  # from 10⁵ to 10⁶ samples
            stream.update(chunk)
        stream.results()
        gc.collect()
        after = tracemalloc.get_traced_memory()[0]
    finally:
        tracemalloc.stop()
    assert stream.n == 1_010_000
    assert stream.nbytes == fixed
    assert after - before < 64 * 1024  # results of a fixed size; nothing that follows n


def test_memory_follows_max_m():
    # 8·(11·P + 4·block per factor) bytes: the block's share is small at this block
    small, large = Stream(1.0, max_m=2**15, block=1024), Stream(1.0, max_m=2**17, block=1024)
    for s in (small, large):
        s.update(np.zeros(10))
    per_factor = (large.nbytes - small.nbytes) / (2**17 - 2**15)
    assert 85 < per_factor < 92


# ------------------------------------------------------------------ bad input


@pytest.mark.parametrize("chunk, match", [
    (np.array([1.0, np.nan, 2.0]), "non-finite.*no gaps"),
    (np.array([1.0, np.inf]), "non-finite"),
    (np.zeros((2, 2, 2)), "1-D .* or 2-D"),
    (np.zeros((4, 3)), "3 channel"),
    (np.array(["a", "b"]), "numeric"),
    (np.array([1 + 2j]), "real"),
    ([[1.0, 2.0], [3.0]], "ragged"),
    (np.array([2**60, 1]), "2\\*\\*53"),
    (np.ma.masked_array([1.0, 2.0], mask=[0, 1]), "masked"),
    # values the running sums could not hold: before, ±1e308 was taken and every later result
    # was NaN ("variance about 1e+nan")
    (np.array([1e308, -1e308]), "beyond ±1e300"),
    (np.array([1e150]), "times their scale"),
])
def test_bad_chunk_is_one_data_error_and_changes_nothing(chunk, match, rng):
    stream = Stream(RATE, statistics=("oadev",))
    y = rng.standard_normal(100)
    stream.update(y)
    before = stream.result("oadev")
    with pytest.raises(DataError, match=match):
        stream.update(chunk)
    assert stream.n == 100
    np.testing.assert_array_equal(stream.result("oadev").var, before.var)


def test_phase_values_beyond_the_sums_range_are_refused(rng):
    stream = Stream(RATE, statistics=("oadev", "mdev"), data_type="phase")
    stream.update(np.cumsum(rng.standard_normal(500)))
    before = stream.result("mdev").var
    with pytest.raises(DataError, match="phase values depart"):
        stream.update(np.array([1e160]))
    stream.update(np.array([1e3]))   # large but within range: taken
    assert stream.n == 501 and not np.array_equal(stream.result("mdev").var, before)


@pytest.mark.parametrize("kwargs, match", [
    ({"rate": 0.0}, "rate"), ({"rate": -1.0}, "rate"), ({"rate": "1"}, "rate"),
    ({"statistics": ("oadev", "foo")}, "streamable statistics are adev, oadev"),
    ({"statistics": "theo1"}, "75 %"), ({"statistics": ()}, "empty"),
    ({"taus": "decade"}, "octave grid only"), ({"max_m": 1}, "max_m"), ({"data_type": "x"}, "data_type"),
    ({"confidence": 1.5}, "confidence"), ({"channels": 0}, "channels"), ({"block": 3}, "block"),
])
def test_bad_option_is_one_parameter_error(kwargs, match):
    options = {"rate": 1.0, **kwargs}
    with pytest.raises(ParameterError, match=match):
        Stream(**options)


def test_empty_chunks_and_too_short_records():
    stream = Stream(RATE, statistics=("oadev", "ohdev"))
    stream.update([])
    stream.update(np.empty((0, 1)))
    assert stream.n == 0 and stream.nbytes == 0
    with pytest.raises(DataError, match="oadev needs at least 2 frequency samples, got 0"):
        stream.result("oadev")
    stream.update([1.0, 2.0])
    with pytest.raises(DataError, match="ohdev needs at least 3 frequency samples, got 2"):
        stream.result("ohdev")
    assert len(stream.result("oadev")) == 1
    with pytest.raises(ParameterError, match="not among this stream's statistics"):
        stream.result("mdev")
    with pytest.raises(ParameterError, match="streamable"):
        stream.result("foo")
    with pytest.raises(ParameterError, match="channel"):
        stream.result("oadev", channel=1)


# ------------------------------------------------------------------ long


@pytest.mark.slow
@pytest.mark.parametrize("data_type", ["freq", "phase"])
def test_long_record_equals_batch(data_type):
    rng = np.random.default_rng(20240601)
    n = 2**20 + 123
    data = power_law_noise(n, 0, data_type=data_type, rng=rng) + power_law_noise(n, -2, data_type=data_type,
                                                                                  h=1e-6, rng=rng)
    stream = Stream(1000.0, statistics=STREAMABLE, data_type=data_type, max_m=2**18)
    for chunk in np.array_split(data, 997):
        stream.update(chunk)
    for name in STREAMABLE:
        got, ref = stream.result(name), getattr(sigmatau, name)(data, rate=1000.0, data_type=data_type)
        rows = slice(0, len(got))
        np.testing.assert_allclose(got.var, ref.var[rows], rtol=RTOL, atol=0)
        np.testing.assert_array_equal(got.alpha, ref.alpha[rows])
        np.testing.assert_array_equal(got.edf, ref.edf[rows])
