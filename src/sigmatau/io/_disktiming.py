"""The timing checks of :mod:`._timing` on timestamps read in chunks, for logs larger than memory.

:func:`process_streamed` applies the policies of :func:`sigmatau.io.read` (``unsorted``,
``duplicates``, ``gaps``, ``gap_threshold``) to a time column it reads piecewise and returns
the same :class:`TimingReport`, with, instead of new arrays, a :class:`RowMap`: which row of the
file (or a gap) each sample of the analysed log is. The map has one entry per run of rows kept
and per gap, so its size follows the irregularities of the log, not its length.

What differs from the in-memory reader:

* timestamps that go backwards are refused (sorting needs the whole record at once), with the
  options that work: sort the file first, or read it in memory;
* the jitter (rms about the median step) is accumulated chunk by chunk (Chan's update of the
  mean and the sum of squares) rather than by one ``numpy.std``: equal to ~1e-15 relative; every
  other figure (median step, rate, gaps and their positions, duplicates, actions) is the same;
* ``gaps="split"`` is refused (the analysis of the longest segment reads it whole).

Memory: one chunk of timestamps per pass, plus the rows dropped as duplicates and the gaps.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Mapping

import numpy as np

from ..errors import DataError
from ._disklayout import Reader
from ._errors import option_hint, repr_kw
from ._timing import AUTO_HOLD_SAMPLES, AUTO_MARK_SHARE, _RATE_TOLERANCE, _fmt, _gap_text, to_seconds
from ._timing_report import Gap, TimingReport

__all__ = ["RowMap", "process_streamed", "scan_times", "CHUNK_ROWS"]


#: Timestamps per read of a pass (8 MiB of int64 or float64).
CHUNK_ROWS = 1 << 20
#: Distinct step values counted exactly for the median before the radix selection takes over.
_MAX_DISTINCT = 1 << 16


@dataclass(frozen=True)
class RowMap:
    """Which row of the file each sample of the analysed log is: pieces that copy a run of rows,
    hold one row (a short gap bridged by ``gaps="auto"``) or are missing (NaN, a marked gap).

    Attributes
    ----------
    out_start : numpy.ndarray
        First sample of each piece (int64, increasing, from 0).
    src : numpy.ndarray
        First row of a copying piece, the row held by a holding one, -1 for a gap.
    step : numpy.ndarray
        1 for a copying piece, 0 otherwise.
    size : int
        Samples of the analysed log.
    """

    out_start: np.ndarray
    src: np.ndarray
    step: np.ndarray
    size: int

    def read(self, rows: Reader, start: int, stop: int) -> np.ndarray:
        """Samples ``start … stop-1`` (float64, NaN for gaps) from ``rows(a, b)``, the file's rows."""
        i0 = int(np.searchsorted(self.out_start, start, side="right")) - 1
        i1 = int(np.searchsorted(self.out_start, stop, side="left"))
        os_ = self.out_start[i0:i1]
        oe = np.append(self.out_start[i0 + 1:i1], self.out_start[i1] if i1 < self.out_start.size else self.size)
        lo, hi = np.maximum(os_, start), np.minimum(oe, stop)
        lens = hi - lo
        step = self.step[i0:i1]
        first = np.where(self.src[i0:i1] >= 0, self.src[i0:i1] + (lo - os_) * step, -1)
        if lens.size == 1 and step[0] == 1:  # one run of rows: a plain read
            return np.asarray(rows(int(first[0]), int(first[0] + lens[0])), dtype=np.float64)
        pos = np.arange(stop - start) - np.repeat(lo - start, lens)
        idx = np.repeat(first, lens) + pos * np.repeat(step, lens)
        out = np.full(stop - start, np.nan)
        valid = idx >= 0
        if not valid.any():
            return out
        lo_row, hi_row = int(idx[valid].min()), int(idx[valid].max()) + 1
        if hi_row - lo_row <= 4 * (stop - start) + 4096:
            buf = np.asarray(rows(lo_row, hi_row), dtype=np.float64)
            out[valid] = buf[idx[valid] - lo_row]
            return out
        # Rows far apart (long runs of dropped duplicates): one read per piece.
        at = 0
        for f, n, s in zip(first.tolist(), lens.tolist(), step.tolist()):
            if f >= 0:
                piece = np.asarray(rows(f, f + (n if s else 1)), dtype=np.float64)
                out[at:at + n] = piece if s else piece[0]
            at += n
        return out


