"""Data checks that change the noise figures: quantisation, decimation, saturation, stuck values.

Each check is exercised on simulated data with a known defect and on clean data,
which must stay silent. The decimation case simulates a 1600 Hz white stream
logged at 200 Hz by keeping every 8th sample versus averaging blocks of 8
(reference: /work/shared/reference/imu-noise-model.md, "Kalibr / VIO conventions":
decimating by k without averaging inflates the apparent N by √k).
"""

from __future__ import annotations

import json
import math
import warnings

import numpy as np
import pytest

from sigmatau.checks import (
    AliasingWarning, DataCheckWarning, QuantizationWarning, SaturationWarning, StuckValueWarning,
    TimestampWarning, check_samples, check_timestamps, estimate_lsb,
)
from sigmatau.errors import ParameterError, SigmaTauWarning


def _quiet(fn, *args, **kw):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        out = fn(*args, **kw)
    return out, [w.category for w in caught]


def test_warning_classes_derive_from_the_library_base():
    for cls in (QuantizationWarning, AliasingWarning, SaturationWarning, StuckValueWarning, TimestampWarning):
        assert issubclass(cls, DataCheckWarning) and issubclass(cls, SigmaTauWarning)


def test_lsb_estimate_on_grids_and_printed_values():
    rng = np.random.default_rng(0)
    assert estimate_lsb(0.05 * np.round(rng.normal(0, 8, 10_000))) == pytest.approx(0.05, rel=1e-9)
    # a 3.33 mg grid printed with 6 significant digits, as in the ADIS16405 file
    printed = np.array([float(f"{v:.6g}") for v in 0.00333 * np.round(rng.normal(-305, 1.3, 5000))])
    assert estimate_lsb(printed) == pytest.approx(0.00333, rel=1e-4)
    assert estimate_lsb(rng.normal(size=10_000)) is None
    assert estimate_lsb(np.ones(100)) is None


def test_clean_white_data_raise_no_warning():
    y = np.random.default_rng(1).normal(0.0, 1e-3, 100_000)
    c, caught = _quiet(check_samples, y, rate=200.0, unit="rad/s")
    assert caught == []
    assert c.lsb is None and c.levels is None and c.saturated == 0 and c.stuck_runs == 0
    assert c.rolloff == "flat" and abs(c.spectrum_ratio - 1.0) < 0.05
    json.dumps(c.to_dict())


def test_quantisation_warned_below_a_few_lsb_only():
    rng = np.random.default_rng(2)
    fine = 0.05 * np.round(rng.normal(0, 10 * 0.05, 50_000) / 0.05)
    c, caught = _quiet(check_samples, fine, rate=100.0, unit="deg/s")
    assert c.lsb == pytest.approx(0.05) and c.std_lsb == pytest.approx(10, rel=0.05)
    assert QuantizationWarning not in caught and not c.coarse
    assert c.quantization_density == pytest.approx(0.05 / math.sqrt(12 * 100.0))
    coarse = 0.00333 * np.round(rng.normal(0, 1.3 * 0.00333, 50_000) / 0.00333)
    c, caught = _quiet(check_samples, coarse, rate=100.0, unit="g")
    assert QuantizationWarning in caught and c.coarse
    assert c.std_lsb == pytest.approx(1.3, rel=0.05)
    with pytest.warns(QuantizationWarning, match="LSB"):
        check_samples(coarse, rate=100.0, unit="g")
    # a known LSB given by the caller is used as is
    c, _ = _quiet(check_samples, fine, rate=100.0, lsb=0.025)
    assert c.lsb == 0.025
    with pytest.raises(ParameterError):
        check_samples(fine, rate=100.0, lsb=-1.0)


def test_decimation_without_averaging_is_detected_when_the_sensor_rate_is_known():
    from scipy.signal import decimate

    rng = np.random.default_rng(3)
    stream = rng.standard_normal(8 * 200_000)          # 1600 Hz white stream
    picked = stream[::8]                               # kept every 8th sample
    blocks = stream.reshape(-1, 8).mean(axis=1)        # means of blocks of 8: white too
    filtered = decimate(stream, 8, ftype="iir")        # anti-alias filter, then every 8th
    c_pick, caught = _quiet(check_samples, picked, rate=200.0)
    c_block, _ = _quiet(check_samples, blocks, rate=200.0)
    c_filt, _ = _quiet(check_samples, filtered, rate=200.0)
    assert c_pick.rolloff == "flat" and c_block.rolloff == "flat" and c_filt.rolloff == "rolls off"
    assert abs(c_pick.spectrum_ratio - 1.0) < 0.05 and abs(c_block.spectrum_ratio - 1.0) < 0.05
    assert c_filt.spectrum_ratio < 0.5
    assert caught == []                                # a flat spectrum alone proves nothing
    c, caught = _quiet(check_samples, picked, rate=200.0, odr=1600.0)
    assert AliasingWarning in caught and c.decimation_factor == pytest.approx(8.0)
    assert any("√8" in f and "block averages would keep N" in f for f in c.findings)
    c, caught = _quiet(check_samples, filtered, rate=200.0, odr=1600.0)
    assert AliasingWarning not in caught and any("anti-alias filter" in f for f in c.findings)
    # picking keeps the per-sample σ: its apparent density is √8 times the true one
    assert picked.std() / blocks.std() == pytest.approx(math.sqrt(8.0), rel=0.01)


