"""``read`` and ``list_topics``: validation, dispatch to a reader, then the shared steps."""

from __future__ import annotations

import inspect

import os
import warnings as _warnings
from dataclasses import replace
from pathlib import Path
from typing import Any, Literal, Mapping, Sequence, Union

import numpy as np

from ..core.validate import DataType, check_data_type, check_rate
from ..errors import DataError, ParameterError, SigmaTauError
from . import _hdf5, _numpy, _parquet, _ros, _text  # noqa: F401  (they register their readers)
from ._columns import list_names, recognise, unused_message
from ._errors import FormatError, InputNotFoundError, InputWarning, TimingWarning, option_hint, repr_kw
from ._model import SensorLog, Source, TopicInfo
from ._progress import Progress
from ._registry import Options, Table, detect, get
from ._stream import OnceInput, is_once
from ._timing import AUTO_MARK_SHARE, check_times, infer_time_unit, process, untimed
from ._units import DEFAULT_UNITS, GROUP_UNITS, TIME_UNITS, canonical_unit, declared_unit, time_unit_name

__all__ = ["read", "list_topics", "detect_format", "MIN_SAMPLES"]

#: Fewest samples a log may have (an Allan variance at τ0 needs 3 phase points).
MIN_SAMPLES = 3

PathLike = Union[str, "os.PathLike[str]"]
ColumnSpec = Union[str, int, Sequence[Union[str, int]], None]

_GAPS = ("auto", "mark", "refuse", "split", "ignore")
_UNSORTED = ("sort", "refuse")
_DUPLICATES = ("drop", "refuse")
_STAMPS = ("header", "bag")
_FORMAT_OPTIONS = {
    "topic": ("rosbag1", "rosbag2"),
    "stamps": ("rosbag1", "rosbag2"),
    "dataset": ("hdf5",),
    "delimiter": ("csv", "stable32"),
}


def _choice(name: str, value: object, allowed: tuple) -> None:
    if value not in allowed:
        raise ParameterError(f"{name}={value!r} must be one of {allowed}")


def _resolve(path: object) -> tuple[Path, str]:
    if not isinstance(path, (str, os.PathLike)):
        raise ParameterError(f"path={path!r} must be a file name (str or path-like)")
    display = os.fspath(path)
    if not display:
        raise ParameterError("path='' names no file")
    p = Path(display)
    if not p.exists():
        raise InputNotFoundError(f"{display}: no such file or directory")
    if p.is_file() and p.stat().st_size == 0:
        raise DataError(f"{display}: the file is empty")
    return p, display


def check_read_options(**options: object) -> None:
    """Check keyword options of :func:`read` without reading anything.

    Raises
    ------
    ParameterError
        One line naming an unknown option or a bad value, as :func:`read` would.
    """
    sig = inspect.signature(read)
    try:
        bound = sig.bind("<path>", **options)
    except TypeError:
        unknown = sorted(set(options) - set(sig.parameters))
        raise ParameterError(f"unknown read option(s) {', '.join(map(repr, unknown))}; sigmatau.io.read takes"
                             f" {', '.join(k for k in sig.parameters if k not in ('path', 'progress'))}") from None
    bound.apply_defaults()
    full = dict(bound.arguments)
    full.pop("path")
    _options(**full)


def _options(**kw: object) -> Options:
    if kw["format"] is not None:
        get(kw["format"])
    _choice("gaps", kw["gaps"], _GAPS)
    _choice("unsorted", kw["unsorted"], _UNSORTED)
    _choice("duplicates", kw["duplicates"], _DUPLICATES)
    if kw["stamps"] is not None:
        _choice("stamps", kw["stamps"], _STAMPS)
    if kw["rate"] is not None:
        kw["rate"] = check_rate(kw["rate"])
    if kw["time_unit"] is not None:
        unit = time_unit_name(kw["time_unit"]) if isinstance(kw["time_unit"], str) else None
        if unit is None:
            raise ParameterError(f"time_unit={kw['time_unit']!r} must be one of {tuple(TIME_UNITS)}")
        kw["time_unit"] = unit
    if kw["data_type"] is not None:
        check_data_type(kw["data_type"])
    units = kw["units"]
    if units is not None and (not isinstance(units, Mapping) or not all(isinstance(k, str) for k in units)):
        raise ParameterError(f"units={units!r} must map group or channel names to unit strings")
    threshold = kw["gap_threshold"]
    if isinstance(threshold, bool) or not isinstance(threshold, (int, float)) or not threshold > 1:
        raise ParameterError(f"gap_threshold={threshold!r} must be a number > 1 (in median steps)")
    kw["gap_threshold"] = float(threshold)
    if kw["time_column"] is True:
        raise ParameterError("time_column=True is not a column; pass a name, an index, None (detect) or False")
    for flag in ("allow_nan",):
        if not isinstance(kw[flag], bool):
            raise ParameterError(f"{flag}={kw[flag]!r} must be True or False")
    if kw["progress"] is not None and not isinstance(kw["progress"], bool):
        raise ParameterError(f"progress={kw['progress']!r} must be True, False or None (when a terminal)")
    kw.pop("progress")
    return Options(**kw)  # type: ignore[arg-type]


