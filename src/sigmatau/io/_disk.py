"""Logs larger than memory: :func:`open_log` gives a :class:`DiskLog`, whose channels are read in pieces.

The same file, options and checks as :func:`sigmatau.io.read`, without loading the samples:

* ``.npy`` (1-D, 2-D in C or Fortran order, structured) and ``.npz`` archives whose members are
  stored uncompressed (``numpy.savez``): each channel is read from its bytes in the file; a
  compressed member (``numpy.savez_compressed``) cannot be read piecewise and is refused in one line;
* HDF5: slices of the datasets (the file stays open until :meth:`DiskLog.close`);
* CSV, TSV, whitespace text and Stable32 files, plain or compressed: read once, in chunks, by the
  text reader's own parsers (:mod:`._text`, pyarrow's exact fast path when it applies), into one
  float64 ``.npy`` file per column in a private temporary directory (:mod:`._disktext`), removed
  by :meth:`DiskLog.close`.

Column choice, names, groups and units are those of :func:`~sigmatau.io.read` (the same
functions); NaN and infinite cells follow the same rule, counted chunk by chunk; the timestamps
go through the same policies (:mod:`._disktiming`): duplicates dropped, gaps marked as NaN or
held, the rate from the median step — except that timestamps going backwards and
``gaps="split"`` are refused with the options that work. :func:`log_size` tells the size of a log
from its headers (or, for text, its first lines and its size) before anything is read.
"""

from __future__ import annotations

import os
import shutil
import threading
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping, Optional

import numpy as np

from ..errors import DataError, ParameterError
from ._disklayout import Layout, Reader, as_dtype, hdf5_layout, npy_layout, npz_layout
from ._disktext import convert, text_size
from ._disktiming import CHUNK_ROWS, RowMap, process_streamed, scan_times
from ._errors import InputWarning, TimingWarning, option_hint, repr_kw
from ._model import Source, TimingReport
from ._read import (MIN_SAMPLES, PathLike, _channel_units, _grouped, _names_groups, _options, _resolve,
                    check_format_options, non_finite_column, untimed_report)
from ._registry import Options, detect, file_sha256
from ._stream import is_once
from ._timing import infer_time_unit

__all__ = ["DiskChannel", "DiskLog", "LogSize", "open_log", "log_size", "OUT_OF_CORE_FORMATS"]


#: Formats :func:`open_log` reads without loading them.
OUT_OF_CORE_FORMATS = ("npy", "npz", "hdf5", "csv", "stable32")


class DiskChannel:
    """One channel of a :class:`DiskLog`: ``n`` float64 samples (NaN for gaps) read in pieces.

    Attributes
    ----------
    name : str
    n : int
        Number of samples.
    """

    def __init__(self, name: str, n: int, read: Reader, state: "_State") -> None:
        self.name = name
        self.n = int(n)
        self._read = read
        self._state = state

    def __len__(self) -> int:
        return self.n

    def __repr__(self) -> str:
        return f"DiskChannel({self.name!r}, n={self.n})"

    def read(self, start: int, stop: int) -> np.ndarray:
        """Samples ``start … stop-1`` as a new float64 array.

        Raises
        ------
        DataError
            The log was closed, or the analysis reading it was cancelled.
        """
        if self._state.closed:
            raise DataError(f"channel {self.name!r}: the log was closed (its temporary files removed)")
        if self._state.cancelled:
            raise DataError(f"channel {self.name!r}: the analysis was cancelled")
        return np.asarray(self._read(int(start), int(stop)), dtype=np.float64)


@dataclass
class _State:
    closed: bool = False
    cancelled: bool = False
    closers: list = field(default_factory=list)
    lock: Any = field(default_factory=threading.Lock)