def test_saturation_pile_up_and_full_scale():
    rng = np.random.default_rng(4)
    walk = np.cumsum(rng.normal(0, 0.05, 50_000))
    clipped = np.clip(walk, -np.inf, np.quantile(walk, 0.99))
    c, caught = _quiet(check_samples, clipped, rate=100.0, unit="deg/s")
    assert SaturationWarning in caught and c.saturated >= 400
    c, caught = _quiet(check_samples, walk, rate=100.0)
    assert SaturationWarning not in caught and c.saturated == 0
    y = rng.normal(0, 1.0, 10_000)
    y[100:110] = 4.0
    c, caught = _quiet(check_samples, y, rate=100.0, full_scale=4.0)
    assert SaturationWarning in caught and c.saturated >= 10
    with pytest.raises(ParameterError):
        check_samples(y, rate=100.0, full_scale=0.0)


def test_stuck_runs_and_held_samples():
    rng = np.random.default_rng(5)
    y = 0.05 * np.round(rng.normal(0, 0.4, 100_000) / 0.05)
    y[5000:5300] = y[5000]                              # 3 s frozen at 100 Hz
    c, caught = _quiet(check_samples, y, rate=100.0)
    assert StuckValueWarning in caught and c.stuck_runs == 1 and c.longest_run >= 300
    c, caught = _quiet(check_samples, y[6000:], rate=100.0)
    assert StuckValueWarning not in caught
    held = np.repeat(rng.normal(size=25_000), 4)        # logged 4x faster than the sensor updates
    c, caught = _quiet(check_samples, held, rate=400.0)
    assert StuckValueWarning in caught and c.repeated_fraction == pytest.approx(0.75, abs=0.01)
    assert any("held samples" in f for f in c.findings)
    c, caught = _quiet(check_samples, np.zeros(100), rate=100.0)
    assert c.levels == 1 and StuckValueWarning in caught


def test_timestamps_out_of_order_duplicated_and_missing():
    t = np.arange(10_000) * 0.005
    t = np.delete(t, np.arange(2000, 2100))             # 100 samples lost
    t[500], t[501] = t[501], t[500]                      # one swap
    t = np.insert(t, 800, t[800])                        # one duplicate
    with pytest.warns(TimestampWarning):
        c = check_timestamps(t)
    assert c.rate == pytest.approx(200.0) and c.mean_rate < 199.0
    assert c.backwards == 1 and c.duplicates == 1 and c.gaps >= 1 and c.missing == pytest.approx(100, abs=2)
    assert np.all(np.diff(t[c.order]) >= 0)
    ns = (np.arange(1000) * 5_000_000).astype(np.int64)  # EuRoC stamps in ns
    c, caught = _quiet(check_timestamps, ns, scale=1e-9)
    assert caught == [] and c.rate == pytest.approx(200.0)
    json.dumps(c.to_dict())
    with pytest.raises(ParameterError):
        check_timestamps([1.0, 1.0, 1.0])


@pytest.mark.parametrize("n, nperseg", [(256, 32), (1000, 64), (4097, 512), (100_003, 4096), (70_000, 255)])
def test_welch_density_is_scipys_welch(n, nperseg, monkeypatch):
    from scipy.signal import welch

    from sigmatau.imu import checks as checks_module

    monkeypatch.setattr(checks_module, "_WELCH_BATCH", 3 * nperseg)  # several batches, a short last one
    x = np.cumsum(np.random.default_rng(n).standard_normal(n)) * 1e-3 + 7.0
    f0, p0 = welch(x - x.mean(), fs=250.0, nperseg=nperseg, detrend="constant")
    f1, p1 = checks_module.welch_density(x, 250.0, nperseg)
    np.testing.assert_array_equal(f1, f0)
    np.testing.assert_allclose(p1, p0, rtol=1e-12, atol=0)


@pytest.mark.parametrize("levels", [2, 3, 50, 10**9])
def test_repeat_runs_match_a_plain_scan(levels, rng):
    from sigmatau.imu.checks import _repeat_runs

    for n in (1, 2, 3, 10, 997):
        x = rng.integers(0, levels, n).astype(float)
        runs, i = [], 0
        while i < n:  # the plain definition: maximal stretches of equal neighbours
            j = i
            while j + 1 < n and x[j + 1] == x[i]:
                j += 1
            if j > i:
                runs.append((i, j - i + 1))
            i = j + 1
        starts, lengths = _repeat_runs(x[1:] == x[:-1])
        assert list(zip(starts.tolist(), lengths.tolist())) == runs