def detect_format(path: PathLike) -> str:
    """The format :func:`read` would use for ``path`` ("csv" covers Stable32-style text too).

    A pipe is consumed by this: its first bytes are read to decide.
    """
    p, display = _resolve(path)
    once = _open_once(p, display)
    try:
        return detect(p, display, head=None if once is None else once.head)[0]
    finally:
        if once is not None:
            once.close()


def read(
    path: PathLike,
    *,
    format: str | None = None,
    columns: ColumnSpec = None,
    time_column: str | int | Literal[False] | None = None,
    time_unit: str | None = None,
    rate: float | None = None,
    data_type: DataType | None = None,
    units: Mapping[str, str] | None = None,
    topic: str | None = None,
    dataset: str | None = None,
    stamps: Literal["header", "bag"] | None = None,
    gaps: Literal["auto", "mark", "refuse", "split", "ignore"] = "auto",
    gap_threshold: float = 1.5,
    unsorted: Literal["sort", "refuse"] = "sort",
    duplicates: Literal["drop", "refuse"] = "drop",
    allow_nan: bool = False,
    delimiter: str | None = None,
    progress: bool | None = None,
) -> SensorLog:
    """Read a sensor log into a :class:`SensorLog`.

    Parameters
    ----------
    path : str or path-like
        A file, or a ROS 2 bag directory. The file is only read, never changed.
        A pipe, FIFO or ``/dev/stdin`` is read once, from its first byte (text
        formats only; a binary format from a pipe is refused).
    format : str, optional
        Reader name (see :func:`formats`); detected from the content and the
        extension when None. Text files whose only numeric column is one value
        per line (or MJD and value) are read as Stable32 data files.
    columns : str, int or sequence of them, optional
        Channels by column name or 0-based index (ROS bags: ``gyro_x`` …
        ``accel_z``). Names match exactly, then ignoring case and a unit in
        brackets, then by canonical channel name. None: every numeric column
        but the time column — only the recognised IMU channels when there are any
        (exact names and patterns such as ``gyro_x``, ``gx``, ``acc.z``,
        ``w_RS_S_x [rad s^-1]``; ``a/../../x`` is not one). Every column left out
        is named in an :class:`InputWarning` and in ``Source.unused_columns``. At
        most :data:`MAX_CHANNELS` (256) channels are read.
    time_column : str, int or False, optional
        The timestamp column. None looks for one by name (t, time, timestamp,
        ``#timestamp [ns]``, ``field.header.stamp``, mjd …); False: none.
    time_unit : {"s", "ms", "us", "ns", "min", "h", "d"}, optional
        Unit of the time column. When None it is taken from the column name
        (``[ns]``, ``_ms`` …), then from the magnitude (Unix time between 1990
        and 2100 in exactly one unit), then from the median step (exactly one
        unit giving 1 µHz–40 kHz); the read is refused when that is ambiguous.
    rate : float, optional
        Sample rate in Hz. Needed when there are no timestamps; with timestamps
        it overrides the measured rate (a TimingWarning says when they disagree
        by more than 1 %).
    data_type : {"freq", "phase"}, optional
        Default "freq" (sensor output); Stable32 files: from "phase"/"frequency"
        in their header or name, else this is required.
    units : mapping, optional
        Units by group ("gyro", "accel", …) or channel, such as
        ``{"gyro": "deg/s", "accel": "g"}``. Gyro and accel units are checked
        (rad/s, mrad/s, deg/s, mdeg/s, deg/h; m/s^2, mm/s^2, g, mg, ug), recorded
        in these ASCII spellings (``°/s``, ``dps``, ``m/s²``, ``µg`` … are accepted).
        Without a declaration, the file's (EuRoC header, ROS message) or the
        default: gyro rad/s, accel m/s^2 (``unit_origin`` says which). A gyro
        or accel unit the file states but that is not one of these (``[rpm]``,
        ``[LSB]``, ``[counts]``) is refused unless a unit is declared here.
    topic : str, optional
        ROS bags: the ``sensor_msgs/msg/Imu`` topic; needed when there are several.
    dataset : str, optional
        HDF5: path of the dataset or group to read.
    stamps : {"header", "bag"}, optional
        ROS bags: message ``header.stamp`` (default) or the bag's receive time.
    gaps : {"auto", "mark", "refuse", "split", "ignore"}
        Steps longer than ``gap_threshold`` median steps. "mark": place the samples
        on the nominal grid, each missing one a NaN, which every statistic treats as
        a gap (Stable32's Regularize); "auto" (default): mark when at most 10 % of the
        samples are missing, a gap of at most 5 samples holding the sample before it,
        else refuse (NaN cells of a data column follow the same share rule);
        "refuse": an error naming where; "split":
        keep the samples and let :meth:`SensorLog.segments` split; "ignore": analyse
        as if the samples were contiguous.
    gap_threshold : float
        In median steps, > 1 (default 1.5: one missing sample is a gap).
    unsorted : {"sort", "refuse"}
        Timestamps going backwards: sort the samples (with a TimingWarning) or refuse.
    duplicates : {"drop", "refuse"}
        Repeated timestamps: keep the first sample of each (with a TimingWarning) or refuse.
    allow_nan : bool
        Keep NaN/inf samples (refused by default).
    delimiter : str, optional
        Text files: the field delimiter (detected when None).
    progress : bool, optional
        Progress bar on stderr: None (default) when stderr is a terminal.

    Returns
    -------
    SensorLog

    Raises
    ------
    InputNotFoundError
        The path does not exist.
    FormatError
        The file is not readable as its format (unrecognised, corrupt, truncated).
    DataError
        No numeric data, too few samples, NaN, timing refused by a policy, a
        gyro or accel unit that is not known, a line longer than
        :data:`MAX_LINE_CHARS`, more than :data:`MAX_CHANNELS` channels, or
        declared sizes beyond the memory available (checked before allocating).
    ParameterError
        A bad argument, or a column, topic or dataset that does not exist (the
        message lists the ones that do).
    MissingDependencyError
        The format needs an optional package (the message names the extra).
    """
    opts = _options(
        format=format, columns=columns, time_column=time_column, time_unit=time_unit, rate=rate,
        data_type=data_type, units=units, topic=topic, dataset=dataset, stamps=stamps, gaps=gaps,
        gap_threshold=gap_threshold,
        unsorted=unsorted, duplicates=duplicates, allow_nan=allow_nan, delimiter=delimiter,
        progress=progress,
    )
    p, display = _resolve(path)
    once = _open_once(p, display)
    try:
        table = _read_table(p, display, opts, format, progress, once)
    finally:
        if once is not None:
            once.close()
    messages: list[tuple[str, type[Warning]]] = []
    log = _finish(table, opts, display, messages)
    for text, category in messages:
        _warnings.warn(text, category, stacklevel=2)
    return log