@dataclass(frozen=True, eq=False, repr=False)
class DiskLog:
    """A sensor log whose samples stay on disk: what :class:`SensorLog` says about a log, with channels
    that are read in pieces (:class:`DiskChannel`). Close it (or use ``with``) to release the file
    and remove the temporary files of a text log.

    Attributes
    ----------
    channels : mapping of str to DiskChannel
    rate, groups, units, data_type, source, timing, unit_origin, original_names, time_origin
        As for :class:`SensorLog`.
    workdir : str or None
        The private temporary directory holding a text log's columns (removed on close).
    """

    channels: Mapping[str, DiskChannel]
    rate: float
    groups: Mapping[str, tuple[str, ...]]
    units: Mapping[str, str]
    data_type: str
    source: Source
    timing: TimingReport
    unit_origin: Mapping[str, str] = field(default_factory=dict)
    original_names: Mapping[str, str] = field(default_factory=dict)
    time_origin: Optional[float] = None
    workdir: Optional[str] = None
    _state: _State = field(default_factory=_State)

    #: No timestamps are held: the samples are on the rate's grid (gaps marked as NaN).
    timestamps = None

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(self.channels)

    def __len__(self) -> int:
        return next(iter(self.channels.values())).n if self.channels else 0

    def __getitem__(self, name: str) -> DiskChannel:
        try:
            return self.channels[name]
        except KeyError:
            raise ParameterError(f"no channel {name!r}; channels are: {', '.join(self.channels)}") from None

    def __contains__(self, name: object) -> bool:
        return name in self.channels

    def __enter__(self) -> "DiskLog":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __repr__(self) -> str:
        return (f"DiskLog({self.source.format} {self.source.path!r}, {len(self.channels)} channels × {len(self)}"
                f" samples at {self.rate:.6g} Hz, on disk)")

    def group_of(self, name: str) -> str:
        """The group a channel belongs to."""
        for group, names in self.groups.items():
            if name in names:
                return group
        return "other"

    def to_dict(self) -> dict[str, Any]:
        """Everything but the samples, as plain Python (the keys of :meth:`SensorLog.to_dict`)."""
        return {
            "source": vars(self.source).copy() | {"columns": list(self.source.columns),
                                                  "unused_columns": list(self.source.unused_columns)},
            "rate": self.rate, "data_type": self.data_type, "n_samples": len(self),
            "channels": list(self.channels), "groups": {k: list(v) for k, v in self.groups.items()},
            "units": dict(self.units), "unit_origin": dict(self.unit_origin),
            "original_names": dict(self.original_names), "time_origin": self.time_origin,
            "timing": self.timing.to_dict(),
        }

    def cancel(self) -> None:
        """Make every further read fail (an analysis interrupted: its threads stop at their next read)."""
        self._state.cancelled = True

    def close(self) -> None:
        """Release the file and remove the temporary directory (idempotent)."""
        with self._state.lock:
            if self._state.closed:
                return
            self._state.closed = True
            closers, self._state.closers[:] = list(self._state.closers), []
        for close in reversed(closers):
            close()


@dataclass(frozen=True)
class LogSize:
    """The size of a log before it is read (:func:`log_size`).

    Attributes
    ----------
    rows : int
        Rows (samples before the timing checks); estimated for text.
    channels : int
        Channels that would be read.
    time : bool
        Whether a time column would be read too.
    exact : bool
        False when ``rows`` is estimated (text files: size / bytes per line of the first lines).
    format : str
    """

    rows: int
    channels: int
    time: bool
    exact: bool
    format: str


# ------------------------------------------------------------------- the common part


def _non_finite(layout: Layout, names: dict[str, str], display: str, gaps: str) -> int:
    """:func:`sigmatau.io._read._non_finite` counted chunk by chunk: the NaN kept as gaps."""
    kept = 0
    for orig, read in layout.readers.items():
        if layout.counts is not None:
            n_nan, first_nan, n_inf, first_inf = layout.counts[orig]
        else:
            n_nan = n_inf = 0
            first_nan = first_inf = -1
            for a in range(0, layout.rows, CHUNK_ROWS):
                v = np.asarray(read(a, min(layout.rows, a + CHUNK_ROWS)), dtype=np.float64)
                bad = ~np.isfinite(v)
                if not bad.any():
                    continue
                nan = np.isnan(v)
                inf = bad & ~nan
                if nan.any():
                    first_nan = first_nan if first_nan >= 0 else a + int(np.flatnonzero(nan)[0])
                    n_nan += int(nan.sum())
                if inf.any():
                    first_inf = first_inf if first_inf >= 0 else a + int(np.flatnonzero(inf)[0])
                    n_inf += int(inf.sum())
        kept += non_finite_column(display, orig, names[orig], gaps, layout.rows, n_nan, first_nan, n_inf, first_inf)
    return kept


