"""Lines of a live text log parsed as :func:`sigmatau.io.read` parses a file, and its timing checked as they come.

:class:`LiveReader` takes the whole lines of a :class:`~sigmatau.io.follow.LiveSource` and

* keeps the first lines until it can tell the layout as the CSV reader does (:class:`LiveLayout`:
  the same sniffing of delimiter, header, units line and numeric columns, the same choice of time
  and channel columns, canonical IMU names, groups and units — the reader itself is run on those
  lines), from :data:`SNIFF_ROWS` data rows, or fewer once :data:`SNIFF_WAIT` seconds have passed;
* parses every later line with the reader's own chunk parser; a line the reader would refuse (a
  wrong number of fields, a value that is not a number, an infinite value, a bad timestamp) is
  left out of the record with a notice instead of ending the run, so the record stays readable;
* checks the timestamps as they arrive (:class:`LiveTiming`) with the policies of the batch readers
  (``gaps``, ``gap_threshold``, ``unsorted``, ``duplicates``): a policy ``refuse`` ends the run with
  the batch reader's kind of message; otherwise each gap, backward or repeated timestamp and large
  jitter is a notice, and the samples handed on for the live statistics are placed on the time grid
  (missing ones NaN, or held under ``gaps="auto"`` for gaps of at most 5 samples, as the batch
  policy does; backward and repeated ones left out — the final analysis sorts and de-duplicates);
* hands back the bytes of every accepted line for the record, which the final analysis reads with
  :func:`read_record` — the very reader of :func:`sigmatau.io.read`, so that on a file nothing was
  left out of, the final analysis is that of the finished file, bit for bit.

Layer: :mod:`sigmatau.io`.
"""

from __future__ import annotations

import io
import math
import time
import warnings as _warnings
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Mapping, Optional

import numpy as np

from ..errors import DataError, ParameterError, SigmaTauError
from ._errors import FormatError, TimingWarning, option_hint, repr_kw
from ._model import SensorLog
from ._progress import Progress
from ._read import MIN_SAMPLES, _finish, _options, _read_table
from ._registry import detect
from ._sniff import (
    _COMMENTS, _INT, _SNIFF_MAX_LINES, _SNIFF_ROWS, _Sniff, _check_lengths, _is_num, _read_head, _split, _strip_comment,
)
from ._text import _choose_columns, _parse_chunk, read_csv, read_stable32
from ._timing import AUTO_HOLD_SAMPLES, AUTO_MARK_SHARE, to_seconds
from .follow import NEW_CONTENT, LiveSource

__all__ = ["SNIFF_ROWS", "SNIFF_WAIT", "LiveLayout", "LiveTiming", "LiveReader", "Step", "read_record"]

#: Data rows the layout is told from, as the batch reader does (its first 200).
SNIFF_ROWS = _SNIFF_ROWS
#: Seconds after the first line after which fewer rows (at least MIN_SAMPLES) are enough.
SNIFF_WAIT = 5.0
#: A step this far from the median step (relative) but below the gap threshold is reported as jitter.
JITTER_NOTICE = 0.25


def _text_of(line: bytes, first: bool) -> str:
    """A line as the reader's text layer sees it: UTF-8 (errors replaced), BOM and CR removed."""
    s = line.decode("utf-8", errors="replace")
    if first and s.startswith("\ufeff"):
        s = s[1:]
    if s.endswith("\r\n"):
        s = s[:-2] + "\n"
    return s


def _is_row(s: str) -> bool:
    t = s.strip()
    return bool(t) and not t.startswith(_COMMENTS)


