"""Missing samples (NaN gaps) in the chunked statistics, against the in-memory functions.

The oracle is always the public in-memory function on the same array with its NaNs
(``tests/test_gaps.py`` checks that one against the definitions): the chunked result
must have the same τ grid, ``n``, ``n_missing``, ``n_effective``, noise type, EDF and
interval, and the variance within 1e-12 relative, at any chunk size — the smallest
allowed (16, below most averaging factors), one that divides nothing here, and one
larger than the record — with gaps scattered, in a burst, at the first and last samples,
and straddling the chunk boundaries; an error or a warning must be the in-memory one.
"""

from __future__ import annotations

import tracemalloc
import warnings
from typing import Callable

import numpy as np
import pytest

import sigmatau
from helpers import assert_same_result
from _noise import NOISES
from sigmatau.errors import DataError
from sigmatau.scale import chunked

RTOL = 1e-12
N = 3001
NOISE_TYPES = ("WPM", "WFM", "FFM", "RWFM")
CHUNKS = (16, 97, 1000, 4096)  # the smallest allowed, a prime, one near N/3, one above N


def _record(noise: str, data_type: str, n: int, rng: np.random.Generator) -> np.ndarray:
    y = NOISES[noise](n, rng) * 1e-9 + 2.5e-7  # a frequency offset, as real oscillators have
    return y if data_type == "freq" else np.cumsum(y) * 0.01 + 3.0


# ------------------------------------------------------------------ gap patterns
# Each takes (n, rng, chunk) and returns the indices to mark missing.


