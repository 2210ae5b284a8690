"""The O(N) MTOT/TTOT/HTOT path held to the plain definition.

``total._tot_sums_fast`` rebuilds ``Σ_n Σ_j z_j(n)²`` from running sums of
the data instead of forming the 9m-point extension of every subsequence
(see the comment above it in ``sigmatau/total.py``). It is compared here with
the construction of numerics.md §1.9 written step by step, on the seven noise
types of ``tests/_noise.py`` as phase (MTOT, TTOT) and as frequency (HTOT),
with odd and prime lengths, factors up to the largest allowed, and a large
linear trend.

Tolerance: 1e-9 relative (issue 6). The fast path products of running sums
lose a few digits for smooth noise; measured against an extended-precision
evaluation of the definition the worst case is about 1e-13.
"""

from __future__ import annotations

import tracemalloc
import warnings

import numpy as np
import pytest
from numpy.lib.stride_tricks import sliding_window_view

import sigmatau.stats.total as total_mod
import sigmatau.stats.total_sums as total_sums
from _noise import NOISES
from sigmatau.core.driver import prepare
from sigmatau.errors import RangeWarning
from sigmatau.stats.total import htotdev, mtotdev, ttotdev

RTOL = 1e-9


def tot_plain(u, m):
    """Mean over subsequences of ``(1/6m)·Σ_j z_j²``, by the steps of numerics §1.9.

    Vectorised over subsequences but otherwise literal: half-average slope,
    uninverted 9m reflection, m-averages, second differences. Each subsequence
    first loses its first sample, a constant the construction ignores, so that
    phase values far larger than their differences (random-run noise) keep
    their digits.
    """
    u = np.asarray(u, dtype=float)
    length = 3 * m
    h1, h2 = length // 2, (length + 1) // 2
    windows = u.size - length + 1
    k = np.arange(length, dtype=float)
    view = sliding_window_view(u, length)
    rows = max(1, (1 << 20) // (9 * m))
    acc = 0.0
    for first in range(0, windows, rows):
        s = view[first : first + rows] - view[first : first + rows, :1]
        slope = (s[:, h2:].mean(axis=1) - s[:, :h1].mean(axis=1)) / h2
        s = s - slope[:, None] * k
        e = np.concatenate((s[:, ::-1], s, s[:, ::-1]), axis=1)
        run = np.zeros((e.shape[0], 9 * m + 1))
        np.cumsum(e, axis=1, out=run[:, 1:])
        a = (run[:, m:] - run[:, :-m]) / m
        z = a[:, : 6 * m] - 2.0 * a[:, m : 7 * m] + a[:, 2 * m : 8 * m]
        acc += float(np.sum(z * z))
    return acc / (6 * m * windows), windows


def fast_mean(u, m, **kw):
    total, windows = total_sums.tot_sums_fast(np.asarray(u, dtype=float), m, **kw)
    return total / (6 * m * windows), windows


def _series(name, n, seed):
    """Frequency samples of noise ``name`` (mean removed) and their phase (N = n + 1)."""
    y = NOISES[name](n, np.random.default_rng(seed))
    y = y - y.mean()
    return y, np.concatenate(([0.0], np.cumsum(y)))


def _assert_close(u, m, **kw):
    want, w_want = tot_plain(u, m)
    got, windows = fast_mean(u, m, **kw)
    assert windows == w_want
    assert got == pytest.approx(want, rel=RTOL, abs=0), m


# --- all seven noise types, long records ---------------------------------------------

# 100 003 is prime; m = 33 334 is the largest factor for its phase (N/3, two
# subsequences) and 33 330 leaves 14 subsequences, fewer than one block.
LONG = 100_002
LONG_FACTORS = [2, 5, 33_330, 33_334]
# Mid-range factors on a shorter record (5 003 phase points, prime; the plain
# construction costs O(N·m)): several blocks plus a partial one.
MID = 5_002
MID_FACTORS = [3, 64, 700, 1_667]


@pytest.mark.slow
@pytest.mark.parametrize("name", list(NOISES))
def test_fast_equals_plain_long_records(name):
    y, x = _series(name, LONG, seed=sum(map(ord, name)))
    for u in (x, y):  # MTOT on phase, HTOT on frequency
        for m in LONG_FACTORS:
            if 3 * m <= u.size:
                _assert_close(u, m)


@pytest.mark.slow
@pytest.mark.parametrize("name", list(NOISES))
def test_fast_equals_plain_mid_factors(name):
    y, x = _series(name, MID, seed=7 + sum(map(ord, name)))
    for u in (x, y):
        for m in MID_FACTORS:
            if 3 * m <= u.size:
                _assert_close(u, m)


def test_fast_equals_plain_mid_factor_on_long_record():
    """A mid factor on the long record: 221 full blocks of 3m windows and a partial one."""
    _, x = _series("RRFM", LONG, seed=3)
    _assert_close(x, 150)


@pytest.mark.parametrize("name", ["WFM", "RWFM", "RRFM"])
@pytest.mark.parametrize("n", [7, 8, 37, 101])
def test_fast_equals_plain_every_factor_short(name, n):
    y, x = _series(name, n, seed=n)
    for u in (x, y):
        for m in range(1, u.size // 3 + 1):
            _assert_close(u, m)


@pytest.mark.parametrize("block", [1, 50, 997, 1 << 20])
def test_batching_of_blocks_does_not_change_the_result(block):
    """One block per batch, batches that do not divide the blocks, all at once."""
    _, x = _series("FFM", 4_999, seed=1)
    for m in (2, 17, 150):
        _assert_close(x, m, block=block)


# --- trends --------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["WPM", "WFM", "RRFM"])
def test_large_linear_phase_trend(name):
    """A line that dwarfs the data changes nothing.

    Offset 3e12 and slope 7e6 per sample against |x| ≤ 2^20; the data are
    integers, so the sum is exact and only the kernel can lose digits.
    """
    _, x = _series(name, 10_000, seed=5)
    x = np.round(x / np.abs(x).max() * 2.0**20)  # integers, |x| ≤ 2^20
    t = np.arange(x.size, dtype=float)
    ramp = x + (3.0e12 + 7.0e6 * t)  # still exact: < 2^53
    for m in (2, 9, 500, 3_333):
        want, _ = tot_plain(x, m)
        got, _ = fast_mean(ramp, m)
        assert got == pytest.approx(want, rel=RTOL, abs=0), m


def test_large_linear_frequency_drift():
    """HTOT removes a linear frequency drift from every subsequence."""
    y, _ = _series("FWFM", 10_001, seed=6)
    y = np.round(y / np.abs(y).max() * 2.0**20)
    t = np.arange(y.size, dtype=float)
    drift = y + (5.0e11 - 1.0e6 * t)
    for m in (2, 40, 700, 3_333):
        want, _ = tot_plain(y, m)
        got, _ = fast_mean(drift, m)
        assert got == pytest.approx(want, rel=RTOL, abs=0), m


# --- public functions ----------------------------------------------------------------


@pytest.mark.parametrize("name", ["WPM", "RRFM"])
def test_public_functions_use_the_fast_path(name, monkeypatch):
    """mtotdev/ttotdev/htotdev over an octave grid equal the plain construction."""
    y, _ = _series(name, 3_001, seed=9)
    rate = 2.0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RangeWarning)
        calls = []
        fast = total_sums.tot_sums_fast
        monkeypatch.setattr(total_sums, "tot_sums_fast", lambda u, m: calls.append(m) or fast(u, m))
        mt = mtotdev(y, rate=rate, ci=None)
        tt = ttotdev(y, rate=rate, ci=None)
        ht = htotdev(y, rate=rate, ci=None)
    assert set(calls) == {int(m) for m in mt.m if m >= total_sums.FAST_MIN_M}
    x, _, _ = prepare(total_mod.MTOT, y, rate, "freq")
    tau0 = 1.0 / rate
    for i, m in enumerate(mt.m):
        mean, windows = tot_plain(x, int(m))
        var = mean / (2.0 * (m * tau0) ** 2)
        assert mt.n[i] == windows
        assert mt.var[i] == pytest.approx(var, rel=RTOL, abs=0)
        assert tt.var[i] == pytest.approx(var * (m * tau0) ** 2 / 3.0, rel=RTOL, abs=0)
    freq = np.diff(x) / tau0
    for i, m in enumerate(ht.m):
        if m == 1:
            continue  # OHVAR, as Stable32 reports (test_total.py)
        mean, windows = tot_plain(freq, int(m))
        assert ht.n[i] == windows
        assert ht.var[i] == pytest.approx(mean / 6.0, rel=RTOL, abs=0)


# --- cost ----------------------------------------------------------------------------


def test_memory_is_linear_in_the_record():
    """No (N × m) array: the peak stays a few copies of the record (about 6 at most)."""
    u = np.random.default_rng(9).standard_normal(100_000)
    for m in (50, u.size // 6, u.size // 3):
        tracemalloc.start()
        try:
            total_sums.tot_sums_fast(u, m)
            _, peak = tracemalloc.get_traced_memory()
        finally:
            tracemalloc.stop()
        assert peak < 8 * u.itemsize * u.size, m