@dataclass
class LiveLayout:
    """The layout of a text log told from its first lines, as :func:`sigmatau.io.read` tells it.

    Attributes
    ----------
    log : SensorLog
        The first lines read by the reader itself: channel names, groups, units, data type, rate,
        time unit (``log.timing``).
    columns : list of str
        The file's column names (``col0`` … without a header).
    channels : list of str
        Canonical channel names, in the order of the parsed value columns.
    time_unit : str or None
        Unit of the time column (None without one).
    data_line : int
        Line of the first data row (1-based); the lines before it are the preamble.
    """

    log: SensorLog
    columns: list
    channels: list
    time_unit: Optional[str]
    data_line: int
    sniff: Any = field(repr=False, default=None)
    usecols: list = field(repr=False, default_factory=list)
    dtype: Any = field(repr=False, default=None)
    int_time: bool = False
    quoted: bool = False
    has_time: bool = False
    display: str = ""

    @classmethod
    def tell(cls, head: list, *, path: Path, display: str, options: Mapping[str, Any]) -> tuple["LiveLayout", list]:
        """The layout of the first lines ``head`` (bytes) and the reader's warnings about them.

        ``path`` names the record (its extension chooses the reader; it is not read).

        Raises what :func:`sigmatau.io.read` raises for such a file (FormatError, DataError,
        ParameterError); the caller decides whether more lines could change that.
        """
        opts = _options(**{**_DEFAULTS, **options})
        raw = b"".join(head)
        for magic, kind in ((b"\x1f\x8b", "gzip"), (b"BZh", "bzip2"), (b"\xfd7zXZ\x00", "xz")):
            if raw.startswith(magic):
                raise FormatError(f"{display}: is {kind}-compressed; sigmatau watch follows plain text as it grows"
                                  " (read the compressed log with sigmatau analyze)")
        fmt, auto = detect(path, display, head=raw[:8192])
        if opts.format is not None:
            fmt, auto = opts.format, False
        if fmt not in ("csv", "stable32"):
            raise FormatError(f"{display}: looks like a {fmt} file; sigmatau watch follows text logs (CSV/TSV/text,"
                              " Stable32 data); read other formats with sigmatau analyze")
        texts = [_text_of(b, i == 0) for i, b in enumerate(head)]
        lines = _read_head(io.StringIO("".join(texts)), display)
        sniff = _Sniff(lines, opts.delimiter, display, opts.delimiter is not None)
        flavour = None if (auto and fmt == "csv") else fmt
        cols = _choose_columns(display, opts, flavour, sniff)
        # The reader on the same lines, with lenient timing: the live checks apply the policies.
        lenient = replace(opts, gaps="mark", unsorted="sort", duplicates="drop", allow_nan=True)
        reader = read_csv if fmt == "csv" else read_stable32
        with Progress(None, "", enabled=False) as bar:
            table = reader(path, display, lenient, bar, auto=auto and fmt == "csv", stream=io.BytesIO(raw))
        messages: list = []
        log = _finish(table, lenient, display, messages)
        names = sniff.names
        original = {v: k for k, v in log.original_names.items()}
        channels = [original[names[j]] for j in cols.channels]
        int_time = False
        if cols.time is not None:
            values = [f[cols.time] for f in sniff.tail]
            int_time = all(_INT.match(v) for v in values) and max(abs(int(v)) for v in values) > 2**53
        k = len(cols.channels)
        dtype = (np.dtype([("t", "<i8")] + [(f"c{c}", "<f8") for c in range(k)]) if int_time
                 else np.dtype(np.float64))
        start = sniff.data_line - 1
        layout = cls(log=log, columns=list(names), channels=channels,
                     time_unit=log.timing.time_unit if cols.time is not None else None, data_line=sniff.data_line,
                     sniff=sniff, usecols=([cols.time] if cols.time is not None else []) + list(cols.channels),
                     dtype=dtype, int_time=int_time, quoted=any('"' in s for s in lines[start:]),
                     has_time=cols.time is not None, display=display)
        return layout, [text for text, category in messages if not issubclass(category, TimingWarning)]

    def parse(self, texts: list, first_line: int) -> tuple[np.ndarray, list]:
        """Parse lines of text; returns the rows and, for each line left out, ``(index, why)``.

        Rows are the reader's: a structured array with ``"t"`` when the timestamps are large
        integers, else float64 of shape (rows, time + channels). A line the reader would refuse
        — not parsed, an infinite value, a timestamp that is not finite — is left out.
        """
        try:
            rows = self._chunk(texts, first_line)
        except DataError:
            pass
        else:
            if self._finite(rows).all():
                return rows, []
        kept, bad = [], []
        for i, s in enumerate(texts):
            try:
                one = self._chunk([s], first_line + i)
            except DataError as exc:
                bad.append((i, str(exc)))
                continue
            if not self._finite(one).all():
                bad.append((i, f"{self.display}: line {first_line + i}: an infinite value or a timestamp that is"
                               " not finite"))
            elif len(one):
                kept.append(one)
        empty = np.empty(0, dtype=self.dtype) if self.int_time else np.empty((0, len(self.usecols)))
        return (np.concatenate(kept) if kept else empty), bad

    def _finite(self, rows: np.ndarray) -> np.ndarray:
        """Per row: no infinite value, and a finite timestamp (NaN values are missing samples)."""
        _, values = self.split_rows(rows)
        ok = ~np.isinf(values).any(axis=1) if values.size else np.ones(len(rows), dtype=bool)
        if self.has_time and not self.int_time:
            ok &= np.isfinite(rows[:, 0])
        return ok

    def _chunk(self, texts: list, first_line: int) -> np.ndarray:
        _check_lengths(texts, first_line, self.display)
        return _parse_chunk(texts, first_line, self.sniff, self.usecols, self.dtype, self.quoted, self.int_time,
                            self.display)

    def header_differs(self, text: str) -> bool:
        """Whether a preamble line of new content is a header naming other columns than ours."""
        sniff = self.sniff
        if not sniff.has_header:
            return False
        body = text.strip()
        for mark in _COMMENTS:
            if body.startswith(mark):
                body = body[len(mark):].strip()
                break
        fields = [body] if sniff.ncols == 1 else _split(body, sniff.delimiter)
        if len(fields) != sniff.ncols or all(_is_num(f) for f in fields):
            return False
        return _Sniff._names(fields, sniff.ncols) != list(sniff.names)

    def split_rows(self, rows: np.ndarray) -> tuple[Optional[np.ndarray], np.ndarray]:
        """Raw timestamps (or None) and the values (rows, channels) of parsed rows."""
        if self.int_time:
            return rows["t"].copy(), np.column_stack([rows[f"c{c}"] for c in range(len(self.channels))])
        if self.has_time:
            return rows[:, 0].copy(), rows[:, 1:]
        return None, rows