def _chunks(n: int, size: int = CHUNK_ROWS):  # type: ignore[no-untyped-def]
    for a in range(0, n, size):
        yield a, min(n, a + size)


def _value(x: object) -> str:
    return str(int(x)) if isinstance(x, (int, np.integer)) else _fmt(float(x))  # type: ignore[arg-type]


@dataclass
class _Order:
    """What the first pass over the raw timestamps finds."""

    first: object = None
    last: object = None
    all_equal: bool = True
    bad: int = 0
    first_bad: int = -1
    back: int = 0
    first_back: int = -1
    back_values: tuple = ()
    dropped: np.ndarray = field(default_factory=lambda: np.empty(0, dtype=np.int64))


def scan_times(time: Reader, n: int, *, name: str, path: str) -> _Order:
    """One pass over the raw timestamps: :func:`sigmatau.io._timing.check_times`'s errors (non-finite,
    all equal), and the steps backwards and the repeated timestamps for :func:`process_streamed`."""
    o = _first_pass(time, n)
    if o.bad:
        raise DataError(f"{path}: time column {name!r} holds {o.bad} non-finite value(s) (first at sample"
                        f" {o.first_bad})")
    if n >= 2 and o.all_equal:
        raise DataError(f"{path}: all {n} timestamps in {name!r} are equal ({_value(o.first)}); cannot tell"
                        " the rate")
    return o


def _first_pass(time: Reader, n: int) -> _Order:
    """Non-finite values, all-equal timestamps, steps backwards and repeated timestamps."""
    o = _Order()
    dropped: list[np.ndarray] = []
    prev = None
    for a, b in _chunks(n):
        t = time(a, b)
        if a == 0:
            o.first = t[0]
        if t.dtype.kind == "f":
            bad = ~np.isfinite(t)
            if bad.any():
                if o.first_bad < 0:
                    o.first_bad = a + int(np.flatnonzero(bad)[0])
                o.bad += int(bad.sum())
        if o.all_equal and not np.all(t == o.first):
            o.all_equal = False
        d = np.diff(t) if prev is None else np.diff(np.concatenate(([prev], t)))
        base = a + (0 if prev is None else -1)  # row of d[0]'s left sample
        back = np.flatnonzero(d < 0)
        if back.size:
            if o.first_back < 0:
                i = base + int(back[0]) + 1
                o.first_back = i
                o.back_values = (t[i - a] if i - a >= 0 else prev, t[i - a - 1] if i - a - 1 >= 0 else prev)
            o.back += int(back.size)
        same = np.flatnonzero(d == 0)
        if same.size:
            dropped.append(base + same + 1)
        prev = t[-1]
    o.last = prev
    if dropped:
        o.dropped = np.concatenate(dropped).astype(np.int64)
    return o


def _differing(dropped: np.ndarray, channels: Mapping[str, Reader], n: int) -> int:
    """How many dropped rows carry a value other than the row kept before them, in any channel
    (NaN equal to NaN), as :func:`sigmatau.io._timing._deduplicated` counts them."""
    if not dropped.size:
        return 0
    differ = np.zeros(dropped.size, dtype=bool)
    for read in channels.values():
        carried = math.nan
        for a, b in _chunks(n):
            lo, hi = np.searchsorted(dropped, [a, b])
            v = np.asarray(read(a, b), dtype=np.float64)
            if hi > lo:
                rows = dropped[lo:hi] - a
                is_dropped = np.zeros(b - a, dtype=bool)
                is_dropped[rows] = True
                kept = np.maximum.accumulate(np.where(is_dropped, -1, np.arange(b - a)))
                ref = np.where(kept[rows] >= 0, v[np.maximum(kept[rows], 0)], carried)
                val = v[rows]
                differ[lo:hi] |= ~((val == ref) | (np.isnan(val) & np.isnan(ref)))
            keep_last = np.flatnonzero(~np.isin(np.arange(a, b), dropped[lo:hi]))
            if keep_last.size:
                carried = float(v[keep_last[-1]])
    return int(differ.sum())