def _finish(layout: Layout, opts: Options, display: str, path: Path,
            messages: list[tuple[str, type[Warning]]]) -> DiskLog:
    """The steps of :func:`sigmatau.io._read._finish` on readers: names, NaN, units, timing, checks."""
    table = layout.table
    if not table.data or layout.rows == 0:
        raise DataError(f"{display}: no numeric data")
    names, groups_of = _names_groups(table)
    kept_nan = 0 if opts.allow_nan else _non_finite(layout, names, display, opts.gaps)
    by_name = {names[o]: r for o, r in layout.readers.items()}
    groups = _grouped(table.data, names, groups_of)
    units, origin = _channel_units(table, opts, display, names, groups_of, groups, by_name, messages)  # type: ignore[arg-type]
    row_map: Optional[RowMap] = None
    time_origin = None
    if layout.time is None:
        report = untimed_report(table, opts, display)
    else:
        assert table.time_name is not None
        n = layout.rows
        order = scan_times(layout.time, n, name=table.time_name, path=display)
        if opts.time_unit is not None:
            unit, reason = opts.time_unit, "given"
        elif table.time_unit is not None:
            unit, reason = table.time_unit, table.time_unit_reason or "stated by the format"
        else:
            # the in-memory inference reads the first and last values and the first 100,001 steps
            head = layout.time(0, min(n, 100_001))
            probe = head if n <= 100_001 else np.concatenate((head, layout.time(n - 1, n)))
            unit, reason = infer_time_unit(probe, name=table.time_name, stated=None, path=display)
        timing_messages: list[str] = []
        rate = opts.rate if opts.rate is not None else table.rate
        row_map, report, time_origin = process_streamed(
            layout.time, n, layout.readers, order=order, unit=unit, unit_reason=reason,
            time_name=table.time_name, rate=rate, rate_source="given" if opts.rate is not None else "file",
            rows=table.rows, path=display, gaps=opts.gaps, gap_threshold=opts.gap_threshold,
            unsorted=opts.unsorted, duplicates=opts.duplicates, warnings=timing_messages)
        messages.extend((m, TimingWarning) for m in timing_messages)
    if kept_nan:
        report = _with_action(report, f"kept {kept_nan} NaN value(s) of the data columns as missing samples"
                                      " (gaps every statistic skips)")
    if report.samples < MIN_SAMPLES:
        raise DataError(f"{display}: only {report.samples} sample(s); at least {MIN_SAMPLES} are needed")
    from ._columns import unused_message

    messages.extend((m, InputWarning) for m in list(table.warnings))
    if table.unused:
        messages.append((unused_message(display, table.unused), InputWarning))
    if not table.sha256:
        table.sha256, table.size = file_sha256(path)
    source = Source(path=display, format=table.format, sha256=table.sha256, size=table.size,
                    detail=table.detail + "; read in chunks (out of core)", columns=table.columns,
                    topic=table.topic, unused_columns=tuple(f"{name} ({why})" for name, why in table.unused))
    state = _State(closers=list(layout.closers))
    channels = {}
    for orig, read in layout.readers.items():
        rows = as_dtype(read, np.float64)
        full = rows if row_map is None else (lambda a, b, r=rows, m=row_map: m.read(r, a, b))
        channels[names[orig]] = DiskChannel(names[orig], report.samples, full, state)
    return DiskLog(channels=channels, rate=report.rate, groups=groups, units=units,
                   data_type=opts.data_type or table.data_type or "freq", source=source, timing=report,
                   unit_origin=origin, original_names={names[o]: o for o in table.data}, time_origin=time_origin,
                   workdir=layout.workdir, _state=state)


def _with_action(report: TimingReport, text: str) -> TimingReport:
    from dataclasses import replace

    return replace(report, actions=report.actions + (text,))


class _Scratch:
    """A private temporary directory (``mkdtemp``: mode 0700), removed by :meth:`remove`."""

    def __init__(self, path: str) -> None:
        self.path = path

    def __str__(self) -> str:
        return self.path

    def remove(self) -> None:
        shutil.rmtree(self.path, ignore_errors=True)


def scratch_dir(workdir: Optional[PathLike], need: int, display: str) -> _Scratch:
    """A private temporary directory with ``need`` bytes free: in ``workdir`` (next to the outputs)
    if it has room, else in the system's temporary directory (``TMPDIR``); else a one-line error."""
    import tempfile

    places = [os.fspath(workdir)] if workdir is not None else []
    places.append(tempfile.gettempdir())
    seen = []
    margin = 64 << 20
    for place in dict.fromkeys(os.path.abspath(p) for p in places):
        try:
            free = shutil.disk_usage(place).free
        except OSError:
            continue
        seen.append(f"{place}: {_fmt(free)} free")
        if free >= need + margin:
            return _Scratch(tempfile.mkdtemp(prefix=".sigmatau-outofcore-", dir=place))
    raise DataError(f"{display}: out of core the text is converted to about {_fmt(need)} of temporary float64"
                    f" files, and no place has room ({'; '.join(seen) or 'none writable'}); free some space or"
                    " point TMPDIR at a larger disk")


def _fmt(n: float) -> str:
    from ._limits import fmt_bytes

    return fmt_bytes(n)


def _text_layout(p: Path, display: str, opts: Options, flavour: Optional[str], workdir: Optional[PathLike],
                 progress: Optional[bool]) -> Layout:
    """A text log converted into a private temporary directory (checked for room first)."""
    rows, k, timed = text_size(p, display, opts, flavour)
    scratch = scratch_dir(workdir, int(8 * rows * (k + timed) * 1.05) + (1 << 20), display)
    try:
        table, readers, time, n, counts = convert(p, display, opts, flavour, scratch.path, progress)
    except BaseException:
        scratch.remove()
        raise
    return Layout(table, readers, time, n, closers=[scratch.remove], counts=counts, workdir=scratch.path)


