"""Dynamic stability (sigmatau.stats.dynamic) and its heat-map figure (sigmatau.report.dynamicfig).

- Every cell is the statistic of its window alone: the per-window path equals the public function
  on the slice, the cumulative OADEV path equals the per-window path (1e-12 relative: only the
  order of the sums differs), and one cell equals the filter-chain definition.
- The stationarity flag: its false-alarm rate on stationary noise, over many seeds, stays within
  the binomial bound of its nominal level; a noise level that doubles halfway is flagged and
  located at the change.
- Bad input gets one-line errors; the result is frozen and JSON-safe; the figure draws on Agg.
"""

from __future__ import annotations

import dataclasses
import json
import math
import warnings

import contextlib

import numpy as np
import pytest
from scipy.stats import binom

import sigmatau
from sigmatau.errors import DataError, ParameterError
from sigmatau.filterchain import oavar
from sigmatau.stats.dynamic import DynamicResult, StationarityCheck, dynamic

# Relative agreement of two paths that sum the same squares in another order (observed ≈ 4e-15).
RTOL_PATHS = 1e-12


def _noise(n, kind, seed, rate=1.0):
    return sigmatau.power_law_noise(n, kind, rng=seed, rate=rate)


def _assert_same(a: DynamicResult, b: DynamicResult) -> None:
    np.testing.assert_allclose(a.dev, b.dev, rtol=RTOL_PATHS, atol=0.0)
    for name in ("ci_low", "ci_high"):
        np.testing.assert_allclose(getattr(a, name), getattr(b, name), rtol=RTOL_PATHS, atol=0.0, equal_nan=True)
    for name in ("n", "alpha", "edf", "taus", "m", "start", "centre"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))


# ------------------------------------------------------------------ the cells are per-window statistics


@pytest.mark.parametrize("statistic, data_type", [("oadev", "freq"), ("mdev", "freq"), ("ohdev", "phase"),
                                                  ("totdev", "freq")])
def test_each_cell_is_the_statistic_of_its_window(statistic, data_type):
    y = _noise(3000, "ffm", 1, rate=10.0)
    r = dynamic(y, rate=10.0, window=1000, step=400, statistic=statistic, data_type=data_type, method="windows")
    func = sigmatau.stats.FUNCTIONS[statistic]
    assert r.dev.shape == (6, r.taus.size) and r.method == "windows"
    for j, s in enumerate(range(0, 2001, 400)):
        plain = func(y[s : s + 1000], rate=10.0, data_type=data_type)
        np.testing.assert_array_equal(plain.m, r.m)
        np.testing.assert_allclose(r.dev[j], plain.dev, rtol=RTOL_PATHS, atol=0.0)
        np.testing.assert_allclose(r.ci_high[j], plain.ci_high, rtol=RTOL_PATHS, atol=0.0, equal_nan=True)
        np.testing.assert_array_equal(r.edf[j], plain.edf)
        np.testing.assert_array_equal(r.alpha[j], plain.alpha)
        np.testing.assert_array_equal(r.n[j], plain.n)


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["wpm", "fpm", "wfm", "ffm", "rwfm"])
@pytest.mark.parametrize("window, step", [(1500, 350), (1500, 1500), (1000, 2000), (600, 1)])
def test_cumulative_oadev_equals_the_per_window_path(kind, window, step):
    y = _noise(4000, kind, 7) * 1e-3 + 0.25  # an offset, as a sensor bias
    ci = None if step == 1 else "chi2"  # 3401 windows: the noise identification is not what is tested
    fast = dynamic(y, rate=100.0, window=window, step=step, method="cumulative", ci=ci)
    slow = dynamic(y, rate=100.0, window=window, step=step, method="windows", ci=ci)
    assert fast.method == "cumulative" and slow.method == "windows"
    _assert_same(fast, slow)


def test_a_quiet_window_after_a_loud_one_keeps_its_digits(rng):
    # Running sums over the record would leave the quiet windows' sums as the difference of two
    # numbers 1e12 times larger; the block-wise sums of squares do not.
    y = np.concatenate([1e6 * rng.normal(size=3000), rng.normal(size=3000)])
    fast = dynamic(y, window=1000, step=250, method="cumulative", ci=None)
    slow = dynamic(y, window=1000, step=250, method="windows", ci=None)
    _assert_same(fast, slow)
    assert fast.stationarity.flagged and fast.stationarity.change_time == 3000.0


def test_integer_counts_beyond_float_precision_and_column_vectors(rng):
    # Raw counts near 2**60: both paths take them exactly relative to a first value.
    y = (2**60 + np.cumsum(rng.integers(-1000, 1000, size=5000))).astype(np.int64)
    _assert_same(dynamic(y, window=1000, step=300, method="cumulative"),
                 dynamic(y, window=1000, step=300, method="windows"))
    z = rng.normal(size=1200)
    _assert_same(dynamic(z[:, None], window=300, step=300), dynamic(list(z), window=300, step=300))


