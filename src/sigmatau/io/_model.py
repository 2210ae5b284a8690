"""The in-memory representation of a sensor log and its timing report."""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any, Mapping, Sequence

import numpy as np

from .._input import DataType
from ..errors import ParameterError
from ._units import SI_UNITS, si_factor

__all__ = ["Gap", "TimingReport", "Source", "TopicInfo", "SensorLog"]


def _fmt_rate(rate: float | None) -> str:
    return "—" if rate is None else f"{rate:.6g} Hz"


def _fmt_seconds(s: float | None) -> str:
    if s is None:
        return "—"
    a = abs(s)
    if a == 0:
        return "0 s"
    if a < 1e-9:
        return f"{s:.3g} s"
    if a < 1e-6:
        return f"{s * 1e9:.3g} ns"
    if a < 1e-3:
        return f"{s * 1e6:.3g} µs"
    if a < 1:
        return f"{s * 1e3:.3g} ms"
    return f"{s:.6g} s"


@dataclass(frozen=True)
class Gap:
    """A step between two timestamps longer than ``gap_threshold`` nominal periods.

    Attributes
    ----------
    index : int
        Index of the first sample after the gap (the log's samples ``index - 1`` and
        ``index`` straddle it).
    time : float
        Time of the last sample before the gap, in s from the first sample.
    duration : float
        The step across the gap, in s.
    missing : int
        Samples missing at the nominal rate (``round(duration·rate) - 1``).
    """

    index: int
    time: float
    duration: float
    missing: int


@dataclass(frozen=True)
class TimingReport:
    """What the timestamps said and what was done about them.

    Attributes
    ----------
    samples : int
        Samples in the log (after sorting and dropping duplicates).
    rows : int
        Rows (or messages) read from the file.
    rate : float
        The sample rate used (Hz): the one given, the file's, or 1/median step.
    rate_source : str
        "given", "file" or "timestamps".
    measured_rate : float or None
        1 / median step between timestamps (None without timestamps).
    mean_rate : float or None
        (samples - 1) / span: below ``measured_rate`` when samples are missing.
    span : float
        Last minus first timestamp in s ((samples - 1)/rate without timestamps).
    jitter_rms, jitter_max : float or None
        Standard deviation and largest deviation from the median of the steps that
        are not gaps, in s.
    out_of_order : int
        Timestamps earlier than the one before them, in file order.
    duplicates : int
        Samples whose timestamp equals the previous one (after sorting);
        ``duplicates_differing`` of them carry values different from the kept sample.
    gaps : tuple of Gap
    gap_threshold : float
        Steps longer than this many median steps are gaps.
    time_column, time_unit, time_unit_reason : str or None
        Where the timestamps came from, their unit and how it was decided.
    unsorted_policy, duplicates_policy, gaps_policy : str
        The policies in force (see :func:`sigmatau.io.read`).
    actions : tuple of str
        What was done to the samples, in words.
    """

    samples: int
    rows: int
    rate: float
    rate_source: str
    measured_rate: float | None = None
    mean_rate: float | None = None
    span: float = 0.0
    jitter_rms: float | None = None
    jitter_max: float | None = None
    out_of_order: int = 0
    duplicates: int = 0
    duplicates_differing: int = 0
    gaps: tuple[Gap, ...] = ()
    gap_threshold: float = 1.5
    time_column: str | None = None
    time_unit: str | None = None
    time_unit_reason: str = ""
    unsorted_policy: str = "sort"
    duplicates_policy: str = "drop"
    gaps_policy: str = "refuse"
    actions: tuple[str, ...] = ()

    @property
    def has_timestamps(self) -> bool:
        return self.time_column is not None

    @property
    def missing(self) -> int:
        """Samples missing in all gaps together, at the nominal rate."""
        return sum(g.missing for g in self.gaps)

    def to_dict(self) -> dict[str, Any]:
        """Plain-Python dictionary (gaps as a list of dicts)."""
        out = {k: getattr(self, k) for k in self.__dataclass_fields__}
        out["gaps"] = [vars(g).copy() for g in self.gaps]
        out["actions"] = list(self.actions)
        return out

    def summary(self) -> str:
        """A few lines of text for a report."""
        lines = [f"samples: {self.samples} (rows read: {self.rows})",
                 f"rate: {_fmt_rate(self.rate)} ({self.rate_source})"]
        if self.has_timestamps:
            lines.append(
                f"timestamps: column {self.time_column!r} in {self.time_unit} ({self.time_unit_reason})"
            )
            lines.append(
                f"measured rate: {_fmt_rate(self.measured_rate)} (median step), mean {_fmt_rate(self.mean_rate)};"
                f" span {_fmt_seconds(self.span)}"
            )
            lines.append(f"jitter: rms {_fmt_seconds(self.jitter_rms)}, max {_fmt_seconds(self.jitter_max)}")
            lines.append(
                f"out of order: {self.out_of_order} (policy {self.unsorted_policy});"
                f" duplicated: {self.duplicates}, {self.duplicates_differing} with different values"
                f" (policy {self.duplicates_policy})"
            )
            gap_text = f"gaps (> {self.gap_threshold:g} steps): {len(self.gaps)}"
            if self.gaps:
                first = ", ".join(f"{_fmt_seconds(g.duration)} at {g.time:.6g} s" for g in self.gaps[:3])
                more = f", … {len(self.gaps) - 3} more" if len(self.gaps) > 3 else ""
                gap_text += f", {self.missing} samples missing: {first}{more}"
            lines.append(f"{gap_text} (policy {self.gaps_policy})")
        else:
            lines.append("timestamps: none (uniform sampling assumed)")
        lines.extend(f"action: {a}" for a in self.actions)
        return "\n".join(lines)


