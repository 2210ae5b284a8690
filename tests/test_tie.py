"""MTIE and TIE rms (sigmatau.tie).

Sources (numerics.md, tests/data/allantools/README.md):

* NBS 1000-point set, numerics.md §7.4: MTIE and TIE rms at m = 1, 10, 100,
  computed independently (no published counterpart) on the NBS phase, i.e. the
  cumulative sum of the frequency set from x_0 = 0 with its 0.49 mean frequency
  kept (PHASE.DAT, which has it removed, gives different numbers). Held to half
  a unit in the seventh digit.
* Stable32 tables: PHASE.DAT "MTIE (Fast)" (factors 2^k − 1) and "TIE rms";
  Keysight 53230A time-interval noise floor "TIE rms". Five significant digits:
  relative 1e-4 on the value, the count column exactly.

MTIE's fast path (running extremes in blocks) is held to a plain O(N·n) scan of
every window.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import refdata
from helpers import assert_printed
from sigmatau.stats import tie
from sigmatau.datasets import nbs1000
from sigmatau.errors import DataError, ParameterError, RangeWarning

STABLE32_RTOL = 1e-4


def explicit(func, data, **kw):
    """Call at explicit factors; those past the default limit warn by design."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RangeWarning)
        return func(data, **kw)


# --- plain definitions (numerics.md §1.15) ------------------------------------------------


def mtie_plain(x: np.ndarray, n: int) -> float:
    """max over k of (max − min of x_k … x_{k+n}), one window at a time."""
    best = 0.0
    for k in range(x.size - n):
        w = x[k : k + n + 1]
        best = max(best, float(w.max() - w.min()))
    return best


def tierms_plain(x: np.ndarray, n: int) -> float:
    return float(np.sqrt(np.mean([(x[i + n] - x[i]) ** 2 for i in range(x.size - n)])))


@pytest.mark.parametrize("n_points", [3, 4, 17, 64, 97, 257])
def test_mtie_every_window_matches_plain_scan(n_points):
    rng = np.random.default_rng(n_points)
    for x in (rng.standard_normal(n_points), np.cumsum(rng.standard_normal(n_points))):
        ms = np.arange(1, n_points)
        r = explicit(tie.mtie, x, data_type="phase", m=ms)
        ref = np.array([mtie_plain(x, int(m)) for m in ms])
        np.testing.assert_allclose(r.dev, ref, rtol=0.0, atol=0.0)  # max/min/subtract: exact
        np.testing.assert_array_equal(r.n, n_points - ms)


def test_mtie_larger_prime_record():
    rng = np.random.default_rng(1)
    x = np.cumsum(rng.standard_normal(2003)) + rng.standard_normal(2003)
    ms = np.array([1, 2, 3, 7, 50, 63, 64, 65, 500, 1001, 1500, 2002])
    r = explicit(tie.mtie, x, data_type="phase", m=ms)
    for m, got in zip(ms, r.dev):
        w = np.lib.stride_tricks.sliding_window_view(x, int(m) + 1)
        assert got == float(np.max(w.max(axis=1) - w.min(axis=1)))


def test_tierms_matches_plain():
    rng = np.random.default_rng(2)
    for n_points in (3, 31, 401):
        x = np.cumsum(rng.standard_normal(n_points))
        ms = np.unique(np.linspace(1, n_points - 1, 12).astype(int))
        r = explicit(tie.tierms, x, data_type="phase", m=ms)
        np.testing.assert_allclose(r.dev, [tierms_plain(x, int(m)) for m in ms], rtol=1e-13)
        np.testing.assert_array_equal(r.n, n_points - ms)


# --- NBS 1000-point set (numerics.md §7.4) ----------------------------------------------------


def test_nbs_mtie_and_tierms():
    y = nbs1000()
    r = tie.mtie(y, m=[1, 10, 100])
    for dev, printed in zip(r.dev, ("9.957453e-01", "7.596560e+00", "5.538177e+01")):
        assert_printed(dev, printed)
    r = tie.tierms(y, m=[1, 10, 100])
    for dev, printed in zip(r.dev, ("5.683385e-01", "4.975004e+00", "4.942407e+01")):
        assert_printed(dev, printed)
    np.testing.assert_array_equal(r.n, [1000, 991, 901])
    np.testing.assert_allclose(r.var, r.dev**2, rtol=1e-15)