def test_auto_takes_the_cumulative_path_for_oadev_on_frequency_data_only(rng):
    y = rng.normal(size=2000)
    assert dynamic(y, window=500, step=250).method == "cumulative"
    assert dynamic(y, window=500, step=250, data_type="phase").method == "windows"
    assert dynamic(y, window=500, step=250, statistic="adev").method == "windows"


def test_a_cell_equals_the_filter_chain_definition(rng):
    y = rng.normal(size=2000)
    r = dynamic(y, rate=4.0, window=800, step=300)
    for j, s in ((0, 0), (2, 600), (r.n_windows - 1, 300 * (r.n_windows - 1))):
        for i, m in enumerate(r.m):
            # The oracle forms each average on its own: 1e-10 covers its longer sums.
            assert r.dev[j, i] ** 2 == pytest.approx(oavar(y[s : s + 800], int(m), rate=4.0), rel=1e-10)


def test_times_grid_and_window_units():
    y = _noise(6000, "wfm", 3, rate=50.0)
    r = dynamic(y, rate=50.0, window=20.0, step=5.0, window_unit="seconds")
    same = dynamic(y, rate=50.0, window=1000, step=250)
    _assert_same(r, same)
    assert (r.window, r.step, r.n_windows) == (1000, 250, 21)
    np.testing.assert_allclose(r.start, np.arange(21) * 5.0)
    np.testing.assert_allclose(r.centre, r.start + 10.0)  # 1000 frequency samples span 20 s
    single = sigmatau.oadev(y[:1000], rate=50.0)
    np.testing.assert_array_equal(r.m, single.m)  # the grid of one window's length
    phase = dynamic(np.cumsum(y) / 50.0, rate=50.0, window=1001, step=250, data_type="phase")
    np.testing.assert_allclose(phase.centre, phase.start + 10.0)  # 1001 phase points span 20 s


# --------------------------------------------------------------------------------- stationarity

#: The flag's test at this level in the Monte-Carlo checks: a higher level than the default
#: (0.01) counts more false alarms, which makes the measured rate a sharper check.
LEVEL = 0.05


def _false_alarms(kind: str, trials: int, seed0: int) -> int:
    return sum(dynamic(_noise(4000, kind, seed0 + s), window=500, step=250, significance=LEVEL)
               .stationarity.flagged for s in range(trials))


def _binomial_bound(trials: int) -> int:
    """Most false alarms a test at level LEVEL gives in ``trials`` runs but once in a thousand."""
    return int(binom.ppf(0.999, trials, LEVEL))


@pytest.mark.slow
def test_stationary_white_noise_is_not_flagged_beyond_the_nominal_rate():
    trials = 150
    alarms = _false_alarms("wfm", trials, 1000)
    assert alarms <= _binomial_bound(trials), f"{alarms} false alarms in {trials} runs at level {LEVEL}"


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["wpm", "fpm", "wfm", "ffm", "rwfm"])
def test_false_alarm_rate_of_every_stationary_noise_type(kind):
    trials = 400
    alarms = _false_alarms(kind, trials, 5000)
    assert alarms <= _binomial_bound(trials), f"{kind}: {alarms} false alarms in {trials} runs at level {LEVEL}"


def test_a_stationary_record_passes_with_a_readable_finding(rng):
    r = dynamic(rng.normal(size=6000), rate=10.0, window=1000, step=500)
    st = r.stationarity
    assert st.tested and not st.flagged and st.change_time is None
    assert not st.disagree.any() and st.disagree.shape == r.dev.shape
    np.testing.assert_array_equal(st.test_windows, np.arange(0, r.n_windows, 2))
    assert "no disagreement" in st.finding and "6 non-overlapping windows" in st.finding
    assert np.all(st.alpha == 0.0)  # white FM, identified on the whole record


@pytest.mark.parametrize("kind", ["wfm", "ffm", "wpm"])
def test_a_noise_level_that_doubles_halfway_is_flagged_and_located(kind):
    y = _noise(8000, kind, 11, rate=20.0)
    y[4000:] *= 2.0
    r = dynamic(y, rate=20.0, window=1000, step=250)
    st = r.stationarity
    assert st.flagged
    assert abs(st.change_time - 200.0) <= 12.5  # sample 4000 at 20 Hz, to one step
    assert f"change of level fits best at t ≈ {st.change_time:.6g} s" in st.finding
    before = r.centre < 200.0 - 25.0
    after = r.centre > 200.0 + 25.0
    hit = st.disagree.any(axis=1)
    assert hit[before].mean() > 0.5 and hit[after].mean() > 0.5
    ratio = np.median(r.dev[after][:, 0]) / np.median(r.dev[before][:, 0])
    assert ratio == pytest.approx(2.0, rel=0.1)