def _steps(time: Reader, n: int, unit: str):  # type: ignore[no-untyped-def]
    """Per chunk: the steps between the kept timestamps in seconds, the index (among the kept samples)
    of the sample before each step, and the raw time before each step."""
    prev = None
    kept_before = 0  # kept samples before this chunk's first row
    for a, b in _chunks(n):
        t = time(a, b)
        full = t if prev is None else np.concatenate(([prev], t))
        d = np.diff(full)
        keep = d != 0
        left = full[:-1][keep]
        # the kept index of the left sample of each step: kept samples up to it, minus one
        ranks = np.cumsum(keep) - 1 if prev is None else np.cumsum(keep) - 2 + kept_before
        yield to_seconds(d[keep], unit), ranks[keep], left
        kept_before += int(np.count_nonzero(keep)) + (1 if prev is None else 0)
        prev = t[-1]


def _kth(time: Reader, n: int, unit: str, ks: tuple[int, ...]) -> list[float]:
    """The k-th smallest steps (0-based), exactly: counted by value when they take few values (a
    regular clock), else by a radix selection on their bits (four more passes at most)."""
    counts: dict[float, int] = {}
    for dt, _, _ in _steps(time, n, unit):
        values, c = np.unique(dt, return_counts=True)
        for v, k in zip(values.tolist(), c.tolist()):
            counts[v] = counts.get(v, 0) + k
        if len(counts) > _MAX_DISTINCT:
            break
    else:
        keys = sorted(counts)
        cum = np.cumsum([counts[k] for k in keys])
        return [keys[int(np.searchsorted(cum, k, side="right"))] for k in ks]
    return [_radix_kth(time, n, unit, k) for k in ks]


def _radix_kth(time: Reader, n: int, unit: str, k: int) -> float:
    """The k-th smallest positive step, 16 bits of its IEEE pattern per pass (order-preserving
    for positive floats)."""
    prefix, shift, rank = 0, 48, k
    while True:
        hist = np.zeros(1 << 16, dtype=np.int64)
        for dt, _, _ in _steps(time, n, unit):
            bits = dt.view(np.uint64)
            if shift < 48:
                bits = bits[(bits >> np.uint64(shift + 16)) == np.uint64(prefix)]
            hist += np.bincount(((bits >> np.uint64(shift)) & np.uint64(0xFFFF)).astype(np.int64),
                                minlength=1 << 16)
        cum = np.cumsum(hist)
        digit = int(np.searchsorted(cum, rank, side="right"))
        rank -= int(cum[digit - 1]) if digit else 0
        prefix = (prefix << 16) | digit
        if shift == 0:
            return float(np.array([prefix], dtype=np.uint64).view(np.float64)[0])
        shift -= 16


@dataclass
class _Spread:
    """Gaps, and the mean and sum of squares (Chan's update) of the other steps less the median."""

    count: int = 0
    mean: float = 0.0
    m2: float = 0.0
    largest: float = 0.0

    def add(self, x: np.ndarray) -> None:
        if not x.size:
            return
        m = float(np.mean(x))
        m2 = float(np.sum((x - m) ** 2))
        total = self.count + x.size
        delta = m - self.mean
        self.mean += delta * x.size / total
        self.m2 += m2 + delta * delta * self.count * x.size / total
        self.count = total
        self.largest = max(self.largest, float(np.max(np.abs(x))))