@dataclass(frozen=True)
class Source:
    """Where a log came from.

    Attributes
    ----------
    path : str
        The path as given.
    format : str
        Reader used ("csv", "stable32", "npy", "npz", "rosbag1", "rosbag2", "hdf5", "parquet").
    sha256 : str
        SHA-256 of the file (of a ROS 2 bag directory: of its files' names and hashes).
    size : int
        Bytes.
    detail : str
        How it was read (delimiter and header, topic and storage, dataset …).
    columns : tuple of str
        Every column (field, dataset member) the file offers.
    topic : str or None
        The ROS topic read.
    unused_columns : tuple of str
        Columns (fields, members) of the file that the automatic choice left out,
        each with the reason: ``"name (not numeric)"`` …; empty when columns were chosen.
    """

    path: str
    format: str
    sha256: str
    size: int
    detail: str = ""
    columns: tuple[str, ...] = ()
    topic: str | None = None
    unused_columns: tuple[str, ...] = ()


@dataclass(frozen=True)
class TopicInfo:
    """A topic of a ROS bag: name, message type and message count."""

    topic: str
    msgtype: str
    count: int


def _readonly(a: np.ndarray) -> np.ndarray:
    if a.flags.writeable:
        a = a.view()
        a.flags.writeable = False
    return a


