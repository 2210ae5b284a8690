"""Column names: IMU channel recognition, the time column, and selection by name or index."""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Sequence

from ..errors import DataError, ParameterError
from ._errors import option_hint
from ._limits import MAX_CHANNELS, check_channels
from ._units import canonical_unit, time_unit_name

__all__ = ["Recognised", "recognise", "time_name", "select", "list_names", "strip_name", "unused_message",
           "short_name"]

_BRACKET_UNIT = re.compile(r"\s*[\[\(]([^\]\)]*)[\]\)]\s*$")
_GYRO_PREFIX = (
    r"gyro|gyr|gyros|gyroscope|w|omega|angular_velocity|angular_rate|ang_vel|angvel|angrate|g"
)
_ACCEL_PREFIX = (
    r"accel|acc|accl|accelerometer|acceleration|a|linear_acceleration|lin_acc|linacc|linear_accel"
)
_AXIS = r"(?P<axis>[xyz])"
_UNIT_SUFFIX = (
    r"(?:_(?P<unit>dps|degps|deg_s|mdps|rads|rad_s|radps|dph|g|mg|ug|mps2|m_s2|mpss))?"
)
_CHANNEL = re.compile(
    rf"^(?:(?P<gyro>{_GYRO_PREFIX})|(?P<accel>{_ACCEL_PREFIX}))_?{_AXIS}{_UNIT_SUFFIX}$"
)
_TEMPERATURE = re.compile(r"^(?:imu_)?(?:temp|temperature)(?:_(?P<unit>c|degc|k))?$")
_TIME = re.compile(
    r"^(?P<base>t|time|timestamp|timestamps|stamp|ts|sec|secs|seconds|epoch|unix_time|mjd"
    r"|header_stamp|rosbagtimestamp|time_stamp)(?:_(?P<unit>s|sec|ms|msec|us|usec|ns|nsec|mjd))?$"
)


def strip_name(name: str) -> tuple[str, str | None]:
    """Split ``"w_RS_S_x [rad s^-1]"`` into ``("w_RS_S_x", "rad s^-1")``; drop a leading '#' or '%'."""
    s = name.strip().lstrip("#%").strip()
    m = _BRACKET_UNIT.search(s)
    if m and m.start() > 0:
        return s[: m.start()].strip(), m.group(1).strip()
    return s, None


def _key(base: str) -> str:
    s = base.lower()
    if s.startswith("field."):  # rostopic echo -p
        s = s[len("field."):]
    # one separator stands for '_'; runs of them and '/' are left as they are, so
    # 'a/../../x' or 'gyro__x' match no pattern instead of passing for a channel
    s = re.sub(r"[.\s\-]", "_", s)
    s = re.sub(r"_rs_s_", "_", s)  # EuRoC/ASL: w_RS_S_x, a_RS_S_x
    return s


@dataclass(frozen=True)
class Recognised:
    """What a column name says: canonical channel name, group and unit (None when unknown)."""

    name: str | None
    group: str | None
    unit: str | None


def recognise(name: str) -> Recognised:
    """Recognise an IMU channel from a column name.

    >>> recognise("w_RS_S_x [rad s^-1]")
    Recognised(name='gyro_x', group='gyro', unit='rad/s')
    >>> recognise("acc_z_g")
    Recognised(name='accel_z', group='accel', unit='g')
    >>> recognise("field.angular_velocity.y")
    Recognised(name='gyro_y', group='gyro', unit=None)
    """
    base, bracket = strip_name(name)
    key = _key(base)
    unit = canonical_unit(bracket) if bracket else None
    m = _CHANNEL.match(key)
    if m:
        group = "gyro" if m.group("gyro") else "accel"
        if unit is None and m.group("unit"):
            unit = canonical_unit(m.group("unit"))
        return Recognised(f"{group}_{m.group('axis')}", group, unit)
    m = _TEMPERATURE.match(key)
    if m:
        unit = bracket or {"c": "degC", "degc": "degC", "k": "K"}.get(m.group("unit") or "")
        return Recognised("temperature", "temperature", unit)
    return Recognised(None, None, None)