def test_detection_power_for_a_doubling_over_seeds():
    found = [dynamic(np.concatenate([_noise(2000, "wfm", s), 2.0 * _noise(2000, "wfm", 100 + s)]),
                     window=500, step=250).stationarity for s in range(20)]
    assert all(st.flagged for st in found)
    assert all(abs(st.change_time - 2000.0) <= 250.0 for st in found)


def test_a_forced_noise_type_is_used_as_given(rng):
    r = dynamic(rng.normal(size=4000), window=500, step=500, alpha=0)
    assert np.all(r.stationarity.alpha == 0.0) and np.all(r.alpha == 0.0)
    expected = [sigmatau.edf("oadev", 0, int(m), 501) for m in r.m]
    np.testing.assert_allclose(r.stationarity.edf, expected, rtol=0, atol=0)


def test_stationarity_is_not_tested_without_two_separate_windows(rng):
    y = rng.normal(size=1000)
    one = dynamic(y, window=1000, step=10)
    assert one.n_windows == 1 and not one.stationarity.tested and not one.stationarity.flagged
    assert one.stationarity.finding.startswith("not tested: 1 window(s)")
    overlapping = dynamic(y, window=600, step=100)  # every window overlaps the first
    assert not overlapping.stationarity.tested
    tie = dynamic(y, window=250, step=250, statistic="mtie")
    assert not tie.stationarity.tested and "not tested" in tie.stationarity.finding


# ------------------------------------------------------------------------------------- bad input


@pytest.mark.parametrize("kwargs, error, match", [
    (dict(window=5000, step=10), ParameterError, r"window=5000 samples is longer than the record \(1000"),
    (dict(window=100, step=0), ParameterError, r"step=0 must be positive"),
    (dict(window=100, step=2.5), ParameterError, r"step=2.5 must be a whole number of samples; for seconds"),
    (dict(window=100, step=0.5), ParameterError, r"step=0.5 is less than one sample; step must be ≥ 1"),
    (dict(window=1.0, step=0.001, window_unit="seconds"), ParameterError, r"step=0.001 is less than one sample"),
    (dict(window=1, step=1), ParameterError, r"window=1 samples is too short for oadev"),
    (dict(window=2, step=1, statistic="theoh"), ParameterError, r"window=2 samples is too short"),
    (dict(window=100, step=10, statistic="allan"), ParameterError, r"statistic='allan' must be one of stdev,"),
    (dict(window=100, step=10, window_unit="minutes"), ParameterError, r"window_unit='minutes'"),
    (dict(window=100, step=10, significance=1.5), ParameterError, r"significance=1.5 must be a number in \(0, 1\)"),
    (dict(window=100, step=10, method="fast"), ParameterError, r"method='fast' must be one of"),
    (dict(window=100, step=10, statistic="mdev", method="cumulative"), ParameterError,
     r"method='cumulative' computes oadev on frequency data only"),
    (dict(window=100, step=10, rate=-1.0), ParameterError, r"rate"),
    (dict(window=True, step=10), ParameterError, r"window=True must be a number of samples"),
])
def test_bad_input_gets_one_clear_line(kwargs, error, match):
    y = np.random.default_rng(0).normal(size=1000)
    with pytest.raises(error, match=match) as info:
        dynamic(y, **kwargs)
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("data, match", [([], "empty"), ([[1.0, 2.0], [3.0, 4.0]], "1-D"),
                                         ([1.0, float("inf")] * 50, "infinite"),
                                         ([float("nan")] * 100, "every one of its 100 samples is missing")])
def test_bad_data_is_a_data_error(data, match):
    with pytest.raises(DataError, match=match) as info:
        dynamic(data, window=10, step=5)
    assert "\n" not in str(info.value)


# ---------------------------------------------------------------------------------------- result


def test_result_is_frozen_and_json_safe(rng):
    r = dynamic(rng.normal(size=3000), rate=2.0, window=600, step=300)
    with pytest.raises(dataclasses.FrozenInstanceError):
        r.window = 3  # type: ignore[misc]
    with pytest.raises(ValueError):
        r.dev[0, 0] = 1.0
    with pytest.raises(ValueError):
        r.stationarity.disagree[0, 0] = True
    d = r.to_dict()
    text = json.dumps(d, allow_nan=False)  # NaN would be invalid JSON
    back = json.loads(text)
    assert back["statistic"] == "oadev" and len(back["dev"]) == r.n_windows
    assert back["stationarity"]["flagged"] is False
    assert back["stationarity"]["change_time"] is None
    # cells without an interval are None, not NaN
    nan_cells = ~np.isfinite(r.ci_low)
    if nan_cells.any():
        j, i = np.argwhere(nan_cells)[0]
        assert back["ci_low"][j][i] is None
    assert "DynamicResult(oadev, 9 windows of 300 s every 150 s" in repr(r)
    assert isinstance(r.stationarity, StationarityCheck) and "no disagreement" in repr(r.stationarity)
    np.testing.assert_allclose(r.var, r.dev**2)