def _scattered(n: int, rng: np.random.Generator, chunk: int) -> np.ndarray:
    return rng.choice(n, n // 100, replace=False)


def _burst(n: int, rng: np.random.Generator, chunk: int) -> np.ndarray:
    start = int(rng.integers(n // 4, n // 2))
    return np.arange(start, start + n // 20)


def _ends(n: int, rng: np.random.Generator, chunk: int) -> np.ndarray:
    return np.array([0, 1, n - 1])


def _chunk_edges(n: int, rng: np.random.Generator, chunk: int) -> np.ndarray:
    # Short gaps across the first boundaries between chunks (the middle when there is none).
    edges = np.arange(chunk, n, chunk)[:20] if chunk < n else np.array([n // 2])
    spans = [np.arange(e - int(rng.integers(1, 4)), e + int(rng.integers(1, 4))) for e in edges]
    where = np.concatenate(spans)
    return where[where < n]


PATTERNS: dict[str, Callable[[int, np.random.Generator, int], np.ndarray]] = {
    "scattered": _scattered, "burst": _burst, "ends": _ends, "chunk_edges": _chunk_edges,
}


def _with_gaps(data: np.ndarray, where: np.ndarray) -> np.ndarray:
    out = data.copy()
    out[where] = np.nan
    return out


# ------------------------------------------------------------------ comparison


def _assert_same(got: sigmatau.StabilityResult, ref: sigmatau.StabilityResult, rtol: float = RTOL) -> None:
    assert_same_result(got, ref, rtol)


def _outcome(call: Callable[[], sigmatau.StabilityResult]):
    """``(result or None, exception or None, warning messages)`` of a call."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            result, error = call(), None
        except DataError as exc:
            result, error = None, exc
    return result, error, [(w.category, str(w.message)) for w in caught]


def _assert_same_outcome(func: Callable, data: np.ndarray, chunk: int, **options: object) -> None:
    """The chunked call gives the in-memory result, or the same one-line error, with the same warnings."""
    ref, ref_err, ref_warn = _outcome(lambda: func(data, **options))
    got, got_err, got_warn = _outcome(lambda: func(chunked.from_array(data, chunk_size=chunk), **options))
    assert got_warn == ref_warn
    if ref_err is not None:
        assert got_err is not None, f"in memory: {ref_err}"
        assert type(got_err) is type(ref_err)
        assert str(got_err) == str(ref_err) and "\n" not in str(got_err)
        return
    assert got_err is None, got_err
    _assert_same(got, ref)


# ---------------------------------------------------------------- equality grid


@pytest.mark.slow
@pytest.mark.parametrize("pattern", sorted(PATTERNS))
@pytest.mark.parametrize("data_type", ["freq", "phase"])
@pytest.mark.parametrize("stat", chunked.STATISTICS)
def test_matches_in_memory(stat, data_type, pattern, rng):
    noise = NOISE_TYPES[(chunked.STATISTICS.index(stat) + sorted(PATTERNS).index(pattern)) % len(NOISE_TYPES)]
    clean = _record(noise, data_type, N, rng)
    func = getattr(sigmatau, stat)
    for chunk in CHUNKS:
        data = _with_gaps(clean, PATTERNS[pattern](N, rng, chunk))
        ref = func(data, rate=50.0, data_type=data_type)
        assert ref.n_missing > 0
        got = func(chunked.from_array(data, chunk_size=chunk), rate=50.0, data_type=data_type)
        _assert_same(got, ref)


@pytest.mark.parametrize("noise", NOISE_TYPES)
@pytest.mark.parametrize("data_type", ["freq", "phase"])
def test_every_pattern_at_once_and_every_statistic(noise, data_type, rng):
    clean = _record(noise, data_type, 4003, rng)
    where = np.concatenate([f(clean.size, rng, 251) for f in PATTERNS.values()])
    data = _with_gaps(clean, where)
    for stat in chunked.STATISTICS:
        ref = getattr(sigmatau, stat)(data, data_type=data_type)
        got = chunked.compute(stat, data, data_type=data_type, chunk_size=251)
        _assert_same(got, ref)


@pytest.mark.slow
def test_factors_far_above_the_chunk(rng):
    # m up to 60 times the chunk; gaps across the reads of every offset (0, m, 2m, 3m).
    clean = _record("FFM", "freq", 8009, rng)
    data = _with_gaps(clean, np.concatenate([_scattered(clean.size, rng, 16), _burst(clean.size, rng, 16)]))
    ms = [1, 2, 15, 16, 17, 100, 333, 1000, 1001, 2000]
    for data_type in ("freq", "phase"):
        series = data if data_type == "freq" else np.cumsum(np.nan_to_num(data)) + np.where(np.isnan(data), np.nan, 0)
        for stat in chunked.STATISTICS:
            for chunk in (16, 17):
                _assert_same_outcome(getattr(sigmatau, stat), series, chunk, m=ms, data_type=data_type, ci=None)


# -------------------------------------------------------------- sources, by name


def test_npy_file_and_compute_by_name(tmp_path, rng):
    data = _with_gaps(_record("RWFM", "freq", 20_011, rng), np.concatenate(
        [_scattered(20_011, rng, 0), _burst(20_011, rng, 0), _ends(20_011, rng, 0)]))
    path = tmp_path / "y.npy"
    np.save(path, data)
    for mmap in (False, True):
        src = chunked.from_npy(path, mmap=mmap, chunk_size=1009)
        for stat in ("oadev", "mdev", "totdev"):
            _assert_same(getattr(sigmatau, stat)(src), getattr(sigmatau, stat)(data))
    for stat in chunked.STATISTICS:
        _assert_same(chunked.compute(stat, str(path), chunk_size=1009, data_type="phase"),
                     getattr(sigmatau, stat)(data, data_type="phase"))


def test_dask_array_with_gaps(rng):
    da = pytest.importorskip("dask.array")
    data = _with_gaps(_record("WFM", "freq", 10_007, rng), _scattered(10_007, rng, 0))
    arr = da.from_array(data, chunks=3000)
    for stat in ("oadev", "totdev"):
        _assert_same(getattr(sigmatau, stat)(arr), getattr(sigmatau, stat)(data))


# ------------------------------------------------------------ options and bias


@pytest.mark.parametrize("options", [
    dict(alpha=0), dict(ci="simple"), dict(ci=None), dict(confidence=0.95), dict(taus="all"),
    dict(taus="decade"),
])
def test_options_pass_through(options, rng):
    n = 3001 if options.get("taus") != "all" else 401
    data = _with_gaps(_record("WFM", "freq", n, rng), _scattered(n, rng, 0))
    for stat in ("oadev", "mdev", "hdev", "totdev"):
        ref = getattr(sigmatau, stat)(data, rate=50.0, **options)
        got = getattr(sigmatau, stat)(chunked.from_array(data, chunk_size=97), rate=50.0, **options)
        _assert_same(got, ref)


@pytest.mark.parametrize("data_type", ["freq", "phase"])
@pytest.mark.parametrize("bias", ["none", "auto", "estimator"])
def test_totdev_bias(bias, data_type, rng):
    data = _with_gaps(_record("FFM", data_type, 10_007, rng), np.concatenate(
        [_scattered(10_007, rng, 0), _burst(10_007, rng, 0)]))
    ref = sigmatau.totdev(data, bias=bias, data_type=data_type)
    _assert_same(chunked.compute("totdev", data, chunk_size=1009, bias=bias, data_type=data_type), ref)


# ------------------------------------------------------------ noise identification


@pytest.mark.slow
@pytest.mark.parametrize("stat", ["oadev", "mdev", "hdev", "ohdev"])
def test_few_blocks_present_streams_b1(stat, rng):
    # A record mostly missing: at the longer factors fewer than 30 block means are present
    # among hundreds of blocks, so the noise type comes from B1 on means streamed past the
    # chunk (and R(n) where B1 cannot split white from flicker PM).
    for noise in ("WPM", "RWFM"):
        clean = _record(noise, "freq", 20_000, rng)
        data = _with_gaps(clean, np.arange(1000, 19_400))
        _assert_same_outcome(getattr(sigmatau, stat), data, 16, m=[1, 4, 16, 64, 100, 128])


@pytest.mark.parametrize("data_type", ["freq", "phase"])
def test_every_other_sample_missing(data_type, rng):
    # No two neighbours present at m = 1 (the lag-1 method has no pair, B1 no block), terms
    # only at even factors of phase data: whatever the in-memory path does, so does this.
    data = _record("WFM", data_type, 3000, rng)
    data[1::2] = np.nan
    for stat in chunked.STATISTICS:
        _assert_same_outcome(getattr(sigmatau, stat), data, 64, data_type=data_type, m=[1, 2, 4, 8])


def test_decimated_phase_without_neighbouring_pairs(rng):
    # x_{4+8k} missing: OADEV keeps terms at m = 4 (they start off the grid of multiples of 4),
    # but the decimated series x_{4j} has no two neighbours present (the lag-1 method gives
    # way to B1, whose blocks all hold a gap: the noise type is carried from m = 1).
    data = _record("WFM", "phase", 3000, rng)
    data[4::8] = np.nan
    for stat in chunked.STATISTICS:
        _assert_same_outcome(getattr(sigmatau, stat), data, 16, data_type="phase", m=[1, 2, 4])


# ------------------------------------------------------------------- edge cases


@pytest.mark.parametrize("data_type", ["freq", "phase"])
def test_all_missing_is_the_in_memory_error(data_type):
    data = np.full(500, np.nan)
    for stat in chunked.STATISTICS:
        _assert_same_outcome(getattr(sigmatau, stat), data, 64, data_type=data_type)


@pytest.mark.parametrize("data_type", ["freq", "phase"])
def test_one_sample_present(data_type):
    data = np.full(500, np.nan)
    data[123] = 1.5
    for stat in chunked.STATISTICS:
        _assert_same_outcome(getattr(sigmatau, stat), data, 64, data_type=data_type)


def test_infinite_value_is_the_in_memory_error(rng):
    data = _record("WFM", "freq", 5000, rng)
    data[[10, 4000]] = np.nan
    data[[3000, 4500]] = [np.inf, -np.inf]
    for stat in chunked.STATISTICS:
        _assert_same_outcome(getattr(sigmatau, stat), data, 1000)


@pytest.mark.parametrize("data_type", ["freq", "phase"])
def test_no_gap_free_term_anywhere(data_type):
    data = np.ones(200) + np.arange(200) * 1e-3
    data[::2] = np.nan
    for stat in chunked.STATISTICS:
        _assert_same_outcome(getattr(sigmatau, stat), data, 16, data_type=data_type)
        _assert_same_outcome(getattr(sigmatau, stat), data, 16, data_type=data_type, m=[3, 5])


@pytest.mark.parametrize("data_type", ["freq", "phase"])
def test_factors_without_a_gap_free_term_are_dropped_as_in_memory(data_type, rng):
    data = _record("WFM", data_type, 100, rng)
    data[::10] = np.nan  # runs of 9 samples
    for stat in chunked.STATISTICS:
        for options in (dict(taus="all"), dict(m=[1, 2, 10, 30])):
            _assert_same_outcome(getattr(sigmatau, stat), data, 16, data_type=data_type, ci=None, **options)


@pytest.mark.parametrize("scale", [1e-150, 1e150])
def test_extreme_scales_with_gaps(scale, rng):
    base = _with_gaps(_record("WFM", "freq", 3001, rng) * 1e9, _scattered(3001, rng, 0))
    for stat in chunked.STATISTICS:
        _assert_same_outcome(getattr(sigmatau, stat), base * scale, 997)


def test_records_without_gaps_are_unchanged(rng):
    data = _record("FFM", "freq", 3001, rng)
    got = sigmatau.oadev(chunked.from_array(data, chunk_size=97))
    assert got.n_missing == 0 and got.n_effective is None
    _assert_same(got, sigmatau.oadev(data))


# ----------------------------------------------------------------------- memory


def test_peak_memory_follows_the_chunk_with_gaps(tmp_path, rng):
    # As tests/test_chunked.py's memory test, with gaps: the running counts of missing
    # samples and the gap-free runs (read whole only when they fit in a chunk) add no
    # record-sized array.
    n, chunk = 1_000_000, 1 << 14
    data = _record("RWFM", "freq", n, rng)
    data[rng.choice(n, 50, replace=False)] = np.nan  # runs of ~20 000 samples: most longer than a chunk
    data[300_000:340_000] = np.nan
    path = tmp_path / "long.npy"
    np.save(path, data)
    for stat in ("oadev", "mdev", "totdev"):  # warm up: first-call imports allocate too
        chunked.compute(stat, _with_gaps(np.random.default_rng(0).standard_normal(2000), [5, 50]), m=[1, 4])
    for stat, data_type in (("oadev", "freq"), ("mdev", "phase"), ("totdev", "freq")):
        src = chunked.from_npy(path, chunk_size=chunk)
        tracemalloc.start()
        try:
            got = chunked.compute(stat, src, m=[1, 8, 1000, 5000], data_type=data_type)
            peak = tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()
        _assert_same(got, getattr(sigmatau, stat)(data, m=[1, 8, 1000, 5000], data_type=data_type))
        assert peak < 48 * 8 * chunk, (stat, peak / (8 * chunk))