def _open_once(p: Path, display: str) -> OnceInput | None:
    """A pipe, FIFO or device opened once (its head kept for detection); None for a file or directory."""
    if not is_once(p):
        return None
    try:
        once = OnceInput(p)
    except OSError as exc:
        raise FormatError(f"{display}: cannot read: {exc.strerror or exc}") from None
    if not once.head:
        once.close()
        raise DataError(f"{display}: the input is empty")
    return once


def check_format_options(name: str, opts: Options, display: str) -> None:
    """Refuse an option that does not apply to the format ``name`` (``dataset`` to a CSV …)."""
    for option, readers in _FORMAT_OPTIONS.items():
        if getattr(opts, option) is not None and name not in readers:
            flag = f"--{option.replace('_', '-')}"
            raise ParameterError(
                f"{option}= ({flag}) applies to {' and '.join(readers)} files only;"
                f" {display} is read as {name}"
            )
    if name in ("rosbag1", "rosbag2") and opts.time_column is not None:
        raise ParameterError(
            f"{display}: time_column= does not apply to ROS bags (nor --time-column);"
            f" use {option_hint('--stamps header|bag', 'stamps=')}"
        )


def _read_table(p: Path, display: str, opts: Options, format: str | None, progress: bool | None,
                once: OnceInput | None) -> Table:
    if format is None:
        name, auto = detect(p, display, head=None if once is None else once.head)
    else:
        name, auto = format, False
    spec = get(name)
    check_format_options(name, opts, display)
    text_reader = name in ("csv", "stable32")
    if once is not None and not text_reader:
        raise FormatError(
            f"{display}: is a pipe or device, and {name} input is read from a regular file only;"
            " save it to a file first"
        )
    try:
        with Progress(None, f"sigmatau: reading {p.name}", enabled=progress) as bar:
            if text_reader:
                return spec.func(p, display, opts, bar, auto=auto and name == "csv",
                                 stream=None if once is None else once.stream())
            return spec.func(p, display, opts, bar)
    except (SigmaTauError, KeyboardInterrupt):
        raise
    except MemoryError:
        raise DataError(f"{display}: not enough memory to read it") from None
    except OSError as exc:
        raise FormatError(f"{display}: cannot read: {exc.strerror or exc}") from None