def test_no_interval_still_tests_stationarity(rng):
    y = rng.normal(size=4000)
    y[2000:] *= 2.0
    r = dynamic(y, window=500, step=500, ci=None)
    assert np.isnan(r.edf).all() and np.isnan(r.ci_low).all()
    assert r.stationarity.flagged and r.stationarity.change_time == 2000.0  # step = window: to one window
    assert json.loads(json.dumps(r.to_dict(), allow_nan=False))["edf"][0][0] is None


# ---------------------------------------------------------------------------------------- figure


def test_the_heat_map_draws_without_warnings(tmp_path):
    pytest.importorskip("matplotlib")
    from sigmatau.report.dynamicfig import dynamic_figure
    from sigmatau.report.plots import save_figure

    y = _noise(8000, "wfm", 5, rate=100.0)
    y[4000:] *= 2.0
    r = dynamic(y, rate=100.0, window=1000, step=250)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # as the suite's configuration, also when run alone
        fig = dynamic_figure(r, unit="deg/s")
        fig.canvas.draw()
    ax = fig.axes[0]
    gids = {a.get_gid() for a in ax.get_children()}
    assert {"dynamic-heatmap", "dynamic-disagree", "dynamic-change"} <= gids
    assert ax.get_yscale() == "log"
    assert ax.get_xlabel() == "window centre [s]"
    assert "OADEV" in fig.axes[1].get_ylabel()  # the colour bar
    assert fig.axes[0].collections[0].norm.__class__.__name__ == "LogNorm"
    paths = save_figure(fig, tmp_path / "dyn", formats=("png", "svg"))
    assert all(p.stat().st_size > 1000 for p in paths)


def test_the_heat_map_draws_into_given_axes_and_refuses_other_objects(rng):
    pytest.importorskip("matplotlib")
    from sigmatau.report.dynamicfig import dynamic_figure
    from sigmatau.report.figbase import new_figure

    r = dynamic(rng.normal(size=2000), window=2000, step=1)  # one window
    fig = new_figure((5.0, 3.0))
    ax = fig.subplots()
    assert dynamic_figure(r, ax, title="one window", mark=False) is fig
    assert ax.get_title() == "one window"
    fig.canvas.draw()
    tdev = dynamic(rng.normal(size=3000), window=1000, step=1000, statistic="tdev")
    bar = dynamic_figure(tdev, unit="rad/s").axes[1]
    assert bar.get_ylabel() == "TDEV [rad/s·s]"  # as the σ–τ figure labels its right axis
    flat = dynamic(np.tile([1.0, -1.0], 500), window=500, step=250)  # one deviation everywhere
    dynamic_figure(flat).canvas.draw()
    with pytest.raises(ParameterError, match="must be a DynamicResult"):
        dynamic_figure(sigmatau.oadev(rng.normal(size=100)))
    assert math.isfinite(float(r.dev[0, 0]))


def test_gaps_leave_empty_cells_and_every_other_cell_is_the_windows_statistic():
    # NaN marks missing samples: each window is the statistic of its own samples (gaps skipped
    # as everywhere); a window of nothing but gaps, or a factor without a gap-free term, is an
    # empty cell (NaN, n = 0), and the stationarity test leaves it out.
    rng = np.random.default_rng(41)
    y = rng.standard_normal(12_000)
    y[rng.choice(y.size, 40, replace=False)] = np.nan
    y[5_000:7_000] = np.nan
    r = dynamic(y, rate=10.0, window=2_000, step=1_000)
    assert r.method == "windows"
    empty = np.flatnonzero(np.all(r.n == 0, axis=1))
    assert empty.tolist() == [5]  # samples 5000–6999: all missing
    assert np.isnan(r.dev[5]).all()
    for i in (0, 4, 8):
        with pytest.warns(sigmatau.RangeWarning) if i == 4 else contextlib.nullcontext():
            want = sigmatau.oadev(y[i * 1_000: i * 1_000 + 2_000], rate=10.0, m=r.m)
        cols = np.searchsorted(r.m, want.m)
        np.testing.assert_allclose(r.dev[i, cols], want.dev, rtol=1e-12)
        np.testing.assert_array_equal(r.n[i, cols], want.n)
        assert (r.n[i] > 0).sum() == want.m.size
    assert r.stationarity.tested and not r.stationarity.flagged