# --- Stable32 tables ----------------------------------------------------------------------------


@pytest.mark.parametrize(
    "func, table, data",
    [
        (tie.mtie, "phasedat/phase_dat_mtie.txt", refdata.phase_dat),
        (tie.tierms, "phasedat/phase_dat_tierms.txt", refdata.phase_dat),
        (tie.tierms, "Keysight53230A_ti_noise_floor/tic_tierms.txt", refdata.tic_phase),
    ],
    ids=["phasedat-mtie", "phasedat-tierms", "keysight-tierms"],
)
def test_stable32_tables(func, table, data):
    t = refdata.load_table(table)
    r = explicit(func, data(), data_type="phase", m=t.af)
    np.testing.assert_allclose(r.dev, t.sigma, rtol=STABLE32_RTOL)
    np.testing.assert_array_equal(r.n, t.n)
    np.testing.assert_allclose(r.taus, t.tau, rtol=1e-12)


# --- properties ---------------------------------------------------------------------------------


def test_not_invariant_to_frequency_offset():
    # A pure frequency offset b: every window spans b·n, every TIE is b·n.
    x = 0.25 * np.arange(100.0)
    for func in (tie.mtie, tie.tierms):
        r = func(x, data_type="phase", m=[1, 5, 20])
        np.testing.assert_allclose(r.dev, [0.25, 1.25, 5.0], rtol=1e-14)
    # A phase offset changes nothing.
    x = np.random.default_rng(3).standard_normal(300)
    for func in (tie.mtie, tie.tierms):
        np.testing.assert_allclose(func(x + 1e3, data_type="phase").dev, func(x, data_type="phase").dev,
                                   rtol=1e-10)


def test_frequency_input_is_integrated_as_given():
    y = np.random.default_rng(4).standard_normal(500) + 2.0
    x = np.concatenate(([0.0], np.cumsum(y))) / 10.0
    for func in (tie.mtie, tie.tierms):
        a = func(y, rate=10.0)
        b = func(x, rate=10.0, data_type="phase")
        np.testing.assert_allclose(a.dev, b.dev, rtol=1e-12)
        np.testing.assert_allclose(a.taus, a.m / 10.0)


def test_default_grids():
    x = np.random.default_rng(5).standard_normal(1001)
    assert tie.mtie(x, data_type="phase").m.max() == 256  # N/2 = 500
    assert tie.tierms(x, data_type="phase").m.max() == 128  # N/4 = 250


def test_errors():
    with pytest.raises(ParameterError, match="outside"):
        tie.mtie(np.arange(10.0), data_type="phase", m=10)
    with pytest.raises(ParameterError, match="outside"):
        tie.tierms(np.arange(10.0), data_type="phase", m=0)
    with pytest.raises(DataError):
        tie.mtie([1.0], data_type="phase")
    with pytest.raises(DataError, match="missing"):
        tie.tierms([np.nan, np.nan, np.nan])
    with pytest.raises(DataError, match="infinite"):
        tie.tierms([np.inf, 1.0, 2.0])
    with pytest.warns(RangeWarning):
        tie.mtie(np.arange(10.0), data_type="phase", m=9)


@pytest.mark.parametrize("chunk", [None, 3, 16])
def test_mtie_octave_doubling_and_rebuilds_in_chunks(chunk, monkeypatch):
    """The running extremes are carried by doubling along the octave grid and rebuilt
    for other factors; with tiny chunks every chunk boundary is crossed."""
    import sigmatau.core.numeric as numeric

    if chunk is not None:
        monkeypatch.setattr(numeric, "CHUNK", chunk)
    rng = np.random.default_rng(21)
    for x in (np.cumsum(rng.standard_normal(301)), rng.standard_normal(256), np.cumsum(np.cumsum(rng.standard_normal(130)))):
        for ms in ([1, 2, 4, 8, 16, 32, 64, 128], [3, 6, 12, 24, 5, 10, 40, 7, 1], [x.size - 1, 1, x.size // 2]):
            ms = np.array(ms)
            got = tie._mtie_kernel(x, ms, 1.0)[0]
            ref = np.array([mtie_plain(x, int(m)) for m in ms]) ** 2
            np.testing.assert_array_equal(got, ref)
        r = tie.mtie(x, data_type="phase", ci=None)
        np.testing.assert_array_equal(r.dev, [mtie_plain(x, int(m)) for m in r.m])