def process_streamed(
    time: Reader,
    n: int,
    channels: Mapping[str, Reader],
    *,
    order: _Order,
    unit: str,
    unit_reason: str,
    time_name: str,
    rate: float | None,
    rate_source: str,
    rows: int,
    path: str,
    gaps: str,
    gap_threshold: float,
    unsorted: str,
    duplicates: str,
    warnings: list[str],
) -> tuple[RowMap | None, TimingReport, float]:
    """:func:`sigmatau.io._timing.process` on timestamps read in chunks (``order``: :func:`scan_times`).

    Returns the row map (None when every row is a sample, in order), the timing report and the
    first timestamp in s. Raises the in-memory reader's one-line errors, and one naming what is
    not done out of core (sorting, ``gaps="split"``).
    """
    o = order
    actions: list[str] = []
    if o.back:
        i = o.first_back
        text = (f"{o.back} timestamp(s) go backwards (first at sample {i} (t = {_value(o.back_values[0])}),"
                f" after {_value(o.back_values[1])})")
        if unsorted == "refuse":
            raise DataError(f"{path}: {text}; to sort the samples by time use"
                            f" {option_hint('--unsorted sort', repr_kw('unsorted', 'sort'))}")
        raise DataError(f"{path}: {text}; out of core the samples are not sorted (that needs the whole record"
                        f" in memory): sort the file by time first, or read it in memory with"
                        f" {option_hint('--memory in', repr_kw('memory', 'in'))}")
    dropped = o.dropped
    n_dup = int(dropped.size)
    differing = 0
    if n_dup:
        differing = _differing(dropped, channels, n)
        i = int(dropped[0])
        text = (f"{n_dup} sample(s) repeat the timestamp before them ({differing} with different values;"
                f" first at sample {i} (t = {_value(time(i, i + 1)[0])}))")
        if duplicates == "refuse":
            raise DataError(f"{path}: {text}; to keep the first of each use"
                            f" {option_hint('--duplicates drop', repr_kw('duplicates', 'drop'))}")
        actions.append(f"dropped {n_dup} duplicated timestamp(s) ({differing} with different values)")
        warnings.append(f"{path}: {text}; kept the first of each")
    m = n - n_dup
    if m < 2:
        raise DataError(f"{path}: only {m} distinct timestamp(s); at least 2 are needed to tell the rate")
    origin = time(0, 1)
    time_origin = float(to_seconds(origin, unit)[0])
    report = _summary(time, n, unit, dropped, m, origin, rate, rate_source, rows, gap_threshold, path, warnings)
    report = replace(report, out_of_order=0, duplicates=n_dup, duplicates_differing=differing,
                     time_column=time_name, time_unit=unit, time_unit_reason=unit_reason,
                     unsorted_policy=unsorted, duplicates_policy=duplicates, gaps_policy=gaps,
                     actions=tuple(actions))
    inserted: list[tuple[int, int, bool]] = []
    if report.gaps:
        share = report.missing / (m + report.missing)
        hints = (f"to mark the missing samples use {option_hint('--gaps mark', repr_kw('gaps', 'mark'))}, to"
                 f" analyse the gap-free segments {option_hint('--gaps split', repr_kw('gaps', 'split'))}, to"
                 f" analyse across the gaps {option_hint('--gaps ignore', repr_kw('gaps', 'ignore'))}")
        if gaps == "auto" and share > AUTO_MARK_SHARE:
            raise DataError(
                f"{path}: {_gap_text(report, m)}, {100 * share:.3g} % of the samples (gaps are marked as"
                f" missing samples by default up to {100 * AUTO_MARK_SHARE:g} %); "
                + hints.replace("to mark the missing samples", "to mark them all the same"))
        if gaps == "refuse":
            raise DataError(f"{path}: {_gap_text(report, m)}; {hints}")
        if gaps == "split":
            raise DataError(f"{path}: {len(report.gaps)} gap(s); out of core the log is not split into its"
                            " gap-free segments (the longest is analysed whole, in memory): use"
                            f" {option_hint('--gaps mark', repr_kw('gaps', 'mark'))} to keep the missing"
                            " samples as gaps, or read it in memory with"
                            f" {option_hint('--memory in', repr_kw('memory', 'in'))}")
        if gaps in ("auto", "mark"):
            hold = AUTO_HOLD_SAMPLES if gaps == "auto" else 0
            held = np.array([g.missing <= hold for g in report.gaps], dtype=bool)
            inserted = [(g.index, g.missing, bool(h)) for g, h in zip(report.gaps, held.tolist())]
            report = _marked(report, held, hold)
        else:
            report = replace(report, actions=report.actions + (f"ignored {len(report.gaps)} gap(s)",))
    elif gaps == "auto":
        report = replace(report, gaps_policy="mark")
    return _row_map(n, dropped, inserted, report.samples), report, time_origin


