"""Timestamps: their unit, the sample rate, jitter, gaps, duplicates and disorder, and the policies.

Policies (parameters of :func:`sigmatau.io.read`):

* ``unsorted``: "sort" (default; a TimingWarning says how many) or "refuse".
* ``duplicates``: "drop" (default; the first sample of each run of equal
  timestamps is kept, a TimingWarning says how many were dropped and how many
  of them carried other values) or "refuse".
* ``gaps``: "auto" (default: as "mark" when at most :data:`AUTO_MARK_SHARE` of the
  samples are missing, except that a gap of at most :data:`AUTO_HOLD_SAMPLES`
  samples holds the sample before it; else refused with the choices), "mark" (Stable32's
  Regularize: the samples are placed on the nominal time grid and each missing
  one is a NaN, which every statistic treats as a gap), "refuse" (the error says
  where), "split" (keep every sample; :meth:`SensorLog.segments` gives the
  gap-free runs) or "ignore" (analyse across the gaps as if the samples were
  contiguous).

A gap is a step longer than ``gap_threshold`` times the median step; it holds
``round(step·rate) − 1`` missing samples at the nominal rate.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Literal

import numpy as np

from ..errors import DataError
from ._errors import option_hint, repr_kw
from ._timing_report import Gap, TimingReport
from ._units import TIME_UNITS

__all__ = ["AUTO_HOLD_SAMPLES", "AUTO_MARK_SHARE", "check_times", "infer_time_unit", "process", "untimed", "segment_report"]

GapPolicy = Literal["auto", "mark", "refuse", "split", "ignore"]

#: Largest share of missing samples (of the samples the nominal grid holds) up to which
#: ``gaps="auto"`` marks them as NaN gaps; beyond it the log is refused with the choices.
AUTO_MARK_SHARE = 0.10
#: Longest gap (missing samples) that ``gaps="auto"`` bridges by holding the sample before it,
#: as a sensor's output register does when a read is missed. Scattered single drops would
#: otherwise leave no gap-free window at long τ on frequency (rate) data, where a term is used
#: only when every sample of its window is present; a held sample changes each statistic by
#: about the share of held samples (a few per million in a log with a drop per second at 1 kHz).
AUTO_HOLD_SAMPLES = 5
UnsortedPolicy = Literal["sort", "refuse"]
DuplicatesPolicy = Literal["drop", "refuse"]

# Sample rates a time unit may imply for a sensor or clock log (Hz): used only to
# choose the unit of an unnamed time column and to refuse when more than one fits.
PLAUSIBLE_RATE = (1e-6, 4e4)
# First timestamps of Unix (or GPS) time between 1990 and 2100, per unit.
_EPOCH_SECONDS = (6.3e8, 4.2e9)
_PER_SECOND = {"ms": 1e3, "us": 1e6, "ns": 1e9}
_RATE_TOLERANCE = 0.01  # relative difference between given and measured rate that warns


def _fmt(x: float) -> str:
    return f"{x:.6g}"


def check_times(raw: np.ndarray, *, name: str, path: str) -> None:
    """Refuse non-finite timestamps and timestamps that are all equal."""
    if raw.dtype.kind == "f":
        bad = ~np.isfinite(raw)
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            raise DataError(
                f"{path}: time column {name!r} holds {int(bad.sum())} non-finite value(s) (first at sample {i})"
            )
    n = raw.size
    if n >= 2 and raw[0] == raw[-1] and np.all(raw == raw[0]):
        raise DataError(f"{path}: all {n} timestamps in {name!r} are equal ({_value(raw[0])}); cannot tell the rate")


def infer_time_unit(t: np.ndarray, *, name: str, stated: str | None, path: str) -> tuple[str, str]:
    """Unit of raw time values and the reason, refusing when it cannot be told.

    Order: the unit given or stated by the name/format; then the magnitude of the
    first value when it is Unix time (1990–2100) in exactly one unit; then the
    median step, when exactly one unit gives a plausible rate (1 µHz–40 kHz).
    """
    if stated is not None:
        return stated, "stated"
    first, last = float(t[0]), float(t[-1])
    epoch = [u for u in ("s", "ms", "us", "ns")
             if all(_EPOCH_SECONDS[0] <= v * TIME_UNITS[u] <= _EPOCH_SECONDS[1] for v in (first, last))]
    if len(epoch) == 1:
        return epoch[0], f"Unix time in {epoch[0]} judging by its magnitude ({_fmt(first)})"
    steps = np.diff(t[: 100_001]).astype(np.float64)
    steps = steps[steps > 0]
    if steps.size == 0:
        raise DataError(f"{path}: time column {name!r} does not increase; cannot tell its unit")
    step = float(np.median(steps))
    fits = {}
    for u in ("s", "ms", "us", "ns"):
        rate = 1.0 / (step * TIME_UNITS[u])
        if PLAUSIBLE_RATE[0] <= rate <= PLAUSIBLE_RATE[1]:
            fits[u] = rate
    if len(fits) == 1:
        (u, rate), = fits.items()
        return u, f"median step {_fmt(step)} gives {_fmt(rate)} Hz only if in {u}"
    readings = ", ".join(f"{_fmt(r)} Hz if {u}" for u, r in fits.items()) or "no plausible rate in any unit"
    raise DataError(
        f"{path}: cannot tell the unit of time column {name!r} (median step {_fmt(step)}: {readings});"
        f" give it with {option_hint('--time-unit s|ms|us|ns', 'time_unit=')}"
    )


def _value(x: np.generic) -> str:
    return str(int(x)) if np.issubdtype(type(x), np.integer) else _fmt(float(x))


def _where(i: int, raw: np.ndarray) -> str:
    return f"sample {i} (t = {_value(raw[i])})"


def process(
    raw: np.ndarray,
    channels: dict[str, np.ndarray],
    *,
    unit: str,
    unit_reason: str,
    time_name: str,
    rate: float | None,
    rate_source: str,
    rows: int,
    path: str,
    gaps: GapPolicy,
    gap_threshold: float,
    unsorted: UnsortedPolicy,
    duplicates: DuplicatesPolicy,
    warnings: list[str],
) -> tuple[np.ndarray, dict[str, np.ndarray], TimingReport, float]:
    """Apply the policies to raw timestamps (int64 or float64, in ``unit``).

    Returns the timestamps in s from the first sample, the channels (reordered or
    thinned when needed), the report, and the first timestamp in s.
    """
    check_times(raw, name=time_name, path=path)
    actions: list[str] = []
    raw, channels, n_back = _sorted(raw, channels, unsorted, path, actions, warnings)
    raw, channels, n_dup, differing = _deduplicated(raw, channels, duplicates, path, actions, warnings)
    m = raw.size
    if m < 2:
        raise DataError(f"{path}: only {m} distinct timestamp(s); at least 2 are needed to tell the rate")
    origin = raw[0]
    t = to_seconds(raw - origin, unit)
    time_origin = float(to_seconds(np.array([origin]), unit)[0])

    report = _summarise(
        t, to_seconds(np.diff(raw), unit), rate=rate, rate_source=rate_source, rows=rows, gap_threshold=gap_threshold,
        path=path, warnings=warnings,
    )
    report = replace(
        report,
        out_of_order=n_back,
        duplicates=n_dup,
        duplicates_differing=differing,
        time_column=time_name,
        time_unit=unit,
        time_unit_reason=unit_reason,
        unsorted_policy=unsorted,
        duplicates_policy=duplicates,
        gaps_policy=gaps,
        actions=tuple(actions),
    )
    if report.gaps:
        share = report.missing / (m + report.missing)
        if gaps == "auto" and share > AUTO_MARK_SHARE:
            raise DataError(
                f"{path}: {_gap_text(report, m)}, {100 * share:.3g} % of the samples (gaps are marked as"
                f" missing samples by default up to {100 * AUTO_MARK_SHARE:g} %); to mark them all the same use"
                f" {option_hint('--gaps mark', repr_kw('gaps', 'mark'))}, to analyse the gap-free segments"
                f" {option_hint('--gaps split', repr_kw('gaps', 'split'))}, to analyse across the gaps"
                f" {option_hint('--gaps ignore', repr_kw('gaps', 'ignore'))}")
        if gaps == "refuse":
            raise DataError(f"{path}: {_gap_text(report, m)}; to mark the missing samples use"
                            f" {option_hint('--gaps mark', repr_kw('gaps', 'mark'))}, to analyse the gap-free"
                            f" segments {option_hint('--gaps split', repr_kw('gaps', 'split'))}, to analyse"
                            f" across the gaps {option_hint('--gaps ignore', repr_kw('gaps', 'ignore'))}")
        if gaps in ("auto", "mark"):
            t, channels, report = _marked(t, channels, report, hold=AUTO_HOLD_SAMPLES if gaps == "auto" else 0)
        else:
            verb = "split the log at" if gaps == "split" else "ignored"
            report = replace(report, actions=report.actions + (f"{verb} {len(report.gaps)} gap(s)",))
    elif gaps == "auto":
        report = replace(report, gaps_policy="mark")
    return t, channels, report, time_origin


def _marked(t: np.ndarray, channels: dict[str, np.ndarray], report: TimingReport,
            hold: int = 0) -> tuple[np.ndarray, dict[str, np.ndarray], TimingReport]:
    """The samples placed on the nominal grid with NaN for every missing one (Stable32's Regularize).

    Each gap of ``report`` gets its ``missing`` samples (``round(step·rate) − 1`` at the
    nominal rate); the timestamps of the inserted samples are interpolated between the
    two around the gap. The gaps' ``index`` becomes that of the first sample after them
    in the marked log, whose samples ``index − missing … index − 1`` are the inserted ones.
    A gap of at most ``hold`` samples holds the sample before it instead of NaN; only the
    longer gaps stay in ``report.gaps``, the held ones are counted in ``report.actions``.
    """
    counts = np.array([g.missing for g in report.gaps], dtype=np.int64)
    where = np.array([g.index for g in report.gaps], dtype=np.int64)
    shift = np.zeros(t.size, dtype=np.int64)
    np.add.at(shift, where, counts)
    new_pos = np.arange(t.size) + np.cumsum(shift)
    size = t.size + int(counts.sum())
    held = counts <= hold
    # index into the original samples of every output sample: the sample itself, or for an
    # inserted one the last sample before it (held) / -1 (missing)
    source = np.full(size, -1, dtype=np.int64)
    source[new_pos] = np.arange(t.size)
    for g_at, k in zip(where[held].tolist(), counts[held].tolist()):
        source[new_pos[g_at] - k: new_pos[g_at]] = g_at - 1
    out = {}
    for name, v in channels.items():
        filled = np.where(source >= 0, v[np.maximum(source, 0)], np.nan)
        out[name] = filled
    grid = np.interp(np.arange(size), new_pos, t)
    gaps = tuple(replace(g, index=int(new_pos[g.index]), missing=int(k))
                 for g, k, h in zip(report.gaps, counts.tolist(), held.tolist()) if not h)
    actions = list(report.actions)
    if held.any():
        actions.append(f"held the sample before each of {int(held.sum())} gap(s) of at most {hold} sample(s)"
                       f" ({int(counts[held].sum())} sample(s))")
    if gaps:
        actions.append(f"marked {int(counts[~held].sum())} missing sample(s) in {len(gaps)} gap(s) as NaN on the"
                       f" {_fmt(report.rate)} Hz grid")
    return grid, out, replace(report, samples=int(size), gaps=gaps, gaps_policy="mark", actions=tuple(actions))


def _sorted(raw: np.ndarray, channels: dict[str, np.ndarray], unsorted: UnsortedPolicy, path: str,
            actions: list[str], warnings: list[str]) -> tuple[np.ndarray, dict[str, np.ndarray], int]:
    """Timestamps that go backwards: refused, or the samples sorted by time (stable). Returns the count."""
    back = np.flatnonzero(raw[1:] < raw[:-1])
    n_back = int(back.size)
    if n_back:
        i = int(back[0]) + 1
        text = f"{n_back} timestamp(s) go backwards (first at {_where(i, raw)}, after {_value(raw[i - 1])})"
        if unsorted == "refuse":
            raise DataError(f"{path}: {text}; to sort the samples by time use"
                            f" {option_hint('--unsorted sort', repr_kw('unsorted', 'sort'))}")
        order = np.argsort(raw, kind="stable")
        raw = raw[order]
        channels = {k: v[order] for k, v in channels.items()}
        actions.append(f"sorted the samples by time ({n_back} out of order)")
        warnings.append(f"{path}: {text}; sorted the samples by time")
    return raw, channels, n_back


def _deduplicated(raw: np.ndarray, channels: dict[str, np.ndarray], duplicates: DuplicatesPolicy, path: str,
                  actions: list[str], warnings: list[str]) -> tuple[np.ndarray, dict[str, np.ndarray], int, int]:
    """Repeated timestamps: refused, or the first sample of each kept. Returns the counts (all, differing)."""
    same = np.flatnonzero(raw[1:] == raw[:-1]) + 1
    n_dup = int(same.size)
    if not n_dup:
        return raw, channels, 0, 0
    # the kept sample of each run of equal timestamps is the one before the run
    run_start = np.concatenate(([True], np.diff(same) != 1))
    kept = np.maximum.accumulate(np.where(run_start, same - 1, 0))
    diff_any = np.zeros(n_dup, dtype=bool)
    for v in channels.values():
        diff_any |= ~((v[same] == v[kept]) | (np.isnan(v[same]) & np.isnan(v[kept])))
    differing = int(diff_any.sum())
    i = int(same[0])
    text = (
        f"{n_dup} sample(s) repeat the timestamp before them ({differing} with different values;"
        f" first at {_where(i, raw)})"
    )
    if duplicates == "refuse":
        raise DataError(f"{path}: {text}; to keep the first of each use"
                        f" {option_hint('--duplicates drop', repr_kw('duplicates', 'drop'))}")
    keep = np.ones(raw.size, dtype=bool)
    keep[same] = False
    raw = raw[keep]
    channels = {k: v[keep] for k, v in channels.items()}
    actions.append(f"dropped {n_dup} duplicated timestamp(s) ({differing} with different values)")
    warnings.append(f"{path}: {text}; kept the first of each")
    return raw, channels, n_dup, differing


def _gap_text(report: TimingReport, n: int) -> str:
    g = report.gaps
    period = 1.0 / report.measured_rate if report.measured_rate else float("nan")
    listed = "; ".join(
        f"{_fmt(x.duration)} s after {_fmt(x.time)} s (before sample {x.index})" for x in g[:3]
    )
    more = f"; … {len(g) - 3} more" if len(g) > 3 else ""
    hint = ""
    if len(g) > max(10, n // 100):
        hint = " (that many gaps suggests bursty timestamps, such as receive times)"
    return (
        f"{len(g)} gap(s) in the timestamps (steps > {report.gap_threshold:g} × the median step"
        f" {_fmt(period)} s; {report.missing} samples missing): {listed}{more}{hint}"
    )


def to_seconds(x: np.ndarray, unit: str) -> np.ndarray:
    """Times in ``unit`` as float64 seconds (dividing by 1e3/1e6/1e9 rounds once, exactly)."""
    x = np.array(x, dtype=np.float64)  # a new array, converted in place below (no second copy)
    per_second = _PER_SECOND.get(unit)
    if per_second:
        np.divide(x, per_second, out=x)
    else:
        np.multiply(x, TIME_UNITS[unit], out=x)
    return x


def _summarise(
    t: np.ndarray,
    dt: np.ndarray,
    *,
    rate: float | None,
    rate_source: str,
    rows: int,
    gap_threshold: float,
    path: str,
    warnings: list[str] | None,
) -> TimingReport:
    lo, hi = (float(dt.min()), float(dt.max())) if dt.size else (math.nan, math.nan)
    uniform = lo == hi  # the common case of clean logs: every step the same, no sort for the median
    step = lo if uniform else float(np.median(dt))
    # 12 digits: decimal timestamps in s leave round-off like 99.99999999999991 Hz
    measured = float(f"{1.0 / step:.12g}")
    nominal = measured if rate is None else rate
    if rate is not None and warnings is not None and abs(rate / measured - 1.0) > _RATE_TOLERANCE:
        warnings.append(
            f"{path}: the {rate_source} rate {_fmt(rate)} Hz differs from the {_fmt(measured)} Hz"
            f" measured from the timestamps by {100 * abs(rate / measured - 1):.3g} %"
        )
    limit = gap_threshold * step
    is_gap = dt > limit
    idx = np.flatnonzero(is_gap)
    gap_list = tuple(
        Gap(index=int(i) + 1, time=float(t[i]), duration=float(dt[i]),
            missing=max(int(round(float(dt[i]) * measured)) - 1, 1))
        for i in idx
    )
    ok = dt[~is_gap] if idx.size else dt  # no copy of the steps when there is no gap
    if uniform:  # ok - step is exactly 0 everywhere
        jitter = (0.0, 0.0) if ok.size else (None, None)
    elif ok.size:
        dev = ok - step
        jitter = (float(np.std(dev)), float(max(dev.max(), -dev.min())))  # about the median: exact 0 when uniform
    else:
        jitter = (None, None)
    span = float(t[-1] - t[0])
    return TimingReport(
        samples=int(t.size),
        rows=rows,
        rate=float(nominal),
        rate_source="timestamps" if rate is None else rate_source,
        measured_rate=float(measured),
        mean_rate=float((t.size - 1) / span) if span > 0 else None,
        span=span,
        jitter_rms=jitter[0],
        jitter_max=jitter[1],
        gaps=gap_list,
        gap_threshold=gap_threshold,
    )


def untimed(n: int, *, rate: float, rate_source: str, rows: int, gaps: GapPolicy,
            gap_threshold: float) -> TimingReport:
    """Report for a log without timestamps: uniform sampling at ``rate`` is assumed."""
    return TimingReport(
        samples=n, rows=rows, rate=rate, rate_source=rate_source,
        span=(n - 1) / rate, gap_threshold=gap_threshold, gaps_policy=gaps,
        time_unit_reason="no time column",
    )


def segment_report(parent: TimingReport, t: np.ndarray, start: int) -> TimingReport:
    """Timing report of one gap-free segment (``t``: the parent's timestamps of it)."""
    if t.size < 2:
        return replace(parent, samples=int(t.size), rows=int(t.size), gaps=(), span=0.0,
                       measured_rate=None, mean_rate=None, jitter_rms=None, jitter_max=None,
                       actions=parent.actions + (f"segment from sample {start}",))
    rate = parent.rate if parent.rate_source != "timestamps" else None
    seg = _summarise(t - t[0], np.diff(t), rate=rate, rate_source=parent.rate_source, rows=int(t.size),
                     gap_threshold=math.inf, path="", warnings=None)
    return replace(
        parent,
        samples=seg.samples, rows=seg.rows, measured_rate=seg.measured_rate, mean_rate=seg.mean_rate,
        span=seg.span, jitter_rms=seg.jitter_rms, jitter_max=seg.jitter_max, gaps=(),
        rate=parent.rate,
        actions=parent.actions + (f"segment of samples {start}–{start + t.size - 1}",),
    )
