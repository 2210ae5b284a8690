"""Unit spellings, the units of each channel group, and their SI factors.

Units are recorded as the file or the user states them; values are never
converted behind the user's back (``SensorLog.to_si`` does it on request).
"""

from __future__ import annotations

import math
import re

from ..errors import ParameterError

__all__ = [
    "DEFAULT_UNITS",
    "GROUP_UNITS",
    "SI_UNITS",
    "TIME_UNITS",
    "canonical_unit",
    "declared_unit",
    "si_factor",
    "time_unit_name",
]

STANDARD_GRAVITY = 9.80665  # m/s², CGPM 1901

#: Units understood for the gyroscope and accelerometer groups, with their SI factor.
GROUP_UNITS: dict[str, dict[str, float]] = {
    "gyro": {
        "rad/s": 1.0,
        "mrad/s": 1e-3,
        "deg/s": math.pi / 180.0,
        "mdeg/s": math.pi / 180.0e3,
        "deg/h": math.pi / 180.0 / 3600.0,
    },
    "accel": {
        "m/s^2": 1.0,
        "mm/s^2": 1e-3,
        "g": STANDARD_GRAVITY,
        "mg": STANDARD_GRAVITY * 1e-3,
        "ug": STANDARD_GRAVITY * 1e-6,
    },
}

#: SI unit of each group that :meth:`SensorLog.to_si` converts to.
SI_UNITS = {"gyro": "rad/s", "accel": "m/s^2"}

#: Unit assumed for a group when neither the file nor the caller states one
#: (ROS REP 103 and EuRoC use these).
DEFAULT_UNITS = {"gyro": "rad/s", "accel": "m/s^2"}

#: Time units accepted for ``time_unit``, with their factor to seconds ("d": days, as MJD).
TIME_UNITS = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9, "min": 60.0, "h": 3600.0, "d": 86400.0}

_ALIASES = {
    "rad/s": "rad/s", "rads": "rad/s", "radps": "rad/s", "rad_s": "rad/s",
    "mrad/s": "mrad/s",
    "deg/s": "deg/s", "dps": "deg/s", "degps": "deg/s", "deg_s": "deg/s",
    "mdeg/s": "mdeg/s", "mdps": "mdeg/s",
    "deg/h": "deg/h", "deg/hr": "deg/h", "deg/hour": "deg/h", "dph": "deg/h",
    "m/s^2": "m/s^2", "mps2": "m/s^2", "m_s2": "m/s^2", "mpss": "m/s^2",
    "mm/s^2": "mm/s^2",
    "g": "g", "mg": "mg", "ug": "ug", "micro-g": "ug", "milli-g": "mg",
}

_TIME_ALIASES = {
    "s": "s", "sec": "s", "secs": "s", "second": "s", "seconds": "s",
    "ms": "ms", "msec": "ms", "millisecond": "ms", "milliseconds": "ms",
    "us": "us", "usec": "us", "microsecond": "us", "microseconds": "us",
    "ns": "ns", "nsec": "ns", "nanosecond": "ns", "nanoseconds": "ns",
    "min": "min", "minute": "min", "minutes": "min",
    "h": "h", "hour": "h", "hours": "h",
    "d": "d", "day": "d", "days": "d", "mjd": "d",
}


def _clean(text: str) -> str:
    s = text.strip().lower()
    s = s.replace("µ", "u").replace("μ", "u").replace("°", "deg").replace("²", "^2").replace("**", "^")
    s = re.sub(r"\s*s\s*\^?\s*-1$", "/s", s)  # EuRoC: "rad s^-1"
    s = re.sub(r"\s*s\s*\^?\s*-2$", "/s^2", s)  # EuRoC: "m s^-2"
    s = s.replace(" ", "")
    s = s.replace("degrees", "deg").replace("degree", "deg").replace("/sec", "/s")
    s = re.sub(r"/s2$", "/s^2", s)
    return s


def canonical_unit(text: str) -> str | None:
    """The canonical (ASCII) spelling of a gyro or accel unit, or None when not recognised.

    >>> canonical_unit("rad s^-1"), canonical_unit("°/s"), canonical_unit("m/s²"), canonical_unit("µg")
    ('rad/s', 'deg/s', 'm/s^2', 'ug')
    """
    return _ALIASES.get(_clean(text))


def time_unit_name(text: str) -> str | None:
    """The canonical time unit ("s", "ms", "us", "ns", "min", "h", "d") or None."""
    s = text.strip().lower().replace("µ", "u").replace("μ", "u")
    return _TIME_ALIASES.get(s)


def declared_unit(group: str, text: object, *, key: str) -> str:
    """Validate a unit declared by the caller for a channel group (or channel of that group)."""
    if not isinstance(text, str) or not text.strip():
        raise ParameterError(f"units[{key!r}]={text!r} must be a non-empty unit string")
    if group in GROUP_UNITS:
        unit = canonical_unit(text)
        if unit is None or unit not in GROUP_UNITS[group]:
            allowed = ", ".join(GROUP_UNITS[group])
            flag = f"--{key}-unit {text}" if key in GROUP_UNITS else f"--unit {key}={text}"
            raise ParameterError(
                f"units[{key!r}]={text!r} ({flag}) is not a {group} unit; use one of {allowed}")
        return unit
    return text.strip()


def si_factor(group: str, unit: str) -> float | None:
    """Factor from ``unit`` to the group's SI unit, or None when there is none."""
    return GROUP_UNITS.get(group, {}).get(unit)