def _summary(time: Reader, n: int, unit: str, dropped: np.ndarray, m: int, origin: np.ndarray,
             rate: float | None, rate_source: str, rows: int, gap_threshold: float, path: str,
             warnings: list[str]) -> TimingReport:
    """:func:`sigmatau.io._timing._summarise` of the kept timestamps, from three passes or more."""
    count = m - 1
    ks = (count // 2,) if count % 2 else (count // 2 - 1, count // 2)
    middle = _kth(time, n, unit, ks)
    step = float(np.mean(np.array(middle)))  # numpy's median: the mean of the middle one or two
    measured = float(f"{1.0 / step:.12g}")
    nominal = measured if rate is None else rate
    if rate is not None and abs(rate / measured - 1.0) > _RATE_TOLERANCE:
        warnings.append(
            f"{path}: the {rate_source} rate {_fmt(rate)} Hz differs from the {_fmt(measured)} Hz"
            f" measured from the timestamps by {100 * abs(rate / measured - 1):.3g} %"
        )
    limit = gap_threshold * step
    found: list[Gap] = []
    spread = _Spread()
    for dt, ranks, left in _steps(time, n, unit):
        is_gap = dt > limit
        for j in np.flatnonzero(is_gap).tolist():
            t_left = float(to_seconds(np.asarray([left[j]]) - origin, unit)[0])
            found.append(Gap(index=int(ranks[j]) + 1, time=t_left, duration=float(dt[j]),
                             missing=max(int(round(float(dt[j]) * measured)) - 1, 1)))
        spread.add(dt[~is_gap] - step)
    span = float(to_seconds(time(n - 1, n) - origin, unit)[0])
    return TimingReport(
        samples=m, rows=rows, rate=float(nominal), rate_source="timestamps" if rate is None else rate_source,
        measured_rate=measured, mean_rate=float((m - 1) / span) if span > 0 else None, span=span,
        jitter_rms=math.sqrt(spread.m2 / spread.count) if spread.count else None,
        jitter_max=spread.largest if spread.count else None,
        gaps=tuple(found), gap_threshold=gap_threshold,
    )


def _marked(report: TimingReport, held: np.ndarray, hold: int) -> TimingReport:
    """The report of :func:`sigmatau.io._timing._marked`: samples, gaps at their new index, actions."""
    counts = np.array([g.missing for g in report.gaps], dtype=np.int64)
    where = np.array([g.index for g in report.gaps], dtype=np.int64)
    before = np.concatenate(([0], np.cumsum(counts)))  # samples inserted before each gap
    new_index = where + before[1:]
    gaps = tuple(replace(g, index=int(i), missing=int(k))
                 for g, i, k, h in zip(report.gaps, new_index.tolist(), counts.tolist(), held.tolist()) if not h)
    actions = list(report.actions)
    if held.any():
        actions.append(f"held the sample before each of {int(held.sum())} gap(s) of at most {hold} sample(s)"
                       f" ({int(counts[held].sum())} sample(s))")
    if gaps:
        actions.append(f"marked {int(counts[~held].sum())} missing sample(s) in {len(gaps)} gap(s) as NaN on the"
                       f" {_fmt(report.rate)} Hz grid")
    return replace(report, samples=int(report.samples + counts.sum()), gaps=gaps, gaps_policy="mark",
                   actions=tuple(actions))


def _row_map(n: int, dropped: np.ndarray, inserted: list[tuple[int, int, bool]], size: int) -> RowMap | None:
    """The pieces of the analysed log: runs of kept rows, split where ``inserted`` — (index among the
    kept samples of the sample after the gap, samples inserted, held) — puts missing or held samples."""
    d = dropped
    if d.size:
        brk = np.flatnonzero(np.diff(d) != 1) + 1
        run_start, run_end = d[np.r_[0, brk]], d[np.r_[brk - 1, d.size - 1]] + 1
        src_start, src_end = np.r_[0, run_end], np.r_[run_start, n]
    else:
        src_start, src_end = np.array([0]), np.array([n])
    keep = src_end > src_start
    src_start, src_end = src_start[keep], src_end[keep]
    if not inserted and src_start.size == 1:
        return None
    kept_start = np.concatenate(([0], np.cumsum(src_end - src_start)[:-1]))
    g_at = np.array([g for g, _, _ in inserted], dtype=np.int64)
    g_k = np.array([k for _, k, _ in inserted], dtype=np.int64)
    cum = np.concatenate(([0], np.cumsum(g_k)))

    def row(j: np.ndarray) -> np.ndarray:  # the file's row of kept sample j
        r = np.searchsorted(kept_start, j, side="right") - 1
        return src_start[r] + (j - kept_start[r])

    bounds = np.union1d(kept_start, g_at)
    starts = [bounds + cum[np.searchsorted(g_at, bounds, side="right")]]
    srcs, steps = [row(bounds)], [np.ones(bounds.size, dtype=np.int64)]
    if inserted:
        held = np.array([h for _, _, h in inserted], dtype=bool)
        starts.append(g_at + cum[1:] - g_k)
        srcs.append(np.where(held, row(g_at - 1), -1))
        steps.append(np.zeros(g_at.size, dtype=np.int64))
    o = np.concatenate(starts)
    order = np.argsort(o, kind="stable")
    return RowMap(o[order].astype(np.int64), np.concatenate(srcs)[order].astype(np.int64),
                  np.concatenate(steps)[order].astype(np.int64), int(size))
