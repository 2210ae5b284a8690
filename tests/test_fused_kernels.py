"""The fused compiled kernels (sigmatau.core.fused, numba) against the numpy kernels they stand for.

Each compiled kernel forms every term with the numpy kernel's own floating-point operations and
differs only in the order in which the squares are summed, so the two agree far below the issue's
1e-12 relative (measured worst over the data of this file: 2.1e-14 for the phase kernels, on
random-run and flicker-walk phase, 1.9e-15 for the frequency kernels; 2.4e-15 for the public
statistics). The public statistics give the same noise types and EDF with either, and the same
intervals to 1e-12.
Skipped without numba (the extra ``fast``).
"""

from __future__ import annotations

import subprocess
import sys
import tracemalloc

import numpy as np
import pytest

pytest.importorskip("numba")

import sigmatau  # noqa: E402
from sigmatau.analysis import analyze_log, log_from_arrays  # noqa: E402
from sigmatau.core import accel, fused, kernels  # noqa: E402
from sigmatau.core.numeric import WindowSums, block_means  # noqa: E402
from sigmatau.core.shared import shared_record  # noqa: E402
from sigmatau.core.validate import to_phase  # noqa: E402
from sigmatau.stats import hadamard, total  # noqa: E402
from sigmatau.uncertainty import lag1  # noqa: E402

#: The issue's bound on the difference of every statistic from the numpy kernels.
RTOL = 1e-12
ALPHAS = (2, 1, 0, -1, -2, -3, -4)

PHASE_KERNELS = {"oavar_phase": kernels.oavar_kernel, "ohvar_phase": hadamard._ohvar_kernel,
                 "mvar_phase": kernels._mvar_kernel, "totvar_phase": total._totvar_kernel}
FREQ_KERNELS = {"oavar_freq": kernels._oavar_freq, "ohvar_freq": hadamard._ohvar_freq,
                "mvar_freq": kernels._mvar_freq, "tvar_freq": kernels._tvar_freq}
