"""The noise type behind each row's EDF (uncertainty.attach.edf_alpha).

Where the data cannot decide — fewer than DECISIVE_AVERAGES averages, or white PM after
flicker PM — a type whiter than one identified at a shorter τ does not set the EDF: the
smallest EDF over the types in between does. The Monte Carlo evidence is in
test_confidence_mc.py (test_long_record_last_octaves_coverage, test_default_path_...).
"""

from __future__ import annotations

import numpy as np
import pytest

import sigmatau
from sigmatau.confidence import deviation_interval, edf_array
from sigmatau.core.result import StabilityResult
from sigmatau.uncertainty.attach import DECISIVE_AVERAGES, attach, edf_alpha


def _raw(statistic: str, ms, n_points: int) -> StabilityResult:
    m = np.asarray(ms, dtype=np.int64)
    var = np.full(m.size, 4.0e-22)
    return StabilityResult(statistic=statistic, taus=m.astype(float), m=m, var=var, dev=np.sqrt(var),
                           n=np.full(m.size, 100), rate=1.0, data_type="phase", n_points=n_points)


def _attach(raw: StabilityResult, alpha) -> StabilityResult:
    a = np.asarray(alpha, dtype=float)
    return attach(raw, np.empty(0), "phase", alpha=None, confidence=0.683, ci="chi2",
                  identified=(a, np.full(a.size, np.nan)))


def test_a_whiter_type_with_few_averages_gets_the_smallest_edf_of_the_types_between():
    n_points = 32769
    raw = _raw("oadev", [1, 1024, 4096], n_points)      # 32768, 32 and 8 averages
    res = _attach(raw, [0, 0, 1])
    assert res.alpha.tolist() == [0, 0, 1]             # the reported type is the identified one
    own = edf_array("oadev", [1], [4096], n_points)[0]
    wfm = edf_array("oadev", [0], [4096], n_points)[0]
    assert wfm < own / 3                               # the case that made intervals too narrow
    assert res.edf[2] == pytest.approx(wfm, rel=1e-12)
    lo, hi = deviation_interval(res.dev[2:], np.array([wfm]), 0.683)
    assert (res.ci_low[2], res.ci_high[2]) == pytest.approx((lo[0], hi[0]), rel=1e-12)
    assert "alpha=0" in res.ci_reason[2] and "identified alpha=1" not in res.ci_reason[0]
    assert res.ci_reason[:2] == ("", "")


def test_a_whiter_type_with_enough_averages_keeps_its_own_edf():
    n_points = 200 * DECISIVE_AVERAGES
    raw = _raw("oadev", [1, 100, 200], n_points)       # 200 averages at m = 100 and 136 at m = 200
    res = _attach(raw, [-1, 0, 0])
    np.testing.assert_allclose(res.edf, edf_array("oadev", [-1, 0, 0], [1, 100, 200], n_points), rtol=1e-12)
    assert res.ci_reason == ("", "", "")


def test_white_pm_after_flicker_pm_never_decides_alone():
    n_points = 2**20
    raw = _raw("oadev", [1, 2, 64], n_points)           # 16384 averages at m = 64
    res = _attach(raw, [1, 2, 2])
    fpm = edf_array("oadev", [1, 1, 1], [1, 2, 64], n_points)
    wpm = edf_array("oadev", [2, 2, 2], [1, 2, 64], n_points)
    np.testing.assert_allclose(res.edf, [fpm[0], min(fpm[1], wpm[1]), min(fpm[2], wpm[2])], rtol=1e-12)
    assert fpm[2] < wpm[2] / 3                          # at m = 64 flicker PM's EDF decides
    assert res.alpha.tolist() == [1, 2, 2] and res.ci_reason[0] == "" and "alpha=1" in res.ci_reason[2]


def test_a_redder_type_at_a_longer_tau_is_taken_as_identified():
    n_points = 4097
    raw = _raw("oadev", [1, 512, 1024], n_points)
    res = _attach(raw, [2, 0, -2])
    np.testing.assert_allclose(res.edf, edf_array("oadev", [2, 0, -2], [1, 512, 1024], n_points), rtol=1e-12)


def test_the_rule_looks_at_shorter_tau_only_whatever_the_row_order():
    n_points = 4097
    raw = _raw("oadev", [1024, 1], n_points)          # m = 1, listed second, identified redder
    assert edf_alpha(raw, np.array([1.0, -1.0])).tolist() == [-1.0, -1.0]
    res = _attach(raw, [1, -1])
    candidates = edf_array("oadev", [-1, 0, 1], [1024] * 3, n_points)
    assert res.edf[0] == pytest.approx(candidates.min(), rel=1e-12)
    assert res.ci_reason[1] == ""
    # an unidentified row neither takes nor gives a type
    assert edf_alpha(_raw("oadev", [1, 1024], n_points), np.array([np.nan, 1.0])).tolist()[1] == 1.0


def test_forced_alpha_and_the_theo_family_are_left_alone():
    x = sigmatau.power_law_noise(2049, 0, data_type="phase", rng=np.random.default_rng(1))
    forced = sigmatau.oadev(x, data_type="phase", m=[1, 512], alpha=1)
    np.testing.assert_allclose(forced.edf, edf_array("oadev", [1, 1], [1, 512], 2049), rtol=1e-12)
    assert forced.ci_reason == ("", "")
    res = _attach(_raw("theobr", [10, 100], 4097), [-1, 0])
    assert not any(r.startswith("EDF for alpha=") for r in res.ci_reason)


def test_no_edf_for_the_identified_type_stays_no_interval():
    # TOTDEV has no EDF for white PM: a redder type seen earlier does not invent one.
    raw = _raw("totdev", [1, 512], 2049)
    res = _attach(raw, [1, 2])
    assert np.isnan(res.edf[1]) and np.isnan(res.ci_low[1]) and np.isnan(res.ci_high[1])


def test_gap_records_count_averages_from_their_effective_length():
    raw = _raw("oadev", [1, 64], 100_000)
    gappy = StabilityResult(**{**raw.__dict__, "n_effective": np.array([100_000, 64 * 100])})
    assert edf_alpha(gappy, np.array([-1.0, 0.0])).tolist() == [-1.0, -1.0]   # 100 averages
    assert edf_alpha(raw, np.array([-1.0, 0.0])).tolist() == [-1.0, 0.0]      # 1562 averages
