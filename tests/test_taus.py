"""τ grids: keyword grids, default and mathematical limits, explicit τ and m.

Stop ratios and limits: numerics.md §1.1–1.7 (Stable32 stop ratio, from Riley's
"evolution of frequency stability analysis software", Table III).
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import sigmatau
from sigmatau import ParameterError, RangeWarning
from sigmatau.datasets import nbs1000
from sigmatau.core.taus import TAU_GRIDS, m_grid, select_m

# name -> (Stable32 stop ratio, mathematical largest m for N phase points).
# stdev/ostdev are not in Stable32's table; they follow AVAR (5) and OAVAR (4).
LIMITS = {
    "adev": (5, lambda n: (n - 1) // 2),
    "oadev": (4, lambda n: (n - 1) // 2),
    "mdev": (4, lambda n: n // 3),
    "tdev": (4, lambda n: n // 3),
    "hdev": (5, lambda n: (n - 1) // 3),
    "ohdev": (4, lambda n: (n - 1) // 3),
    "stdev": (5, lambda n: (n - 1) // 2),  # K = ⌊M/m⌋ ≥ 2 averages
    "ostdev": (4, lambda n: n - 2),  # M - m + 1 ≥ 2 moving averages
}


# --- m_grid -------------------------------------------------------------------------------


def test_grid_names():
    assert TAU_GRIDS == ("octave", "decade", "all", "log")


def test_octave():
    assert m_grid("octave", 1000).tolist() == [1, 2, 4, 8, 16, 32, 64, 128, 256, 512]
    assert m_grid("octave", 1024).tolist()[-1] == 1024
    assert m_grid("octave", 1023).tolist()[-1] == 512
    assert m_grid("octave", 1).tolist() == [1]
    assert m_grid("octave", 2 ** 40).tolist() == [2 ** k for k in range(41)]


def test_decade():
    assert m_grid("decade", 1000).tolist() == [1, 2, 4, 10, 20, 40, 100, 200, 400, 1000]
    assert m_grid("decade", 39).tolist() == [1, 2, 4, 10, 20]
    assert m_grid("decade", 3).tolist() == [1, 2]
    assert m_grid("decade", 10 ** 6).tolist()[-4:] == [100000, 200000, 400000, 1000000]


def test_all():
    assert m_grid("all", 7).tolist() == [1, 2, 3, 4, 5, 6, 7]
    assert m_grid("all", 7, m_min=3).tolist() == [3, 4, 5, 6, 7]


def test_log():
    ms = m_grid("log", 1000)
    assert ms[0] == 1 and ms[-1] == 1000
    assert np.all(np.diff(ms) > 0)
    # ten logarithmic steps per decade once they are more than one apart
    big = ms[ms >= 100]
    np.testing.assert_allclose(big[1:] / big[:-1], 10 ** 0.1, rtol=0.02)
    assert len(ms) <= 31
    assert m_grid("log", 100, points_per_decade=3).tolist() == [1, 2, 5, 10, 22, 46, 100]
    assert m_grid("log", 1).tolist() == [1]


@pytest.mark.parametrize("kind", TAU_GRIDS)
def test_grids_are_sorted_unique_int_within_bounds(kind):
    for m_max in (1, 2, 3, 9, 10, 11, 99, 100, 101, 4999):
        ms = m_grid(kind, m_max)
        assert ms.dtype == np.int64
        assert ms.size >= 1 and ms[0] == 1
        assert ms[-1] <= m_max
        assert np.all(np.diff(ms) > 0)
        ms = m_grid(kind, m_max, m_min=3)
        assert np.all(ms >= 3) and np.all(ms <= m_max)


@pytest.mark.parametrize("kind", TAU_GRIDS)
def test_empty_grid(kind):
    assert m_grid(kind, 0).size == 0
    assert m_grid(kind, 4, m_min=5).size == 0


def test_even_grids():
    assert m_grid("octave", 100, even=True).tolist() == [2, 4, 8, 16, 32, 64]
    assert m_grid("decade", 100, even=True).tolist() == [2, 4, 10, 20, 40, 100]
    assert m_grid("all", 11, even=True).tolist() == [2, 4, 6, 8, 10]
    assert m_grid("all", 11, m_min=2, even=True).tolist() == [2, 4, 6, 8, 10]
    for kind in TAU_GRIDS:
        for m_max in (2, 3, 10, 101, 1000):
            ms = m_grid(kind, m_max, even=True)
            assert ms.size >= 1
            assert np.all(ms % 2 == 0) and np.all(ms >= 2) and np.all(ms <= m_max)
            assert np.all(np.diff(ms) > 0)


def test_bad_grid_arguments():
    with pytest.raises(ParameterError, match="taus='weekly'"):
        m_grid("weekly", 100)
    for ppd in (0, -1, 2.5):
        with pytest.raises(ParameterError, match="points_per_decade"):
            m_grid("log", 100, points_per_decade=ppd)


# --- default and mathematical limits per statistic ----------------------------------------


@pytest.fixture(params=sorted(LIMITS))
def name(request):
    return request.param


@pytest.mark.slow
@pytest.mark.parametrize("n_phase", [1001, 1003, 1004])
def test_default_limit(name, n_phase):
    stop, _ = LIMITS[name]
    x = np.random.default_rng(n_phase).standard_normal(n_phase)
    stat = getattr(sigmatau, name)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # keyword grids never warn
        everything = stat(x, data_type="phase", taus="all")
        octave = stat(x, data_type="phase")
        decade = stat(x, data_type="phase", taus="decade")
        log = stat(x, data_type="phase", taus="log")
    default_max = n_phase // stop
    assert everything.m.tolist() == list(range(1, default_max + 1))
    assert octave.m.tolist() == [2 ** k for k in range(default_max.bit_length())]
    assert decade.m[-1] <= default_max and log.m[-1] == default_max
    assert everything.n_points == n_phase


@pytest.mark.slow
def test_default_limit_frequency_data(name):
    # N counts phase points: M frequency samples give N = M + 1.
    stop, _ = LIMITS[name]
    result = getattr(sigmatau, name)(nbs1000(), taus="all")
    assert result.n_points == 1001
    assert result.m[-1] == 1001 // stop


def test_default_limit_short_record(name):
    # For short records the default limit never falls below one factor.
    stat = getattr(sigmatau, name)
    for size in range(4, 12):
        result = stat(np.random.default_rng(size).standard_normal(size), data_type="phase", taus="all")
        assert result.m[0] == 1
        assert result.m[-1] == max(1, min(size // LIMITS[name][0], LIMITS[name][1](size)))


def test_explicit_m_past_default_warns(name):
    stop, math_max = LIMITS[name]
    x = np.random.default_rng(5).standard_normal(1001)
    stat = getattr(sigmatau, name)
    default_max = 1001 // stop
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        inside = stat(x, data_type="phase", m=[1, default_max])
    assert inside.m.tolist() == [1, default_max]
    with pytest.warns(RangeWarning, match=rf"{name}.*m=\[{default_max + 1}\]") as record:
        beyond = stat(x, data_type="phase", m=[1, default_max + 1])
    assert beyond.m.tolist() == [1, default_max + 1]
    # stacklevel points at the caller, not at sigmatau's internals
    assert record[0].filename == __file__
    with pytest.warns(RangeWarning):
        last = stat(x, data_type="phase", m=math_max(1001))
    assert last.n[0] >= 1 and np.isfinite(last.dev[0])
    with pytest.raises(ParameterError, match=rf"m=\[{math_max(1001) + 1}\]"):
        stat(x, data_type="phase", m=math_max(1001) + 1)


def test_explicit_taus_past_default_warns():
    y = nbs1000()
    with pytest.warns(RangeWarning, match="m > 200"):
        result = sigmatau.adev(y, taus=[10.0, 300.0])
    assert result.m.tolist() == [10, 300]


# --- explicit τ -----------------------------------------------------------------------------


def test_explicit_taus_exact_multiples():
    y = nbs1000()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        r = sigmatau.oadev(y, taus=[4.0, 1.0, 1.0, 2.0])
        assert r.m.tolist() == [1, 2, 4]
        assert r.taus.tolist() == [1.0, 2.0, 4.0]
        # 0.3·10 = 3.0000000000000004: round-off is not "off the grid"
        r = sigmatau.oadev(y, rate=10.0, taus=[0.1, 0.2, 0.3, 0.5])
        assert r.m.tolist() == [1, 2, 3, 5]
        np.testing.assert_allclose(r.taus, [0.1, 0.2, 0.3, 0.5], rtol=1e-15)
        r = sigmatau.oadev(y, taus=np.array([2, 8]))
        assert r.m.tolist() == [2, 8]
        r = sigmatau.oadev(y, taus=16.0)
        assert r.m.tolist() == [16]


def test_explicit_taus_rounded_with_warning():
    y = nbs1000()
    with pytest.warns(RangeWarning, match="not multiples") as record:
        r = sigmatau.oadev(y, taus=[1.4, 2.6, 4.0])
    assert record[0].filename == __file__
    assert r.m.tolist() == [1, 3, 4]
    assert r.taus.tolist() == [1.0, 3.0, 4.0]
    with pytest.warns(RangeWarning, match="not multiples"):
        r = sigmatau.oadev(y, rate=4.0, taus=[0.3, 1.0])
    assert r.m.tolist() == [1, 4]


def test_explicit_taus_rounding_to_zero_rejected():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RangeWarning)
        with pytest.raises(ParameterError, match=r"m=\[0\]"):
            sigmatau.oadev(nbs1000(), taus=[0.2, 1.0])


def test_explicit_m_sorted_unique():
    r = sigmatau.mdev(nbs1000(), m=[10, 1, 10, 4])
    assert r.m.tolist() == [1, 4, 10]
    assert r.m.dtype == np.int64


# --- even-only factors and the Theo τ convention (select_m) ------------------------------


def _select(**kw):
    args = dict(
        n_points=1001, rate=1.0, taus="octave", m=None, points_per_decade=10,
        m_min=2, m_max=1000, stop_ratio=1.0, even=True, tau_factor=0.75,
    )
    args.update(kw)
    return select_m("theo1", **args)


def test_even_keyword_grids():
    assert _select().tolist() == [2, 4, 8, 16, 32, 64, 128, 256, 512]
    assert _select(taus="all").tolist() == list(range(2, 1001, 2))
    assert _select(taus="decade").tolist() == [2, 4, 10, 20, 40, 100, 200, 400, 1000]
    assert np.all(_select(taus="log") % 2 == 0)


def test_even_explicit_taus():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        # τ = 0.75·m·τ0
        assert _select(taus=[7.5, 75.0]).tolist() == [10, 100]
    with pytest.warns(RangeWarning, match=r"multiples of 1\.5·τ0"):
        assert _select(taus=[8.0]).tolist() == [10]


def test_even_explicit_m():
    assert _select(m=[2, 10]).tolist() == [2, 10]
    with pytest.raises(ParameterError, match=r"even.*m=\[3\]"):
        _select(m=[2, 3])
    with pytest.raises(ParameterError, match=r"m=\[1002\]"):
        _select(m=[1002])
