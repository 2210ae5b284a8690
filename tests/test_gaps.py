"""Missing samples (NaN gaps) in every statistic (sigmatau.core.gaps).

Each statistic with gaps must equal its plain definition restricted to the terms whose
samples are all present. The oracles here never call the gap code:

* window statistics (a term reads every sample of a window): the statistic of the window
  alone has exactly one term, so the result is the mean (MTIE: the largest) of the
  single-window results over the windows free of gaps;
* point statistics on phase (OADEV, OHDEV, ADEV, HDEV, TIE rms, TOTDEV, STDEV, OSTDEV):
  the terms written out point by point, NaN propagating.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

import sigmatau
from sigmatau import DataError
from sigmatau.confidence import edf as edf_of
from sigmatau.noise.generate import power_law_noise

RTOL = 1e-12
GRADEV_DIR = Path(__file__).resolve().parents[2] / "shared" / "refdata" / "allantools" / "tests" / "gradev"


def _quiet(f, *args, **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", sigmatau.SigmaTauWarning)
        return f(*args, **kwargs)


def _with_gaps(x, rng, count, burst=False):
    out = np.array(x, dtype=float)
    if burst:
        start = rng.integers(5, x.size - count - 5)
        out[start:start + count] = np.nan
    else:
        out[rng.choice(x.size, count, replace=False)] = np.nan
    return out


# --- window statistics: the mean of single-window results -----------------------------------

#: statistic -> phase points its window spans at factor m
WINDOW = {
    "mdev": lambda m: 3 * m, "tdev": lambda m: 3 * m, "mtotdev": lambda m: 3 * m,
    "ttotdev": lambda m: 3 * m, "htotdev": lambda m: 3 * m + 1, "theo1": lambda m: m + 1,
    "mtie": lambda m: m + 1,
    "mhdev": lambda m: 4 * m, "ldev": lambda m: 4 * m, "mhtotdev": lambda m: 4 * m,
    # PVAR's terms read 2m frequency samples (SigmaTheta's N − 2m terms), 2m + 1 phase points
    "pdev": lambda m: 2 * m + 1,
}
#: on frequency data every statistic's term reads a whole window of samples
FREQ_WINDOW = dict(WINDOW, oadev=lambda m: 2 * m + 1, ohdev=lambda m: 3 * m + 1, tierms=lambda m: m + 1)


def _window_oracle(name, data, data_type, m, points):
    span = points(m) - (1 if data_type == "freq" else 0)  # samples a window reads
    windows = [data[i:i + span] for i in range(data.size - span + 1)]
    windows = [w for w in windows if not np.isnan(w).any()]
    if name in ("mtie", "tierms"):
        # MTIE and TIE rms need 3 points as a record, so their windows are written out
        phases = [w if data_type == "phase" else np.concatenate(([0.0], np.cumsum(w))) for w in windows]
        if name == "mtie":
            return max(float(np.ptp(p)) ** 2 for p in phases), len(windows)
        return float(np.mean([(p[-1] - p[0]) ** 2 for p in phases])), len(windows)
    f = getattr(sigmatau, name)
    values = []
    for w in windows:
        r = _quiet(f, w, data_type=data_type, m=[m], ci=None)
        assert r.n[0] >= 1
        values.append(r.var[0])
    return float(np.mean(values)), len(windows)


@pytest.mark.slow
@pytest.mark.parametrize("data_type", ["freq", "phase"])
@pytest.mark.parametrize("name", sorted(FREQ_WINDOW))
def test_window_statistics_equal_the_mean_over_gap_free_windows(name, data_type):
    if data_type == "phase" and name not in WINDOW:
        pytest.skip("a point statistic on phase data (test below)")
    rng = np.random.default_rng(7)
    x = _with_gaps(rng.standard_normal(160).cumsum() if data_type == "phase" else rng.standard_normal(160), rng, 9)
    x = _with_gaps(x, rng, 6, burst=True)
    points = FREQ_WINDOW[name] if data_type == "freq" else WINDOW[name]
    ms = [2, 4, 6] if name == "theo1" else [1, 2, 3, 5]
    got = _quiet(getattr(sigmatau, name), x, data_type=data_type, m=ms, ci=None)
    assert got.n_missing == int(np.isnan(x).sum())
    for m, var in zip(got.m.tolist(), got.var):
        want, windows = _window_oracle(name, x, data_type, m, points)
        np.testing.assert_allclose(var, want, rtol=1e-10, err_msg=f"{name} m={m}")
        if name == "theo1":
            assert got.n[list(got.m).index(m)] == windows * m // 2
        elif name != "mtie":
            assert got.n[list(got.m).index(m)] == windows


# --- point statistics on phase: terms written out ------------------------------------------


def _point_terms(x, m, coeffs, blocks):
    if blocks:
        x = x[: ((x.size - 1) // m) * m + 1: m]
        m = 1
    k = x.size - (len(coeffs) - 1) * m
    return np.array([sum(c * x[i + j * m] for j, c in enumerate(coeffs)) for i in range(k)])


POINT = {
    "oadev": ((1, -2, 1), False, 2.0), "adev": ((1, -2, 1), True, 2.0),
    "ohdev": ((1, -3, 3, -1), False, 6.0), "hdev": ((1, -3, 3, -1), True, 6.0),
}


@pytest.mark.parametrize("name", sorted(POINT))
def test_point_statistics_on_phase_use_terms_whose_points_are_present(name):
    coeffs, blocks, scale = POINT[name]
    rng = np.random.default_rng(11)
    x = _with_gaps(rng.standard_normal(300).cumsum(), rng, 40)
    got = _quiet(getattr(sigmatau, name), x, data_type="phase", rate=2.0, m=[1, 2, 3, 7, 20], ci=None)
    for m, var, n in zip(got.m.tolist(), got.var, got.n):
        t = _point_terms(x, m, coeffs, blocks)
        t = t[np.isfinite(t)]
        assert n == t.size
        np.testing.assert_allclose(var, np.sum(t ** 2) / (scale * (m * 0.5) ** 2 * t.size), rtol=RTOL)


def test_tierms_stdev_ostdev_on_phase_with_gaps():
    rng = np.random.default_rng(12)
    x = _with_gaps(rng.standard_normal(200).cumsum(), rng, 25)
    for m in (1, 3, 8):
        d = x[m:] - x[:-m]
        d = d[np.isfinite(d)]
        np.testing.assert_allclose(_quiet(sigmatau.tierms, x, data_type="phase", m=[m]).var[0], np.mean(d ** 2), rtol=RTOL)
        np.testing.assert_allclose(_quiet(sigmatau.ostdev, x, data_type="phase", m=[m], ci=None).var[0],
                                   np.var(d, ddof=1) / m ** 2, rtol=RTOL)
        xs = x[: ((x.size - 1) // m) * m + 1: m]
        b = np.diff(xs)
        b = b[np.isfinite(b)]
        np.testing.assert_allclose(_quiet(sigmatau.stdev, x, data_type="phase", m=[m], ci=None).var[0],
                                   np.var(b, ddof=1) / m ** 2, rtol=RTOL)


def test_nonoverlapped_statistics_keep_their_block_grid_on_frequency_data():
    # ADEV, HDEV and STDEV on frequency data: blocks of m samples from the record's start; a
    # block holding a gap is missing, and so is every term that reads it.
    rng = np.random.default_rng(13)
    y = _with_gaps(rng.standard_normal(400), rng, 30)
    for m in (1, 2, 5, 9):
        b = np.array([y[k * m:(k + 1) * m].mean() for k in range(y.size // m)])
        a = b[1:] - b[:-1]
        h = b[2:] - 2 * b[1:-1] + b[:-2]
        a, h, bb = a[np.isfinite(a)], h[np.isfinite(h)], b[np.isfinite(b)]
        r = _quiet(sigmatau.adev, y, m=[m], ci=None)
        np.testing.assert_allclose(r.var[0], np.mean(a ** 2) / 2, rtol=1e-11)
        assert r.n[0] == a.size
        np.testing.assert_allclose(_quiet(sigmatau.hdev, y, m=[m], ci=None).var[0], np.mean(h ** 2) / 6, rtol=1e-11)
        np.testing.assert_allclose(_quiet(sigmatau.stdev, y, m=[m], ci=None).var[0], np.var(bb, ddof=1), rtol=1e-11)


def test_ostdev_on_frequency_data_uses_gap_free_windows():
    rng = np.random.default_rng(14)
    y = _with_gaps(rng.standard_normal(300), rng, 20)
    for m in (1, 4, 10):
        w = np.array([y[i:i + m].mean() for i in range(y.size - m + 1)])
        w = w[np.isfinite(w)]
        np.testing.assert_allclose(_quiet(sigmatau.ostdev, y, m=[m], ci=None).var[0], np.var(w, ddof=1), rtol=1e-11)


def test_totdev_on_phase_extends_the_record_at_its_ends():
    rng = np.random.default_rng(15)
    x = _with_gaps(rng.standard_normal(120).cumsum(), rng, 12)
    N = x.size
    for m in (1, 3, 10, 50):
        def xstar(j):
            if j < 0:
                return 2 * x[0] - x[-j]
            if j >= N:
                return 2 * x[-1] - x[2 * N - 2 - j]
            return x[j]
        t = np.array([xstar(i - m) - 2 * xstar(i) + xstar(i + m) for i in range(1, N - 1)])
        t = t[np.isfinite(t)]
        r = _quiet(sigmatau.totdev, x, data_type="phase", m=[m], ci=None)
        np.testing.assert_allclose(r.var[0], np.sum(t ** 2) / (2 * m ** 2 * t.size), rtol=RTOL)
        assert r.n[0] == t.size


def test_totdev_on_frequency_data_pools_the_runs():
    # Frequency data: the phase after a gap is unknown, so each gap-free run is a record of its
    # own, extended at its own ends.
    rng = np.random.default_rng(16)
    y = rng.standard_normal(300)
    y[[40, 41, 150]] = np.nan
    runs = [y[:40], y[42:150], y[151:]]
    for m in (1, 4, 12):
        parts = [_quiet(sigmatau.totdev, r, m=[m], ci=None) for r in runs]
        total = sum(p.var[0] * p.n[0] for p in parts)
        count = sum(p.n[0] for p in parts)
        r = _quiet(sigmatau.totdev, y, m=[m], ci=None)
        np.testing.assert_allclose(r.var[0], total / count, rtol=RTOL)
        assert r.n[0] == count


# --- against allantools' gap-resistant ADEV -------------------------------------------------


@pytest.mark.skipif(not GRADEV_DIR.is_dir(), reason="../shared/refdata not present")
def test_oadev_with_gaps_equals_allantools_gradev():
    allantools = pytest.importorskip("allantools")
    y_gap = np.loadtxt(GRADEV_DIR / "y_gap.dat")  # 1000 phase points, 200 NaN
    assert np.isnan(y_gap).sum() == 200
    ours = sigmatau.oadev(y_gap, data_type="phase", taus="all", ci=None)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        taus, dev, _, ns = allantools.gradev(y_gap, data_type="phase", rate=1.0, taus=ours.taus)
    common = np.isin(ours.taus, taus)
    assert common.sum() >= 200
    idx = np.searchsorted(taus, ours.taus[common])
    np.testing.assert_allclose(ours.dev[common], dev[idx], rtol=1e-12)
    np.testing.assert_array_equal(ours.n[common], ns[idx])


@pytest.mark.skipif(not GRADEV_DIR.is_dir(), reason="../shared/refdata not present")
def test_gapped_record_stays_within_the_complete_records_interval():
    # y_gap is y with a burst of 200 of its 1000 phase points removed. Where the gapped record
    # keeps at least half of the complete record's terms, its estimate lies inside the complete
    # record's 95 % interval; wherever both have an interval, the two intervals overlap. (With
    # fewer terms left the two estimates share little and may differ by more: MDEV at m = 128
    # keeps 34 of 617 terms, EDF 1.4, and lies below the complete record's interval.)
    y = np.loadtxt(GRADEV_DIR / "y.dat")
    y_gap = np.loadtxt(GRADEV_DIR / "y_gap.dat")
    checked = 0
    for name in ("oadev", "mdev", "ohdev", "totdev", "theoh"):
        full = _quiet(getattr(sigmatau, name), y, data_type="phase", confidence=0.95)
        gap = _quiet(getattr(sigmatau, name), y_gap, data_type="phase", confidence=0.95)
        for j, tau in enumerate(gap.taus):
            i = np.flatnonzero(np.isclose(full.taus, tau))
            if i.size == 0 or not (np.isfinite(full.ci_low[i[0]]) and np.isfinite(gap.ci_low[j])):
                continue
            i = i[0]
            assert gap.ci_low[j] <= full.ci_high[i] and full.ci_low[i] <= gap.ci_high[j], (name, tau)
            if gap.n[j] >= full.n[i] / 2:
                assert full.ci_low[i] <= gap.dev[j] <= full.ci_high[i], (name, tau)
                checked += 1
    assert checked >= 25


# --- EDF, noise type and intervals from the terms used --------------------------------------


def test_edf_is_that_of_the_equivalent_contiguous_record():
    rng = np.random.default_rng(3)
    y = _with_gaps(rng.standard_normal(5000), rng, 10, burst=True)
    y = _with_gaps(y, rng, 40)
    r = sigmatau.oadev(y, alpha=0)
    assert r.n_effective is not None and r.n_missing == 50
    for m, n, neq, nu in zip(r.m, r.n, r.n_effective, r.edf):
        assert neq == n + 2 * m  # OADEV on frequency samples: N − 2m + 1 terms from N − 1 samples... in phase points
        assert nu == pytest.approx(edf_of("oadev", 0, int(m), int(neq)), rel=1e-12)


@pytest.mark.parametrize("alpha", [2, 1, 0, -1, -2])
def test_noise_identification_tolerates_gaps(alpha):
    # The same record with 2 % of its samples missing (scattered and a burst) is identified as
    # the complete one at every τ where the lag-1 method applies to both.
    rng = np.random.default_rng(100 + alpha)
    y = power_law_noise(2 ** 14, alpha=alpha, rng=rng)
    gapped = _with_gaps(_with_gaps(y, rng, 100), rng, 200, burst=True)
    ms = [1, 4, 16, 64]
    full = sigmatau.identify(y, ms, data_type="freq")
    part = sigmatau.identify(gapped, ms, data_type="freq")
    both = [i for i in range(len(ms)) if full.method[i] == part.method[i] == "lag1"]
    assert len(both) >= 3
    assert [part.alpha[i] for i in both] == [full.alpha[i] for i in both]
    assert part.alpha.tolist() == full.alpha.tolist() or alpha in (1, 2)


@pytest.mark.slow
def test_interval_coverage_with_gaps_on_the_default_path():
    # White FM with 5 % of the samples missing (scattered and one burst), noise type identified
    # (not forced): the 68.3 % interval of OADEV must cover the true σ_y(τ) = 1/√m at about
    # its rate. Bound: ±3 binomial standard deviations over 400 records.
    trials, hits = 400, {1: 0, 8: 0, 64: 0}
    rng = np.random.default_rng(2024)
    for _ in range(trials):
        y = _with_gaps(_with_gaps(rng.standard_normal(4096), rng, 20), rng, 100, burst=True)
        r = sigmatau.oadev(y, m=list(hits))
        for m, lo, hi in zip(r.m.tolist(), r.ci_low, r.ci_high):
            hits[m] += lo <= 1.0 / np.sqrt(m) <= hi
    p = 0.6827
    tol = 3 * np.sqrt(p * (1 - p) / trials)
    for m, h in hits.items():
        assert abs(h / trials - p) < tol, (m, h / trials)


# --- input -----------------------------------------------------------------------------------


def test_masked_values_and_nan_are_the_same_gap():
    rng = np.random.default_rng(5)
    y = rng.standard_normal(500)
    mask = np.zeros(500, bool)
    mask[[3, 100, 101, 402]] = True
    a = sigmatau.mdev(np.ma.masked_array(y, mask=mask))
    b = sigmatau.mdev(np.where(mask, np.nan, y))
    np.testing.assert_array_equal(a.dev, b.dev)
    np.testing.assert_array_equal(a.ci_high, b.ci_high)


def test_input_never_modified_and_complete_records_unchanged():
    rng = np.random.default_rng(6)
    y = rng.standard_normal(1000)
    before = sigmatau.oadev(y)
    g = y.copy()
    g[10] = np.nan
    keep = g.copy()
    sigmatau.theoh(g)
    np.testing.assert_array_equal(g, keep)
    after = sigmatau.oadev(y)
    np.testing.assert_array_equal(before.dev, after.dev)
    assert before.n_missing == 0 and before.n_effective is None


def test_factors_without_a_gap_free_term_are_left_out():
    y = np.random.default_rng(8).standard_normal(100)
    y[::10] = np.nan  # runs of 9 samples: OADEV terms up to m = 4 only
    r = sigmatau.oadev(y, taus="all", ci=None)
    assert r.m.max() == 4
    with pytest.warns(sigmatau.RangeWarning, match=r"no gap-free term at m=\[10\]"):
        sigmatau.oadev(y, m=[2, 10], ci=None)


@pytest.mark.parametrize("name", ["oadev", "mdev", "totdev", "theoh"])
def test_no_gap_free_stretch_is_one_clear_line(name):
    y = np.ones(200)
    y[::2] = np.nan
    with pytest.raises(DataError, match="gap") as exc_info:
        _quiet(getattr(sigmatau, name), y + np.arange(200) * 1e-3)
    assert "\n" not in str(exc_info.value)