def _names_groups(table: Table) -> tuple[dict[str, str], dict[str, str]]:
    """Channel name and group of each chosen column (canonical IMU names unless they collide)."""
    proposed: dict[str, tuple[str, str]] = {}
    for orig in table.data:
        if orig in table.rename:
            proposed[orig] = (table.rename[orig], table.groups.get(orig, "other"))
        else:
            rec = recognise(orig)
            proposed[orig] = (rec.name or orig, table.groups.get(orig) or rec.group or "other")
    counts: dict[str, int] = {}
    for name, _ in proposed.values():
        counts[name] = counts.get(name, 0) + 1
    names = {o: (n if counts[n] == 1 else o) for o, (n, _) in proposed.items()}
    groups = {o: g for o, (_, g) in proposed.items()}
    return names, groups


def _file_unit(text: str, group: str) -> str:
    """A unit as the file states it, in sigmatau's spelling when it is a known gyro or accel unit."""
    if group in GROUP_UNITS:
        return canonical_unit(text) or text.strip()
    return text.strip()


_EXAMPLE_UNIT = {"gyro": "deg/s", "accel": "g"}


def _printable(text: str) -> str:
    """A unit from the file as shown in a message: as is when plain, else quoted and cut
    (a control character from a file must not reach the terminal)."""
    return text if text.isprintable() and len(text) <= 40 else repr(text[:40])


def _check_units(units: Mapping[str, str], origin: Mapping[str, str], groups: Mapping[str, tuple[str, ...]],
                 original: Mapping[str, str], display: str) -> None:
    """Refuse a gyro or accel unit from the file that sigmatau does not know.

    Taking it for the SI default would scale every result by an unknown factor
    (``[rpm]``, ``[LSB]``, ``[counts]``); a unit the caller declared overrides it.
    """
    for group, known in GROUP_UNITS.items():
        for name in groups.get(group, ()):
            unit = units.get(name)
            if unit is None or unit in known or origin.get(name) == "declared":
                continue
            example = _EXAMPLE_UNIT[group]
            column = original.get(name, name)
            raise DataError(
                f"{display}: column {column!r} is in {unit!r}, not a {group} unit sigmatau knows"
                f" ({', '.join(known)}); convert the samples or declare their unit with"
                f" {option_hint(f'--{group}-unit {example}', f'units={{{group!r}: {example!r}}}')}"
            )


