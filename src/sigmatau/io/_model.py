"""The in-memory representation of a sensor log (its timing report is in ``_timing_report``)."""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any, Mapping, Sequence

import numpy as np

from ..core.validate import DataType
from ..errors import ParameterError
from ._timing_report import Gap, TimingReport
from ._units import SI_UNITS, si_factor

__all__ = ["Gap", "TimingReport", "Source", "TopicInfo", "SensorLog"]


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
        was; a marked log loses its missing samples); runs shorter than ``min_samples`` are left out. Without gaps the
        result is ``[self]``. Each segment's timestamps start at 0 and its
        ``time_origin`` is moved to its first sample; its timing report describes
        the segment.
        """
        if not self.timing.gaps or self.timestamps is None:
            return [self] if len(self) >= min_samples else []
        from ._timing import segment_report

        # a marked log holds the missing samples (NaN) just before each gap's index
        marked = self.timing.gaps_policy == "mark"
        starts = [0, *(g.index for g in self.timing.gaps)]
        stops = [*(g.index - (g.missing if marked else 0) for g in self.timing.gaps), len(self)]
        out = []
        for lo, hi in zip(starts, stops):
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