def _format_of(p: Path, display: str, opts: Options) -> tuple[str, Optional[str]]:
    """The reader name and, for text, the flavour (None: detected, as ``read`` does)."""
    if is_once(p):
        raise DataError(f"{display}: a pipe or device is read once, in memory; save it to a file to analyse it"
                        " out of core")
    if opts.format is None:
        name, auto = detect(p, display)
    else:
        name, auto = opts.format, False
    check_format_options(name, opts, display)
    if name not in OUT_OF_CORE_FORMATS:
        raise DataError(f"{display}: {name} logs are not read out of core (only {', '.join(OUT_OF_CORE_FORMATS)});"
                        f" read it in memory with {option_hint('--memory in', repr_kw('memory', 'in'))}")
    flavour = None if (name == "csv" and auto) else name
    return name, flavour


def log_size(path: PathLike, **options: Any) -> Optional[LogSize]:
    """Rows and channels of a log from its headers, without reading its samples.

    Parameters
    ----------
    path : str or path-like
    **options
        The options of :func:`sigmatau.io.read` (column choice, format, dataset …).

    Returns
    -------
    LogSize or None
        None for the formats :func:`open_log` does not read (ROS bags, Parquet) and for pipes.
    """
    opts = _options(**_all_options(options))
    p, display = _resolve(path)
    try:
        name, flavour = _format_of(p, display, opts)
    except DataError:
        return None
    if name in ("csv", "stable32"):
        rows, k, timed = text_size(p, display, opts, flavour)
        return LogSize(rows, k, timed, False, name)
    layout = {"npy": npy_layout, "npz": npz_layout, "hdf5": hdf5_layout}[name](p, display, opts)
    for close in layout.closers:
        close()
    return LogSize(layout.rows, len(layout.readers), layout.time is not None, True, name)


def _all_options(options: Mapping[str, Any]) -> dict[str, Any]:
    import inspect

    from ._read import read

    sig = inspect.signature(read)
    unknown = sorted(set(options) - set(sig.parameters) - {"path"})
    if unknown:
        raise ParameterError(f"unknown read option(s) {', '.join(map(repr, unknown))}")
    full = {k: v.default for k, v in sig.parameters.items() if k != "path"}
    full.update(options)
    return full


def open_log(path: PathLike, *, workdir: Optional[PathLike] = None, **options: Any) -> DiskLog:
    """Open a log larger than memory: a :class:`DiskLog` whose channels are read in pieces.

    Parameters
    ----------
    path : str or path-like
        An ``.npy``, an ``.npz`` of stored (uncompressed) arrays, an HDF5 file, or a text log
        (CSV, TSV, whitespace, Stable32; plain or compressed). Only read, never changed.
    workdir : str or path-like, optional
        Where the private temporary directory of a text log goes (tried first; the system's
        temporary directory otherwise), checked for free space first.
    **options
        The options of :func:`sigmatau.io.read`, with the same meaning and checks.

    Returns
    -------
    DiskLog
        Close it (or use ``with``): that removes the temporary files, also after an error.

    Raises
    ------
    DataError
        What :func:`~sigmatau.io.read` refuses, and one line for what is not done out of core: a
        compressed ``.npz``, ROS bags and Parquet, a pipe, timestamps going backwards,
        ``gaps="split"``, no room for the temporary files.

    Examples
    --------
    >>> import tempfile, pathlib, numpy as np
    >>> from sigmatau import io
    >>> f = pathlib.Path(tempfile.mkdtemp()) / "gyro.npz"
    >>> np.savez(f, gyro_x=np.zeros(1000), gyro_y=np.ones(1000), rate=np.array(100.0))
    >>> with io.open_log(f) as log:
    ...     log.names, len(log), log.rate, log["gyro_y"].read(0, 3).tolist()
    (('gyro_x', 'gyro_y'), 1000, 100.0, [1.0, 1.0, 1.0])
    """
    import warnings

    progress = options.get("progress")
    opts = _options(**_all_options(options))
    p, display = _resolve(path)
    name, flavour = _format_of(p, display, opts)
    layout: Optional[Layout] = None
    try:
        if name in ("csv", "stable32"):
            layout = _text_layout(p, display, opts, flavour, workdir, progress)
        else:
            layout = {"npy": npy_layout, "npz": npz_layout, "hdf5": hdf5_layout}[name](p, display, opts)
        messages: list[tuple[str, type[Warning]]] = []
        log = _finish(layout, opts, display, p, messages)
    except BaseException:
        for close in reversed(layout.closers if layout is not None else []):
            close()
        raise
    for text, category in messages:
        warnings.warn(text, category, stacklevel=2)
    return log