def time_name(name: str) -> tuple[int, str | None] | None:
    """Whether a column name is a time column: (priority, unit or None), lower priority first.

    >>> time_name("#timestamp [ns]")
    (1, 'ns')
    >>> time_name("field.header.stamp"), time_name("%time"), time_name("gyro_x")
    ((0, 'ns'), (3, 'ns'), None)
    """
    raw = name.strip()
    base, bracket = strip_name(raw)
    key = _key(base)
    if raw.startswith("%") and key == "time":  # rostopic echo -p: receive time in ns
        return 3, "ns"
    if key in ("header_stamp",) and raw.lower().startswith("field."):
        return 0, "ns"
    m = _TIME.match(key)
    if not m:
        return None
    unit = time_unit_name(bracket) if bracket else None
    if unit is None and m.group("unit"):
        unit = time_unit_name(m.group("unit"))
    if unit is None and m.group("base") == "mjd":
        unit = "d"
    if unit is None and m.group("base") in ("sec", "secs", "seconds"):
        unit = "s"
    priority = 0 if m.group("base") in ("header_stamp",) else 1 if m.group("base") in (
        "t", "time", "timestamp", "timestamps", "stamp", "ts", "time_stamp") else 2
    return priority, unit


def short_name(name: str, limit: int = 60) -> str:
    """A column name quoted for a message, cut to ``limit`` characters (a header field can be huge).

    >>> short_name("gyro_x"), short_name("x" * 100, limit=4)
    ("'gyro_x'", "'xxxx'… (100 characters)")
    """
    return repr(name) if len(name) <= limit else f"{name[:limit]!r}… ({len(name):,} characters)"


def list_names(names: Sequence[str], limit: int = 40) -> str:
    """Comma-separated names for a one-line message (long lists are cut)."""
    shown = ", ".join(short_name(n) for n in names[:limit])
    return shown + (f", … {len(names) - limit} more" if len(names) > limit else "")


def _match(names: Sequence[str], wanted: str) -> list[int]:
    exact = [i for i, n in enumerate(names) if n == wanted]
    if exact:
        return exact
    low = wanted.strip().lower()
    hits = [i for i, n in enumerate(names) if n.strip().lower() == low]
    if hits:
        return hits
    hits = [i for i, n in enumerate(names) if strip_name(n)[0].lower() == strip_name(wanted)[0].lower()]
    if hits:
        return hits
    return [i for i, n in enumerate(names) if recognise(n).name == low]


def _resolve(names: Sequence[str], spec: object, *, path: str, what: str, param: str) -> int:
    n = len(names)
    if isinstance(spec, bool) or not isinstance(spec, (str, int)) and not hasattr(spec, "__index__"):
        raise ParameterError(f"{param}={spec!r} must be a {what} name or a 0-based index")
    if isinstance(spec, str):
        hits = _match(names, spec)
        if not hits:
            raise ParameterError(f"{path}: no {what} {spec!r}; {what}s are: {list_names(names)}")
        if len(hits) > 1:
            raise ParameterError(
                f"{path}: {what} {spec!r} is ambiguous: {list_names([names[i] for i in hits])}"
            )
        return hits[0]
    idx = int(spec)  # type: ignore[arg-type]
    if not -n <= idx < n:
        raise ParameterError(
            f"{path}: {param} index {idx} is out of range: the file has {n} {what}s"
            f" (0–{n - 1}): {list_names(names)}"
        )
    return idx % n


@dataclass(frozen=True)
class Selection:
    time: int | None
    time_unit: str | None  # unit the name states
    channels: tuple[int, ...]
    skipped: tuple[str, ...]  # numeric columns left out by the automatic choice
    unused: tuple[tuple[str, str], ...] = ()  # (column, why) of every column the automatic choice left out