def _finish(table: Table, opts: Options, display: str, messages: list[tuple[str, type[Warning]]]) -> SensorLog:
    data = table.data
    if not data or table.rows == 0:
        raise DataError(f"{display}: no numeric data")
    names, groups_of = _names_groups(table)
    kept_nan = 0 if opts.allow_nan else _non_finite(data, names, display, opts.gaps)
    channels = {names[o]: v for o, v in data.items()}
    groups = _grouped(data, names, groups_of)
    units, origin = _channel_units(table, opts, display, names, groups_of, groups, channels, messages)
    channels, timestamps, report, time_origin = _timing(table, opts, display, channels, messages)
    if kept_nan:
        report = replace(report, actions=report.actions + (
            f"kept {kept_nan} NaN value(s) of the data columns as missing samples (gaps every statistic skips)",))
    n = report.samples
    if n < MIN_SAMPLES:
        raise DataError(f"{display}: only {n} sample(s); at least {MIN_SAMPLES} are needed")
    warn_texts: list[str] = list(table.warnings)
    if table.unused:
        warn_texts.append(unused_message(display, table.unused))
    messages.extend((m, InputWarning) for m in warn_texts)
    source = Source(
        path=display, format=table.format, sha256=table.sha256, size=table.size, detail=table.detail,
        columns=table.columns, topic=table.topic,
        unused_columns=tuple(f"{name} ({why})" for name, why in table.unused),
    )
    return SensorLog(
        channels=channels,
        rate=report.rate,
        timestamps=timestamps,
        groups=groups,
        units=units,
        data_type=opts.data_type or table.data_type or "freq",  # type: ignore[arg-type]
        source=source,
        timing=report,
        unit_origin=origin,
        original_names={names[o]: o for o in data},
        time_origin=time_origin,
    )


def _non_finite(data: dict[str, np.ndarray], names: dict[str, str], display: str, gaps: str) -> int:
    """NaN cells are missing samples under ``gaps`` "mark" (any share) and "auto" (at most
    AUTO_MARK_SHARE of a column); anything else non-finite, and NaN under the other policies, is one
    line naming the first column and where. Returns the NaN cells kept."""
    kept = 0
    for orig, v in data.items():
        bad = ~np.isfinite(v)
        if not bad.any():
            continue
        nan = np.isnan(v)
        inf = bad & ~nan
        first_inf = int(np.flatnonzero(inf)[0]) if inf.any() else -1
        kept += non_finite_column(display, orig, names[orig], gaps, v.size, int(nan.sum()),
                                  int(np.flatnonzero(nan)[0]) if nan.any() else -1, int(inf.sum()), first_inf)
    return kept


def non_finite_column(display: str, orig: str, name: str, gaps: str, rows: int, n_nan: int, first_nan: int,
                      n_inf: int, first_inf: int) -> int:
    """The rule of :func:`_non_finite` for one column from its counts: the NaN kept as gaps, or the
    one-line error (also used by the out-of-core reader, which counts them chunk by chunk)."""
    called = repr(orig) if name == orig else f"{orig!r} ({name})"
    if n_inf:
        raise DataError(f"{display}: column {called} holds {n_inf} infinite value(s) (first at sample"
                        f" {first_inf}); remove them from the file")
    if not n_nan:
        return 0
    share = n_nan / rows
    if gaps == "mark" or (gaps == "auto" and share <= AUTO_MARK_SHARE):
        return n_nan
    why = (f"{100 * share:.3g} % of the column, more than the {100 * AUTO_MARK_SHARE:g} % kept as gaps by default"
           if gaps == "auto" else f"gaps={gaps!r}")
    raise DataError(
        f"{display}: column {called} holds {n_nan} NaN value(s) (first at sample {first_nan}; {why});"
        f" to keep them as missing samples use {option_hint('--gaps mark', repr_kw('gaps', 'mark'))}"
    )


def _grouped(data: dict[str, np.ndarray], names: dict[str, str],
             groups_of: dict[str, str]) -> dict[str, tuple[str, ...]]:
    """Channel names by group, gyro and accel first."""
    group_members: dict[str, list[str]] = {}
    for o in data:
        group_members.setdefault(groups_of[o], []).append(names[o])
    order = ["gyro", "accel", "temperature", "phase", "freq"]
    return {g: tuple(group_members[g]) for g in sorted(group_members, key=lambda g: (
        order.index(g) if g in order else len(order), g))}


def _channel_units(table: Table, opts: Options, display: str, names: dict[str, str], groups_of: dict[str, str],
                   groups: dict[str, tuple[str, ...]], channels: dict[str, np.ndarray],
                   messages: list[tuple[str, type[Warning]]]) -> tuple[dict[str, str], dict[str, str]]:
    """Each channel's unit and where it came from: the file, then ``units=``, then the group default."""
    data = table.data
    units: dict[str, str] = {}
    origin: dict[str, str] = {}
    for o in data:
        if o in table.units and table.units[o]:
            units[names[o]] = _file_unit(table.units[o], groups_of[o])
            origin[names[o]] = table.unit_origin
    if opts.units:
        _declared_units(opts.units, display, names, groups_of, groups, channels, units, origin, messages)
    _check_units(units, origin, groups, {names[o]: o for o in data}, display)
    for group, unit in DEFAULT_UNITS.items():
        for name in groups.get(group, ()):
            if name not in units:
                units[name] = unit
                origin[name] = "default"
    for name in channels:
        units.setdefault(name, "")
        origin.setdefault(name, "")
    return units, origin


