"""The TOTVAR kernel, which never builds the reflected extension, against one that does.

:func:`sigmatau.stats.total._totvar_kernel` reads the doubly reflected series
only at the two ends and sums the squares chunk by chunk. The oracles here
build the whole 3N-point extension with ``np.concatenate`` (the construction
the kernel replaced) or loop over the definition term by term, so any slip in
the edge bookkeeping (off-by-one at i = m or i = N-1-m, the case 2m > N where
one term reflects at both ends, chunks that straddle the edges) shows up as a
wrong sum, not as a rounding difference.
"""

from __future__ import annotations

import numpy as np
import pytest

from sigmatau.stats import total as total_mod
from sigmatau.stats.total import _totvar_kernel
from test_total import totvar_plain  # the written definition, one term at a time

RTOL = 1e-12


def totvar_extension(x, ms, tau0):
    """TOTVAR from the explicit extension ``[2x_0 - x_{N-2…1}, x, 2x_{N-1} - x_{N-2…1}]``."""
    n_pts = x.size
    inner = x[n_pts - 2 : 0 : -1]
    ext = np.concatenate((2.0 * x[0] - inner, x, 2.0 * x[-1] - inner))
    c = n_pts - 2  # x*_i sits at ext[i + c]
    i = np.arange(1, n_pts - 1)
    var = np.empty(len(ms))
    for k, m in enumerate(ms):
        d2 = ext[i - m + c] - 2.0 * ext[i + c] + ext[i + m + c]
        var[k] = float(np.sum(d2 * d2)) / (2.0 * (m * tau0) ** 2 * (n_pts - 2))
    return var


def _records():
    rng = np.random.default_rng(20240611)
    recs = {}
    for n in (3, 4, 5, 10):
        recs[f"rw{n}"] = np.cumsum(rng.standard_normal(n))
        recs[f"white{n}"] = rng.standard_normal(n) * 1e-9
        recs[f"offset{n}"] = 1e6 + rng.standard_normal(n) * 1e-6
    recs["rw257"] = np.cumsum(rng.standard_normal(257)) * 1e-3
    recs["white1000"] = rng.standard_normal(1000) * 1e-9
    recs["offset777"] = 1e6 + np.cumsum(rng.standard_normal(777)) * 1e-9
    recs["rwrw1500"] = np.cumsum(np.cumsum(rng.standard_normal(1500))) * 1e-6
    recs["drift_rw2048"] = 5.0 * np.arange(2048) + np.cumsum(rng.standard_normal(2048))
    return recs


RECORDS = _records()


@pytest.mark.parametrize("name", sorted(RECORDS))
def test_every_factor_matches_the_extension(name):
    x = RECORDS[name]
    ms = np.arange(1, x.size, dtype=np.int64)  # every valid m, 1 … N-1
    var, n = _totvar_kernel(x, ms, 0.7)
    want = totvar_extension(x, ms, 0.7)
    np.testing.assert_allclose(var, want, rtol=RTOL, atol=0)
    np.testing.assert_array_equal(n, x.size - 2)
    assert n.dtype == np.int64


@pytest.mark.parametrize("name", [k for k in sorted(RECORDS) if RECORDS[k].size <= 10])
def test_short_records_match_the_written_definition(name):
    x = RECORDS[name]
    ms = np.arange(1, x.size, dtype=np.int64)
    var, _ = _totvar_kernel(x, ms, 2.5)
    want = [totvar_plain(list(x), int(m), 2.5)[0] for m in ms]  # the written definition, term by term
    np.testing.assert_allclose(var, want, rtol=RTOL, atol=0)


def test_three_points_by_hand():
    # N = 3: one term, i = 1. m = 1: x0 - 2x1 + x2; m = 2: (2x0 - x1) - 2x1 + (2x2 - x1).
    x = np.array([1.0, 4.0, 2.0])
    var, n = _totvar_kernel(x, np.array([1, 2]), 1.0)
    assert var[0] == (1 - 8 + 2) ** 2 / 2.0
    assert var[1] == (2 * 1 - 4 - 8 + 2 * 2 - 4) ** 2 / (2.0 * 4)
    np.testing.assert_array_equal(n, [1, 1])


def test_integer_phase_is_exact():
    # Integer samples keep every term and partial sum exact, so any reordering of
    # the summation gives the same bits: the kernel must equal the oracle exactly.
    rng = np.random.default_rng(7)
    x = np.cumsum(rng.integers(-50, 51, 3001)).astype(float)
    ms = np.unique(np.r_[np.arange(1, 40), 2 ** np.arange(6, 12), 1499, 1500, 1501, 2999, 3000])
    np.testing.assert_array_equal(_totvar_kernel(x, ms, 1.0)[0], totvar_extension(x, ms, 1.0))


@pytest.mark.parametrize("chunk", [1, 2, 3, 7, 64])
def test_chunks_straddling_the_edges(monkeypatch, chunk):
    # Tiny chunks make edge chunks start and stop inside the reflected parts and,
    # for 2m > N, hold terms reflected at both ends.
    monkeypatch.setattr(total_mod, "CHUNK", chunk)
    rng = np.random.default_rng(chunk)
    x = np.cumsum(rng.standard_normal(151))
    ms = np.arange(1, x.size, dtype=np.int64)
    np.testing.assert_allclose(_totvar_kernel(x, ms, 1.0)[0], totvar_extension(x, ms, 1.0), rtol=RTOL, atol=0)


def test_long_record_crosses_chunk_boundaries():
    # Longer than several default chunks, so interior and edges both span chunks.
    rng = np.random.default_rng(3)
    x = 1e6 + np.cumsum(rng.standard_normal(100_003)) * 1e-9
    n = x.size
    ms = np.unique(np.r_[2 ** np.arange(0, 17), 32767, 32768, 32769, n // 2 - 1, n // 2, n // 2 + 1, n - 2, n - 1])
    np.testing.assert_allclose(_totvar_kernel(x, ms, 1e-3)[0], totvar_extension(x, ms, 1e-3), rtol=RTOL, atol=0)


def test_kernel_allocates_nothing_record_sized():
    # The memory beyond x is a few chunk buffers, whatever m: a record-sized
    # temporary (8·N bytes) would show in the traced peak.
    import tracemalloc

    rng = np.random.default_rng(11)
    x = np.cumsum(rng.standard_normal(400_000))
    ms = np.array([1, 2, 1024, 100_000, 199_999, 399_999])
    tracemalloc.start()
    try:
        _totvar_kernel(x, ms, 1.0)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < 8 * x.size / 4