_DEFAULTS = dict(format=None, columns=None, time_column=None, time_unit=None, rate=None, data_type=None, units=None,
                 topic=None, dataset=None, stamps=None, gaps="auto", gap_threshold=1.5, unsorted="sort",
                 duplicates="drop", allow_nan=False, delimiter=None, progress=False)


def _fmt(x: float) -> str:
    return f"{x:.6g}"


class LiveTiming:
    """The timing checks of :mod:`sigmatau.io._timing`, one chunk of timestamps at a time.

    The median step is the one of the first rows (those the layout was told from); each later step
    is compared with it. Counts and jitter accumulate in :meth:`summary`.
    """

    def __init__(self, *, unit: str, measured_rate: float, gaps: str, gap_threshold: float, unsorted: str,
                 duplicates: str, display: str) -> None:
        self.unit, self.rate, self.display = unit, float(measured_rate), display
        self.step = 1.0 / self.rate
        self.gaps, self.threshold, self.unsorted, self.duplicates = gaps, gap_threshold, unsorted, duplicates
        self.last: Any = None  # largest raw timestamp so far
        self.first: Any = None
        self.last_values: Optional[np.ndarray] = None
        self.rows = self.samples = self.out_of_order = self.repeated = self.n_gaps = self.missing = 0
        self.held = 0
        self._jit_n, self._jit_sum, self._jit_sq, self.jitter_max = 0, 0.0, 0.0, 0.0
        self.jitter_events = 0
        self._share_said = False

    def _where(self, i: int, raw: np.ndarray, k: int) -> str:
        v = raw[k]
        return f"sample {i} (t = {int(v) if raw.dtype.kind in 'iu' else _fmt(float(v))})"

    def _seconds(self, raw_value: Any) -> float:
        return float(to_seconds(np.array([raw_value - self.first]), self.unit)[0])

    def feed(self, raw: np.ndarray, values: np.ndarray) -> tuple[np.ndarray, list]:
        """Check one chunk; returns the samples for the live statistics and the notices ``(kind, text)``."""
        if raw.size and self.first is None:  # the first sample: no step before it
            self.first = self.last = raw[0]
            self.last_values = values[0].copy()
            self.rows = self.samples = 1
            rest, notices = self.feed(raw[1:], values[1:])
            return np.concatenate([values[:1], rest]), notices
        notices: list = []
        if raw.size == 0:
            return values[:0], notices
        # prev[i]: the latest timestamp before sample i, which is the last sample kept
        prev = np.maximum.accumulate(np.concatenate((np.array([self.last], dtype=raw.dtype), raw[:-1])))
        kept = raw > prev
        self._disorder(raw, prev, raw < prev, raw == prev, self.rows, notices)
        steps = to_seconds(raw[kept] - prev[kept], self.unit)
        out = self._on_grid(values[kept], steps, raw[kept], np.flatnonzero(kept) + self.rows, notices)
        self.rows += raw.size
        self.samples += int(kept.sum())
        self.last = max(self.last, raw.max())
        return out, notices

    def _disorder(self, raw: np.ndarray, prev: np.ndarray, back: np.ndarray, same: np.ndarray, base: int,
                  notices: list) -> None:
        nb, nd = int(back.sum()), int(same.sum())
        if nb:
            k = int(np.flatnonzero(back)[0])
            text = f"timestamp goes backwards at {self._where(base + k, raw, k)}, after {prev[k]}"
            if self.unsorted == "refuse":
                raise DataError(f"{self.display}: {text}; to sort the samples by time use"
                                f" {option_hint('--unsorted sort', repr_kw('unsorted', 'sort'))}")
            self.out_of_order += nb
            notices.append(("backwards", f"{text} ({nb} in this chunk); left out of the live view, the final"
                                         " analysis sorts the samples by time"))
        if nd:
            k = int(np.flatnonzero(same)[0])
            text = f"{self._where(base + k, raw, k)} repeats the timestamp before it"
            if self.duplicates == "refuse":
                raise DataError(f"{self.display}: {text}; to keep the first of each use"
                                f" {option_hint('--duplicates drop', repr_kw('duplicates', 'drop'))}")
            self.repeated += nd
            notices.append(("duplicate", f"{text} ({nd} in this chunk); the first of each is kept"))

    def _on_grid(self, values: np.ndarray, steps: np.ndarray, raw: np.ndarray, index: np.ndarray,
                 notices: list) -> np.ndarray:
        """The kept samples with the missing ones of each gap inserted (NaN, or held), per policy."""
        is_gap = steps > self.threshold * self.step
        ok = steps[~is_gap] - self.step
        if ok.size:
            self._jit_n += ok.size
            self._jit_sum += float(ok.sum())
            self._jit_sq += float(np.dot(ok, ok))
            big = np.abs(ok) > JITTER_NOTICE * self.step
            self.jitter_max = max(self.jitter_max, float(np.abs(ok).max()))
            if big.any():
                self.jitter_events += int(big.sum())
                j = int(np.flatnonzero(~is_gap)[np.flatnonzero(big)[0]])
                notices.append(("jitter", f"step of {_fmt(steps[j])} s before sample {int(index[j])}, more than"
                                          f" {100 * JITTER_NOTICE:g} % off the median step {_fmt(self.step)} s"
                                          f" ({self.jitter_events} such steps so far)"))
        gi = np.flatnonzero(is_gap)
        if gi.size == 0:
            self.last_values = values[-1].copy() if len(values) else self.last_values
            return values
        counts = np.maximum(np.rint(steps[gi] * self.rate).astype(np.int64) - 1, 1)
        k = int(gi[0])
        text = (f"gap of {_fmt(steps[k])} s before sample {int(index[k])} (t = {_fmt(self._seconds(raw[k]))} s;"
                f" {int(counts[0])} samples missing)")
        if self.gaps == "refuse":
            raise DataError(f"{self.display}: {text}; to mark the missing samples use"
                            f" {option_hint('--gaps mark', repr_kw('gaps', 'mark'))}, to analyse the gap-free"
                            f" segments {option_hint('--gaps split', repr_kw('gaps', 'split'))}, to analyse"
                            f" across the gaps {option_hint('--gaps ignore', repr_kw('gaps', 'ignore'))}")
        self.n_gaps += int(gi.size)
        self.missing += int(counts.sum())
        more = f" and {gi.size - 1} more in this chunk" if gi.size > 1 else ""
        what = {"ignore": "analysed across (--gaps ignore)", "split": "the final analysis keeps the longest"
                " gap-free segment (--gaps split)"}.get(self.gaps, "marked as missing samples")
        notices.append(("gap", f"{text}{more}; {what}"))
        self._share(notices)
        if self.gaps == "ignore":
            self.last_values = values[-1].copy()
            return values
        return self._inserted(values, gi, counts)

    def _inserted(self, values: np.ndarray, gi: np.ndarray, counts: np.ndarray) -> np.ndarray:
        hold = AUTO_HOLD_SAMPLES if self.gaps == "auto" else 0
        pos = np.arange(len(values)) + np.cumsum(np.bincount(gi, weights=counts, minlength=len(values))
                                                 ).astype(np.int64)
        out = np.full((len(values) + int(counts.sum()), values.shape[1]), np.nan)
        out[pos] = values
        for g, c in zip(gi.tolist(), counts.tolist()):
            if c <= hold:
                before = values[g - 1] if g > 0 else self.last_values
                if before is not None:
                    out[pos[g] - c:pos[g]] = before
                    self.held += c
        self.last_values = values[-1].copy()
        return out

    def _share(self, notices: list) -> None:
        share = self.missing / max(self.samples + self.missing, 1)
        if self.gaps == "auto" and share > AUTO_MARK_SHARE and not self._share_said:
            self._share_said = True
            notices.append(("gap", f"{100 * share:.3g} % of the samples are missing so far: beyond"
                                   f" {100 * AUTO_MARK_SHARE:g} % the final analysis refuses the log unless"
                                   " --gaps mark, split or ignore is given"))

    def summary(self) -> dict:
        """Counts, span and jitter so far (JSON-ready)."""
        n = self._jit_n
        rms = math.sqrt(max(self._jit_sq / n - (self._jit_sum / n) ** 2, 0.0)) if n else None
        return {"rows": self.rows, "samples": self.samples, "measured_rate": self.rate,
                "span": self._seconds(self.last) if self.first is not None else 0.0,
                "gaps": self.n_gaps, "missing": self.missing, "held": self.held,
                "out_of_order": self.out_of_order, "duplicates": self.repeated,
                "jitter_rms": rms, "jitter_max": self.jitter_max if n else None, "jitter_events": self.jitter_events}