def unused_message(path: str, unused: Sequence[tuple[str, str]], what: str = "column") -> str:
    """One line naming every column left out and why, and how to choose columns instead.

    >>> print(unused_message("a.csv", [("gyro_third", "not a recognised channel name")]))  # doctest: +ELLIPSIS
    a.csv: 1 column not used: 'gyro_third' (not a recognised channel name); choose columns with --columns ...
    """
    shown = [f"{short_name(name)} ({why})" for name, why in unused[:40]]
    more = f", … {len(unused) - 40} more" if len(unused) > 40 else ""
    plural = "" if len(unused) == 1 else "s"
    return (f"{path}: {len(unused)} {what}{plural} not used: {', '.join(shown)}{more};"
            f" choose {what}s with {option_hint('--columns', 'columns=')}")


def select(
    names: Sequence[str],
    numeric: Sequence[bool],
    *,
    columns: object,
    time_column: object,
    path: str,
    what: str = "column",
    first_bad: Sequence[str | None] | None = None,
) -> Selection:
    """Choose the time column and the channel columns.

    ``columns`` None picks every numeric column but the time column, or only the
    recognised IMU channels (gyro, accel, temperature) when there are any.
    ``time_column`` None looks for a column named like a time (t, time,
    timestamp, ``#timestamp [ns]``, ``field.header.stamp``, mjd …); False means none.
    """

    def numeric_or_raise(i: int) -> None:
        if not numeric[i]:
            sample = f" (value {first_bad[i]!r})" if first_bad and first_bad[i] is not None else ""
            raise DataError(f"{path}: {what} {names[i]!r} is not numeric{sample}")

    time_idx: int | None = None
    time_unit: str | None = None
    if time_column is False:
        pass
    elif time_column is not None:
        time_idx = _resolve(names, time_column, path=path, what=what, param="time_column")
        numeric_or_raise(time_idx)
        hit = time_name(names[time_idx])
        time_unit = hit[1] if hit else None
    else:
        found = [(p[0], i, p[1]) for i, nm in enumerate(names) if numeric[i] and (p := time_name(nm))]
        if found:
            _, time_idx, time_unit = min(found)

    unused: list[tuple[str, str]] = []
    if columns is None:
        cands = [i for i in range(len(names)) if numeric[i] and i != time_idx]
        imu = [i for i in cands if recognise(names[i]).group is not None]
        chosen = imu if imu else cands
        skipped = tuple(names[i] for i in cands if i not in chosen)
        for i, name in enumerate(names):
            if i == time_idx or i in chosen:
                continue
            if not numeric[i]:
                why = "not numeric"
            elif time_column is None and time_name(name) is not None:
                why = "another time column"
            else:
                why = "not a recognised channel name"
            unused.append((name, why))
        check_channels(path, len(chosen), what)
    else:
        specs = [columns] if isinstance(columns, (str, int)) else list(columns)  # type: ignore[call-overload]
        if not specs:
            raise ParameterError("columns=[] selects nothing; pass None for all numeric columns")
        chosen = []
        for spec in specs:
            i = _resolve(names, spec, path=path, what=what, param="columns")
            if i == time_idx:
                raise ParameterError(
                    f"{path}: {what} {names[i]!r} is the time column; it cannot also be a channel"
                    f" (to read it as data: {option_hint('--time-column none', 'time_column=False')})"
                )
            if i in chosen:
                raise ParameterError(f"{path}: {what} {names[i]!r} is selected twice")
            numeric_or_raise(i)
            chosen.append(i)
        skipped = ()
        if len(chosen) > MAX_CHANNELS:
            raise ParameterError(
                f"{path}: {len(chosen)} {what}s selected; at most {MAX_CHANNELS} channels are read at once"
            )
    if not chosen:
        if any(numeric):
            raise DataError(
                f"{path}: no numeric {what} besides the time column {names[time_idx]!r}"  # type: ignore[index]
                f"; {what}s are: {list_names(names)}"
            )
        raise DataError(f"{path}: no numeric data; {what}s are: {list_names(names)}")
    return Selection(time_idx, time_unit, tuple(chosen), skipped, tuple(unused))