@dataclass(frozen=True, eq=False, repr=False)
class SensorLog:
    """Sensor samples read from a file, with what is known about them.

    Attributes
    ----------
    channels : mapping of str to numpy.ndarray
        One read-only float64 array per channel, all of the same length, in file
        order of the columns. IMU channels get canonical names (``gyro_x`` …
        ``accel_z``, ``temperature``); other channels keep their column names
        (or ``col0``, ``col1`` … without a header; ``phase``/``freq`` for
        Stable32 files).
    rate : float
        Sample rate in Hz (see ``timing.rate_source``).
    timestamps : numpy.ndarray or None
        Time of each sample in s from the first sample (sorted, no duplicates), or
        None when the file has no time column.
    groups : mapping of str to tuple of str
        Channels per group: "gyro", "accel", "temperature", "phase", "freq", "other".
    units : mapping of str to str
        Unit of each channel ("" when unknown).
    unit_origin : mapping of str to str
        Where each unit came from: "file", "format", "declared", "default" or "".
    data_type : {"freq", "phase"}
        "freq" for sensor output (rate, specific force, fractional frequency);
        "phase" for integrated data (Stable32 phase files).
    source : Source
    timing : TimingReport
    original_names : mapping of str to str
        Column name in the file of each channel.
    time_origin : float or None
        First timestamp in the file's own time scale, converted to s (for example
        Unix time, or MJD·86400).
    """

    channels: Mapping[str, np.ndarray]
    rate: float
    timestamps: np.ndarray | None
    groups: Mapping[str, tuple[str, ...]]
    units: Mapping[str, str]
    data_type: DataType
    source: Source
    timing: TimingReport
    unit_origin: Mapping[str, str] = field(default_factory=dict)
    original_names: Mapping[str, str] = field(default_factory=dict)
    time_origin: float | None = None

    def __post_init__(self) -> None:
        chans = {k: _readonly(np.asarray(v, dtype=np.float64)) for k, v in self.channels.items()}
        object.__setattr__(self, "channels", chans)
        if self.timestamps is not None:
            object.__setattr__(self, "timestamps", _readonly(np.asarray(self.timestamps, dtype=np.float64)))

    # -- access -----------------------------------------------------------------
    @property
    def names(self) -> tuple[str, ...]:
        """Channel names, in order."""
        return tuple(self.channels)

    @property
    def n_samples(self) -> int:
        return len(self)

    def __len__(self) -> int:
        return next(iter(self.channels.values())).size if self.channels else 0

    def __getitem__(self, name: str) -> np.ndarray:
        try:
            return self.channels[name]
        except KeyError:
            raise ParameterError(
                f"no channel {name!r}; channels are: {', '.join(self.channels)}"
            ) from None

    def __contains__(self, name: object) -> bool:
        return name in self.channels

    def group_of(self, name: str) -> str:
        """The group a channel belongs to."""
        for group, names in self.groups.items():
            if name in names:
                return group
        return "other"

    def as_array(self, names: Sequence[str] | None = None) -> np.ndarray:
        """Samples as a new (n_samples, n_channels) float64 array."""
        names = list(self.channels) if names is None else list(names)
        return np.column_stack([self[n] for n in names]) if names else np.empty((len(self), 0))

    def __repr__(self) -> str:
        parts = []
        for group, names in self.groups.items():
            units = {self.units.get(n, "") for n in names}
            unit = units.pop() if len(units) == 1 else "mixed"
            parts.append(f"{group}[{unit or '?'}]: {', '.join(names)}")
        gaps = f", {len(self.timing.gaps)} gaps" if self.timing.gaps else ""
        return (
            f"SensorLog({self.source.format} {self.source.path!r}, {len(self.channels)} channels × "
            f"{len(self)} samples at {self.rate:.6g} Hz{gaps}; " + "; ".join(parts) + ")"
        )

    def to_dict(self) -> dict[str, Any]:
        """Everything but the sample arrays, as plain Python."""
        return {
            "source": vars(self.source).copy() | {"columns": list(self.source.columns),
                                                  "unused_columns": list(self.source.unused_columns)},
            "rate": self.rate,
            "data_type": self.data_type,
            "n_samples": len(self),
            "channels": list(self.channels),
            "groups": {k: list(v) for k, v in self.groups.items()},
            "units": dict(self.units),
            "unit_origin": dict(self.unit_origin),
            "original_names": dict(self.original_names),
            "time_origin": self.time_origin,
            "timing": self.timing.to_dict(),
        }

    # -- derived logs -----------------------------------------------------------
    def select(self, names: Sequence[str]) -> "SensorLog":
        """A log with only the named channels (in the order given)."""
        if isinstance(names, str):
            names = [names]
        chans = {n: self[n] for n in names}
        groups = {g: tuple(n for n in members if n in chans) for g, members in self.groups.items()}
        return replace(
            self,
            channels=chans,
            groups={g: m for g, m in groups.items() if m},
            units={n: self.units.get(n, "") for n in chans},
            unit_origin={n: self.unit_origin.get(n, "") for n in chans},
            original_names={n: self.original_names.get(n, n) for n in chans},
        )

    def segments(self, min_samples: int = 2) -> list["SensorLog"]:
        """The gap-free runs of samples, each as a log of its own.

        The log is split at every gap of ``timing.gaps`` (whatever the gap policy
        was); runs shorter than ``min_samples`` are left out. Without gaps the
        result is ``[self]``. Each segment's timestamps start at 0 and its
        ``time_origin`` is moved to its first sample; its timing report describes
        the segment.
        """
        if not self.timing.gaps or self.timestamps is None:
            return [self] if len(self) >= min_samples else []
        from ._timing import segment_report

        bounds = [0, *(g.index for g in self.timing.gaps), len(self)]
        out = []
        for lo, hi in zip(bounds[:-1], bounds[1:]):
            if hi - lo < min_samples:
                continue
            t = self.timestamps[lo:hi]
            out.append(
                replace(
                    self,
                    channels={k: v[lo:hi] for k, v in self.channels.items()},
                    timestamps=t - t[0],
                    timing=segment_report(self.timing, t, lo),
                    time_origin=None if self.time_origin is None else self.time_origin + float(t[0]),
                )
            )
        return out

    def to_si(self) -> "SensorLog":
        """A log with gyro channels in rad/s and accel channels in m/s^2.

        Other channels are unchanged; ``unit_origin`` of a converted channel gets
        "+converted". Raises ParameterError when a gyro or accel channel has no
        known unit.
        """
        chans = dict(self.channels)
        units = dict(self.units)
        origin = dict(self.unit_origin)
        for group, si in SI_UNITS.items():
            for name in self.groups.get(group, ()):
                factor = si_factor(group, self.units.get(name, ""))
                if factor is None:
                    raise ParameterError(
                        f"channel {name!r} has unit {self.units.get(name, '')!r}, which has no known"
                        f" factor to {si}; declare its unit"
                    )
                if factor != 1.0:
                    chans[name] = self.channels[name] * factor
                units[name] = si
                origin[name] = origin.get(name, "") + "+converted" if factor != 1.0 else origin.get(name, "")
        return replace(self, channels=chans, units=units, unit_origin=origin)