@dataclass
class Step:
    """What :meth:`LiveReader.step` accepted.

    Attributes
    ----------
    record : bytes
        The accepted lines, as they came, for the record.
    samples : numpy.ndarray or None
        Samples for the live statistics, (rows, channels), on the time grid (NaN where missing).
    notices : list of (kind, text)
    eof : bool
        The input ended.
    grew : bool
        Bytes arrived.
    """

    record: bytes = b""
    samples: Optional[np.ndarray] = None
    notices: list = field(default_factory=list)
    eof: bool = False
    grew: bool = False


class LiveReader:
    """Lines of a :class:`~sigmatau.io.follow.LiveSource` → layout, checked samples and the record.

    Parameters
    ----------
    source : LiveSource
    options : mapping
        Keyword options of :func:`sigmatau.io.read` (``columns``, ``time_column``, ``rate``,
        ``units``, ``gaps`` …), checked already.
    record : Path
        Where the caller keeps the record (a regular file): its name chooses the reader as the
        file's own name would.
    """

    def __init__(self, source: LiveSource, options: Mapping[str, Any], record: Path) -> None:
        self.source = source
        self.record = record
        self._nan_said = False
        self.options = dict(options)
        self.layout: Optional[LiveLayout] = None
        self.timing: Optional[LiveTiming] = None
        self._head: list = []
        self._head_rows = 0
        self._first_at: Optional[float] = None
        self._tried_rows = 0
        self._line = 0  # lines of the current content seen
        self._preamble = False  # new content: skip its header lines
        self.dropped = 0
        self.ended = False  # the content can no longer be read as the same table
        self.samples = 0
        self.undelivered = b""

    def step(self, timeout: float) -> Step:
        """Poll the source once and take what it brought.

        When a policy refuses the input (or the layout cannot be told), the lines accepted before
        the refusal are left in :attr:`undelivered` for the record.
        """
        poll = self.source.poll(timeout)
        out = Step(notices=list(poll.notices), eof=poll.eof, grew=poll.grew)
        try:
            self._take(poll.lines, out)
        except SigmaTauError:
            self.undelivered = out.record + b"".join(self._head)
            raise
        return out

    def finish(self, *, end_of_input: bool) -> Step:
        """The end of the run: the layout told from whatever came, and the unfinished last line
        parsed when the input really ended (``end_of_input``), else left out with a notice."""
        out = Step()
        rest = self.source.rest()
        if rest and not self.ended:
            if end_of_input:
                self._take([rest], out)
            else:
                out.notices.append(("partial", f"the unfinished last line ({len(rest):,} bytes, no newline yet)"
                                               " is left out"))
        if self.layout is None and self._head:
            try:
                self._tell(out, force=True)
            except SigmaTauError:  # the final read words it
                out.record += b"".join(self._head)
                self._head = []
        return out

    def _take(self, lines: list, out: Step) -> None:
        if self.ended:
            return
        for piece in _pieces(lines):
            if piece is NEW_CONTENT:
                self._preamble = True
                self._line = 0
                continue
            if self.layout is None:
                self._collect(piece, out)
            else:
                self._data(piece, out)
            if self.ended:
                return

    def _collect(self, lines: list, out: Step) -> None:
        """Lines before the layout is known: kept until it can be told."""
        if self._first_at is None:
            self._first_at = time.monotonic()
        self._head.extend(lines)
        self._line += len(lines)
        self._head_rows += sum(_is_row(_text_of(b, False)) for b in lines)
        waited = time.monotonic() - self._first_at >= SNIFF_WAIT
        enough = self._head_rows >= SNIFF_ROWS or len(self._head) >= _SNIFF_MAX_LINES
        if enough or (waited and self._head_rows >= max(MIN_SAMPLES, 1.5 * self._tried_rows)):
            self._tell(out, force=enough)

    def _tell(self, out: Step, force: bool) -> None:
        self._tried_rows = self._head_rows
        try:
            with _warnings.catch_warnings():
                _warnings.simplefilter("ignore")
                layout, messages = LiveLayout.tell(self._head, path=self.record, display=self.source.display,
                                                   options=self.options)
        except ParameterError:
            raise
        except SigmaTauError:
            if force:
                raise
            return
        self.layout = layout
        out.notices.extend(("columns", m) for m in messages)
        log = layout.log
        if layout.has_time:
            o = {**_DEFAULTS, **self.options}
            self.timing = LiveTiming(unit=layout.time_unit or "s", measured_rate=log.timing.measured_rate or log.rate,
                                     gaps=o["gaps"], gap_threshold=float(o["gap_threshold"]),
                                     unsorted=o["unsorted"], duplicates=o["duplicates"],
                                     display=self.source.display)
        head, self._head = self._head, []
        cut = layout.data_line - 1
        out.record += b"".join(head[:cut])
        self._parse(head[cut:], layout.data_line, out)

    def _data(self, lines: list, out: Step) -> None:
        first = self._line + 1
        self._line += len(lines)
        if self._preamble:
            lines, first = self._skip_preamble(lines, first, out)
            if not lines:
                return
        self._parse(lines, first, out)

    def _skip_preamble(self, lines: list, first: int, out: Step) -> tuple[list, int]:
        """New content (rotation, truncation): its lines before the first data row are left out of
        the record (its header would be read as a bad row); a header naming other columns ends it."""
        layout = self.layout
        assert layout is not None
        for i, b in enumerate(lines):
            s = _text_of(b, first + i == 1)
            if not _is_row(s):
                continue
            rows, bad = layout.parse([s], first + i)
            if len(rows):
                self._preamble = False
                return lines[i:], first + i
            if layout.header_differs(s):
                self.ended = True
                out.eof = True
                out.notices.append(("columns", f"{self.source.display}: the new content has other columns"
                                               f" ({_strip_comment(s).strip()[:200]!r}); stopped reading it"))
                return [], first
        return [], first

    def _parse(self, lines: list, first: int, out: Step) -> None:
        layout = self.layout
        assert layout is not None
        texts = [_text_of(b, first + i == 1) for i, b in enumerate(lines)]
        rows, bad = layout.parse(texts, first)
        left_out = {i for i, _ in bad}
        for _, why in bad:
            self.dropped += 1
            out.notices.append(("bad-line", f"{why}; left out of the record"))
        out.record += b"".join(b for i, b in enumerate(lines) if i not in left_out) if left_out else b"".join(lines)
        if len(rows) == 0:
            return
        raw, values = layout.split_rows(rows)
        if not self._nan_said and np.isnan(values).any():
            self._nan_said = True
            policy = {**_DEFAULTS, **self.options}["gaps"]
            later = ("" if policy in ("auto", "mark") else
                     f"; the final analysis refuses them under --gaps {policy} (use --gaps mark)")
            out.notices.append(("gap", f"{self.source.display}: NaN values (missing samples) from line"
                                       f" {first} on{later}"))
        if self.timing is not None and raw is not None:
            values, notices = self.timing.feed(raw, values)
            out.notices.extend(notices)
        self.samples += len(values)
        out.samples = values if out.samples is None else np.concatenate([out.samples, values])


def _pieces(lines: list) -> list:
    """``lines`` cut at each NEW_CONTENT marker: lists of lines, with the markers between them."""
    out: list = []
    cur: list = []
    for b in lines:
        if b is NEW_CONTENT or b == NEW_CONTENT:
            if cur:
                out.append(cur)
                cur = []
            out.append(NEW_CONTENT)
        else:
            cur.append(b)
    if cur:
        out.append(cur)
    return out


def read_record(path: Path, display: str, options: Mapping[str, Any]) -> SensorLog:
    """The record of a watched source read as :func:`sigmatau.io.read` reads a file, named ``display``.

    The same reader, options, policies, warnings and errors as ``read(path, **options)``; only the
    name in the log's source and in the messages is the source's, not the record's copy.
    """
    opts = _options(**{**_DEFAULTS, **options})
    if path.stat().st_size == 0:
        raise DataError(f"{display}: no data arrived")
    table = _read_table(path, display, opts, opts.format, False, None)
    messages: list = []
    log = _finish(table, opts, display, messages)
    for text, category in messages:
        _warnings.warn(text, category, stacklevel=2)
    return log