#: Largest factor of each kernel for N phase points (the Statistic's max_m).
MAX_M = {"oavar": lambda n: (n - 1) // 2, "ohvar": lambda n: (n - 1) // 3, "mvar": lambda n: n // 3,
         "tvar": lambda n: n // 3, "totvar": lambda n: n - 1}


def _noise(n, alpha, data_type, seed):
    return sigmatau.power_law_noise(n, alpha, data_type=data_type, rng=seed) * 1e-3 + 0.25


def _octaves(top):
    return 2 ** np.arange(int(np.log2(top)) + 1)


def _grids(n_points, name, dense):
    top = MAX_M[name.split("_")[0]](n_points)
    if dense:  # every factor: the window sums go through increments, doublings and restarts
        return [np.arange(1, top + 1)]
    mixed = np.unique(np.round(np.geomspace(1, top, 25)).astype(np.int64))  # a decade-like grid
    return [_octaves(top), mixed]


def _numpy(kernel, *args):
    """The numpy kernel, and numpy for any kernel it calls (TVAR calls MVAR's dispatcher)."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv(accel.ENV, "0")
        return kernel.numpy(*args)


def _assert_close(fast, slow, what):
    var_f, n_f = fast
    var_s, n_s = slow
    np.testing.assert_array_equal(n_f, n_s, err_msg=what)
    np.testing.assert_allclose(var_f, var_s, rtol=RTOL, atol=0, err_msg=what)


@pytest.fixture(autouse=True)
def _numba_on(monkeypatch):
    """The kernels called below choose by themselves; the oracle calls ``.numpy`` directly."""
    monkeypatch.setenv(accel.ENV, "1")


@pytest.mark.parametrize("alpha", ALPHAS)
@pytest.mark.parametrize("n, dense", [(1001, True), (131_075, False)])
def test_phase_kernels_match_numpy(alpha, n, dense):
    x = _noise(n, alpha, "phase", seed=abs(alpha) + n)
    for name, kernel in PHASE_KERNELS.items():
        for ms in _grids(n, name, dense):
            _assert_close(getattr(fused, name)(x, ms, 0.01), _numpy(kernel, x, ms, 0.01), f"{name} alpha={alpha}")


@pytest.mark.slow
@pytest.mark.parametrize("alpha", ALPHAS)
@pytest.mark.parametrize("n, dense", [(1000, True), (131_073, False)])
def test_frequency_kernels_match_numpy(alpha, n, dense):
    y = _noise(n, alpha, "freq", seed=abs(alpha) + n)
    mean = float(y.mean())
    centred = y - y.mean()
    for name, kernel in FREQ_KERNELS.items():
        for ms in _grids(n + 1, name, dense):
            expected = _numpy(kernel, centred, ms, 0.01)
            _assert_close(getattr(fused, name)(y, ms, 0.01, mean=mean), expected, f"{name} alpha={alpha}")
            _assert_close(getattr(fused, name)(centred, ms, 0.01), expected, f"{name} centred alpha={alpha}")


@pytest.mark.parametrize("ms", [[1, 2, 4, 8, 16, 32, 64], list(range(1, 40)), [3, 5, 6, 12, 24, 7, 100, 50, 1],
                                [96, 192, 384, 768]])
def test_window_sums_are_numpy_window_sums_bit_for_bit(ms):
    y = _noise(5000, -2, "freq", seed=3)
    mean = float(y.mean())
    ms = np.asarray(ms)
    for double in (False, True):
        ref = WindowSums(y - y.mean(), double=double)
        ws = fused._WindowSums(y, mean, double=double)
        for m in np.sort(ms).tolist():
            ref.advance(m)
            ws.advance(m)
            ws._flush()
            ws._settle_a()
            if ws.a_state == "virtual":
                ws._store_a()
                fused.nb.fill_a(ws.a, y, mean, ws.w)
                ws.a_state = "stored"
            np.testing.assert_array_equal(ws.a[:ref.a.size], ref.a, err_msg=f"A at m={m}")
            if double:
                np.testing.assert_array_equal(ws.b[:ref.b.size], ref.b, err_msg=f"B at m={m}")


@pytest.mark.parametrize("alpha", ALPHAS)
def test_lag1_and_block_means(alpha):
    y = _noise(40_001, alpha, "freq", seed=11 - alpha)
    for m in (1, 2, 3, 7, 8, 64, 129, 256, 1000):
        z = block_means(y, m)
        np.testing.assert_array_equal(fused.block_means(y, m), z)  # numpy's pairwise sums, bit for bit
        level = z
        for d in range(4):
            for acf in ("standard", "stable32"):
                assert fused.lag1_r1(z, d, acf) == pytest.approx(lag1._lag1_r1(level, acf), rel=RTOL, abs=1e-15)
            level = np.diff(level)
    assert np.isnan(fused.lag1_r1(np.ones(100), 0))  # constant: r1 undefined, as numpy raises
    for m in (1, 2, 16, 1000):  # the identification itself, fused and not
        a = lag1.lag1_of_series(y, m, data_type="freq", dmin=0, dmax=3, detrend=False, acf="standard",
                                min_points=30)
        with pytest.MonkeyPatch.context() as mp:
            mp.setenv(accel.ENV, "0")
            b = lag1.lag1_of_series(y, m, data_type="freq", dmin=0, dmax=3, detrend=False, acf="standard",
                                    min_points=30)
        assert (a.alpha, a.d, a.n) == (b.alpha, b.d, b.n)
        assert a.alpha_estimate == pytest.approx(b.alpha_estimate, rel=RTOL, abs=1e-12)


def test_block_sums_built_from_halves_in_a_scope_are_numpy_block_means():
    y = _noise(300_007, -1, "freq", seed=5)
    with shared_record(y):
        for m in _octaves(4096).tolist():
            np.testing.assert_array_equal(fused.block_means(y, m), block_means(y, m), err_msg=f"m={m}")


def test_record_scans_are_numpy_bit_for_bit(rng):
    y = rng.standard_normal(100_003) * 1e-3 + 0.02
    for ddof in (0, 1):
        assert fused.std(y, ddof) == float(y.std(ddof=ddof))
    assert fused.abs_peak(-y) == float(np.max(np.abs(y)))
    gappy = y.copy()
    gappy[[5, 17]] = np.nan
    assert fused.abs_peak(gappy) == float(np.nanmax(np.abs(gappy)))
    assert fused.all_finite(y) and not fused.all_finite(gappy) and fused.all_finite(y[::3])
    bad = y.copy()
    bad[-1] = -np.inf
    assert not fused.all_finite(bad)
    for rate in (1.0, 1000.0, 3.7):
        np.testing.assert_array_equal(fused.phase_of_freq(y, y.mean(), rate), to_phase(y - y.mean(), rate, "freq"))


STATS = ("oadev", "mdev", "tdev", "ohdev", "totdev", "theoh")


def _public(name, data, data_type):
    if name == "theoh":
        return sigmatau.theoh(data, rate=100.0, data_type=data_type, method="fast")
    return sigmatau.stats.FUNCTIONS[name](data, rate=100.0, data_type=data_type)


def _assert_same_statistic(fast, slow, what):
    np.testing.assert_array_equal(fast.m, slow.m, err_msg=what)
    np.testing.assert_array_equal(fast.n, slow.n, err_msg=what)
    np.testing.assert_array_equal(fast.alpha, slow.alpha, err_msg=what)
    np.testing.assert_array_equal(fast.edf, slow.edf, err_msg=what)
    for field in ("var", "ci_low", "ci_high"):
        np.testing.assert_allclose(getattr(fast, field), getattr(slow, field), rtol=RTOL, atol=0,
                                   err_msg=f"{what} {field}")
    # α̂ = -2(δ + d) + 2θ is of order one and passes through zero: compared in absolute terms
    # (white FM gives α̂ ≈ 1e-5 with r1's last digits the only difference)
    np.testing.assert_allclose(fast.alpha_estimate, slow.alpha_estimate, rtol=RTOL, atol=1e-12, err_msg=what)
    assert fast.ci_reason == slow.ci_reason and fast.bias == slow.bias, what


@pytest.mark.slow
@pytest.mark.filterwarnings("ignore::sigmatau.SigmaTauWarning")  # TheoH's Fast TheoBR on phase noise says so
@pytest.mark.parametrize("alpha", [2, 1, 0, -1, -2])
@pytest.mark.parametrize("data_type", ["freq", "phase"])
def test_public_statistics_identical_with_and_without_numba(alpha, data_type, monkeypatch):
    data = _noise(30_001, alpha, data_type, seed=100 + alpha)
    fast = {name: _public(name, data, data_type) for name in STATS}
    with shared_record(data):  # the main job's path: work shared between the statistics
        shared = {name: _public(name, data, data_type) for name in STATS}
    monkeypatch.setenv(accel.ENV, "0")
    for name in STATS:
        slow = _public(name, data, data_type)
        _assert_same_statistic(fast[name], slow, f"{name} alpha={alpha} {data_type}")
        _assert_same_statistic(shared[name], fast[name], f"{name} shared")
        np.testing.assert_array_equal(shared[name].var, fast[name].var)  # the scope changes no digit


def test_the_scope_shares_passes_between_statistics(monkeypatch):
    """In a shared_record scope OHDEV takes its sums from OADEV's pass, TheoH its OAVAR rows from
    TOTDEV's, and each lag-1 r1 is computed once; the results are those of the statistics alone."""
    y = _noise(60_000, -1, "freq", seed=21)
    alone = {name: _public(name, y, "freq") for name in ("ohdev", "theoh")}
    calls = {"window sums": 0, "oavar phase": 0, "lag1": 0}

    def counting(name, real):
        def f(*args, **kwargs):
            calls[name] += args[0].size > 50_000  # the record (TheoBR's κ reads a block-averaged copy)
            return real(*args, **kwargs)
        return f

    monkeypatch.setattr(fused, "_WindowSums", counting("window sums", fused._WindowSums))
    monkeypatch.setattr(fused.nb, "oavar_phase_sum", counting("oavar phase", fused.nb.oavar_phase_sum))
    monkeypatch.setattr(fused, "lag1_r1", counting("lag1", fused.lag1_r1))
    with shared_record(y):
        _public("oadev", y, "freq")
        first = dict(calls)
        shared = {name: _public(name, y, "freq") for name in ("ohdev", "totdev", "theoh")}
        _public("oadev", y, "freq")
    assert calls["window sums"] == first["window sums"] + 1  # OHDEV's pass was OADEV's; OADEV again: its own
    assert calls["oavar phase"] == 0 and first["lag1"] > 0
    assert calls["lag1"] < 3 * first["lag1"]  # the Allan-family r1 of OADEV are reused
    for name, result in alone.items():
        np.testing.assert_array_equal(shared[name].var, result.var, err_msg=name)
        np.testing.assert_array_equal(shared[name].ci_low, result.ci_low, err_msg=name)


def test_the_scope_forms_other_sums_only_for_the_statistics_it_names(monkeypatch):
    """A scope that names its statistics forms OHDEV's sums in OADEV's pass only when it names
    OHDEV, and TheoH's OAVAR rows in TOTDEV's pass only when it names TheoH (or OADEV); a
    statistic the scope did not name still gets its own pass and the same numbers."""
    y = _noise(60_000, -1, "freq", seed=22)
    alone = {name: _public(name, y, "freq") for name in ("ohdev", "theoh")}
    k2 = []
    real_terms, real_double = fused.nb.a_terms, fused.nb.a_double_terms

    def terms(a, yy, mean, m, k1, kk2, virtual):
        k2.append(kk2)
        return real_terms(a, yy, mean, m, k1, kk2, virtual)

    def double(a, yy, mean, w, virtual, k1, kk2):
        k2.append(kk2)
        return real_double(a, yy, mean, w, virtual, k1, kk2)

    monkeypatch.setattr(fused.nb, "a_terms", terms)
    monkeypatch.setattr(fused.nb, "a_double_terms", double)
    rows = {}
    real_totvar = fused.nb.totvar_sums

    def totvar(x, m, with_oavar):
        rows[names] = rows.get(names, 0) + bool(with_oavar)
        return real_totvar(x, m, with_oavar)

    monkeypatch.setattr(fused.nb, "totvar_sums", totvar)
    formed = {}
    for names in (("mdev", "oadev", "totdev"), ("oadev", "ohdev", "totdev", "theoh"), None):
        k2.clear()
        with shared_record(y, statistics=names):
            _public("oadev", y, "freq")
            formed[names] = sum(k > 0 for k in k2)
            _public("totdev", y, "freq")
            late = {name: _public(name, y, "freq") for name in ("ohdev", "theoh")}
        for name, result in alone.items():
            np.testing.assert_array_equal(late[name].var, result.var, err_msg=f"{name} {names}")
            np.testing.assert_array_equal(late[name].ci_high, result.ci_high, err_msg=f"{name} {names}")
    assert formed[("mdev", "oadev", "totdev")] == 0 and rows.get(("mdev", "oadev", "totdev"), 0) > 0
    assert formed[("oadev", "ohdev", "totdev", "theoh")] > 0 and formed[None] > 0
    assert rows[("oadev", "ohdev", "totdev", "theoh")] > 0 and rows[None] > 0


@pytest.mark.slow
def test_the_main_job_with_and_without_numba(monkeypatch):
    channels = {"gyro_x": _noise(150_000, 0, "freq", seed=1), "gyro_y": _noise(150_000, -1, "freq", seed=2)}
    log = log_from_arrays(channels, rate=200.0, units={"gyro_x": "rad/s", "gyro_y": "rad/s"})
    fast = analyze_log(log, workers=2)
    monkeypatch.setenv(accel.ENV, "0")
    slow = analyze_log(log, workers=1)
    for a, b in zip(fast.channels, slow.channels):
        assert sorted(a.results) == sorted(b.results)
        for name in a.results:
            _assert_same_statistic(a.results[name], b.results[name], f"{a.name} {name}")


def test_no_record_sized_temporaries():
    """OADEV, OHDEV, MDEV and TOTDEV hold at most the validated samples and one array of the
    record's size (A, B or the phase) at once; numpy's kernels add a mean-removed copy."""
    y = _noise(2_000_000, 0, "freq", seed=9)
    for name in ("oadev", "ohdev", "mdev", "totdev"):
        tracemalloc.start()
        sigmatau.stats.FUNCTIONS[name](y, ci=None)
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        assert peak < 2.2 * y.nbytes, (name, peak / y.nbytes)


def test_dispatch(monkeypatch):
    monkeypatch.delenv(accel.ENV)
    assert accel.fused_for(accel.FUSED_MIN_POINTS - 1) is None
    assert accel.fused_for(accel.FUSED_MIN_POINTS) is fused
    monkeypatch.setenv(accel.ENV, "0")
    assert accel.fused_for(10**9) is None
    monkeypatch.setenv(accel.ENV, "1")
    assert accel.fused_for(10) is fused
    for name, kernel in {**PHASE_KERNELS, **FREQ_KERNELS}.items():
        assert kernel.fused_name == name and callable(kernel.numpy)


def test_import_sigmatau_does_not_import_numba(monkeypatch):
    monkeypatch.delenv(accel.ENV)  # the default: a small record goes to numpy, numba is never imported
    code = "import sys, sigmatau; sigmatau.oadev([1.0, 2.0, 4.0, 3.0, 5.0]); print('numba' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"
