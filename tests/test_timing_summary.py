"""The timing summary's shortcuts (no sort for a uniform log, no copy without gaps) against the
plain formulas: the median step, the rms and largest jitter about it, on uniform, jittered and
gapped timestamps, integer and float."""

from __future__ import annotations

import numpy as np
import pytest

from sigmatau.io._timing import _summarise, to_seconds


def _plain(t: np.ndarray, dt: np.ndarray, threshold: float) -> tuple[float, float, float, int]:
    step = float(np.median(dt))
    ok = dt[~(dt > threshold * step)]
    return step, float(np.std(ok - step)), float(np.max(np.abs(ok - step))), int(np.sum(dt > threshold * step))


def _cases():
    rng = np.random.default_rng(20261207)
    ns = 1_700_000_000_000_000_000 + np.arange(5000, dtype=np.int64) * 1_000_000
    yield "uniform ns", ns, "ns"
    jitter = ns + rng.integers(-20_000, 20_000, ns.size)
    yield "jittered ns", np.sort(jitter), "ns"
    yield "gapped ns", np.concatenate([ns[:1000], ns[1010:]]), "ns"
    yield "gapped jittered ns", np.concatenate([np.sort(jitter)[:2000], np.sort(jitter)[2004:]]), "ns"
    s = np.arange(3000) / 100.0
    yield "decimal s", s, "s"
    yield "gapped decimal s", np.concatenate([s[:100], s[103:]]), "s"
    yield "uniform ms", np.arange(0, 4000, 5, dtype=np.int64), "ms"


@pytest.mark.parametrize("name, raw, unit", list(_cases()), ids=[c[0] for c in _cases()])
def test_summary_equals_the_plain_formulas(name, raw, unit):
    t = to_seconds(raw - raw[0], unit)
    dt = to_seconds(np.diff(raw), unit)
    np.testing.assert_array_equal(t, (raw - raw[0]).astype(np.float64) / {"ns": 1e9, "ms": 1e3, "s": 1.0}[unit]
                                  if unit != "s" else (raw - raw[0]).astype(np.float64))
    rep = _summarise(t, dt, rate=None, rate_source="", rows=raw.size, gap_threshold=1.5, path="x", warnings=[])
    step, rms, peak, n_gaps = _plain(t, dt, 1.5)
    assert rep.measured_rate == float(f"{1.0 / step:.12g}")
    assert (rep.jitter_rms, rep.jitter_max, len(rep.gaps)) == (rms, peak, n_gaps)
    before = raw.copy()
    to_seconds(raw, unit)
    np.testing.assert_array_equal(raw, before)  # converted in a copy, never in the caller's array