def _declared_units(declared: Mapping[str, str], display: str, names: dict[str, str], groups_of: dict[str, str],
                    groups: dict[str, tuple[str, ...]], channels: dict[str, np.ndarray], units: dict[str, str],
                    origin: dict[str, str], messages: list[tuple[str, type[Warning]]]) -> None:
    """``units=`` applied by group, channel or original column name (a warning where the file said otherwise)."""
    by_original = {o: names[o] for o in names}
    for key, text in declared.items():
        if key in groups:
            targets = [(n, key) for n in groups[key]]
        elif key in channels:
            targets = [(key, next(g for o, g in groups_of.items() if names[o] == key))]
        elif key in by_original:
            targets = [(by_original[key], groups_of[key])]
        else:
            raise ParameterError(
                f"units key {key!r} is neither a group ({', '.join(groups)}) nor a channel"
                f" ({', '.join(channels)}) of {display}"
            )
        for name, group in targets:
            unit = declared_unit(group, text, key=key)
            if name in units and units[name] != unit and origin.get(name) in ("file", "format"):
                messages.append((
                    f"{display}: channel {name!r} is in {_printable(units[name])} according to the"
                    f" {origin[name]};"
                    f" using the declared {unit}", InputWarning))
            units[name] = unit
            origin[name] = "declared"


def untimed_report(table: Table, opts: Options, display: str) -> Any:
    """The timing report of a table without a time column: the rate given or the file's (else the
    one-line error asking for one)."""
    rate = opts.rate if opts.rate is not None else table.rate
    rate_source = "given" if opts.rate is not None else "file"
    if opts.time_unit is not None:
        raise ParameterError(f"{display}: time_unit={opts.time_unit!r} (--time-unit) given but the file has"
                             " no time column")
    if rate is None:
        raise ParameterError(
            f"{display}: no time column and no rate; give the rate in Hz with"
            f" {option_hint('--rate HZ', 'rate=')} or the time column with"
            f" {option_hint('--time-column NAME', 'time_column=')}"
            f" (columns: {list_names(list(table.columns))})"
        )
    return untimed(table.rows, rate=rate, rate_source=rate_source, rows=table.rows,
                   gaps=opts.gaps, gap_threshold=opts.gap_threshold)


def _timing(table: Table, opts: Options, display: str, channels: dict[str, np.ndarray],
            messages: list[tuple[str, type[Warning]]]) -> tuple[dict[str, np.ndarray], Any, Any, Any]:
    """Channels, timestamps, timing report and time origin: from the time column, or the rate alone."""
    rate = opts.rate if opts.rate is not None else table.rate
    rate_source = "given" if opts.rate is not None else "file"
    if table.time is None:
        return channels, None, untimed_report(table, opts, display), None
    assert table.time_name is not None
    check_times(table.time, name=table.time_name, path=display)
    if opts.time_unit is not None:
        unit, reason = opts.time_unit, "given"
    elif table.time_unit is not None:
        unit, reason = table.time_unit, table.time_unit_reason or "stated by the format"
    else:
        unit, reason = infer_time_unit(table.time, name=table.time_name, stated=None, path=display)
    timing_messages: list[str] = []
    timestamps, channels, report, time_origin = process(
        table.time, channels, unit=unit, unit_reason=reason, time_name=table.time_name,
        rate=rate, rate_source=rate_source, rows=table.rows, path=display, gaps=opts.gaps,
        gap_threshold=opts.gap_threshold, unsorted=opts.unsorted, duplicates=opts.duplicates,
        warnings=timing_messages,
    )
    messages.extend((m, TimingWarning) for m in timing_messages)
    return channels, timestamps, report, time_origin


def list_topics(path: PathLike) -> list[TopicInfo]:
    """Topics of a ROS 1 bag or ROS 2 bag (directory, ``.db3`` or ``.mcap``): name, type, count."""
    p, display = _resolve(path)
    name, _ = detect(p, display)
    if name not in ("rosbag1", "rosbag2"):
        raise ParameterError(f"{display}: not a ROS bag (read as {name}); list_topics reads ROS bags only")
    return _ros.topics(p, display)
