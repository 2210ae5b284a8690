"""The preparation steps of the main job, applied to every channel of a log before its statistics.

The order is fixed and documented (docs/prep.md): **part → outliers → drift → average**. A part
first, so that every later estimate reads only the samples analysed; outliers before the drift,
so that a spike cannot tilt the drift fit; the drift before averaging, so that it is estimated at
the full resolution. Each step is the :mod:`sigmatau.prep` function of that name; its record
(parameters, estimates with standard errors, samples affected) goes with the channel into
results.json and the report.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, replace
from typing import Any, Optional

import numpy as np

from ..errors import ParameterError
from ..prep import DRIFT_MODELS, average, drift, outliers, part

__all__ = ["Preparation", "prepare_log", "parse_part"]

#: Channel groups that hold no sensor noise: only the steps that keep the channels aligned
#: (part, average) apply to them.
_AUXILIARY = ("temperature",)


@dataclass(frozen=True)
class Preparation:
    """What to do to every channel before the statistics, in the order of the fields.

    Attributes
    ----------
    part : (start, stop) in seconds, optional
        Keep ``[start, stop)``, seconds from the first sample (either may be None).
    outliers : float, optional
        Replace by gaps the samples farther than ``k`` robust standard deviations from the
        median (:func:`sigmatau.prep.outliers` with ``action="gap"``).
    drift : str, optional
        Remove the drift with this model (:data:`sigmatau.prep.DRIFT_MODELS`).
    average : int, optional
        Average m consecutive samples (the rate becomes rate/m).
    """

    part: Optional[tuple[Optional[float], Optional[float]]] = None
    outliers: Optional[float] = None
    drift: Optional[str] = None
    average: Optional[int] = None

    def __bool__(self) -> bool:
        return any(v is not None for v in asdict(self).values())

    def describe(self) -> str:
        """One line: the steps in order, e.g. ``"part 10–600 s, outliers k=5 (gaps), drift linear"``."""
        done = []
        if self.part is not None:
            a, b = self.part
            done.append(f"part {'start' if a is None else f'{a:g}'}–{'end' if b is None else f'{b:g}'} s")
        if self.outliers is not None:
            done.append(f"outliers k={self.outliers:g} (gaps)")
        if self.drift is not None:
            done.append(f"drift {self.drift}")
        if self.average is not None:
            done.append(f"average {self.average}")
        return ", ".join(done)


def parse_part(text: str) -> tuple[Optional[float], Optional[float]]:
    """``"START:END"`` in seconds (either side may be empty) as ``(start, stop)``.

    >>> parse_part("10:600"), parse_part(":60"), parse_part("5:")
    ((10.0, 600.0), (None, 60.0), (5.0, None))
    """
    if not isinstance(text, str) or text.count(":") != 1:
        raise ParameterError(f"part={text!r} must be START:END in seconds (either may be empty), e.g. 10:600")
    a, b = (s.strip() for s in text.split(":"))
    try:
        return (float(a) if a else None, float(b) if b else None)
    except ValueError:
        raise ParameterError(f"part={text!r} must be START:END in seconds (either may be empty), e.g. 10:600") from None


def prepare_log(log: Any, prep: Optional[Preparation]) -> tuple[Any, dict[str, tuple[dict, ...]]]:
    """The log with every channel prepared, and each channel's records of the steps.

    The input log is not modified (a new log is returned); timestamps follow the part and the
    averaging (each average keeps the time of its first sample) and the rate becomes rate/m.
    """
    if not prep:
        return log, {}
    if prep.drift is not None and prep.drift not in DRIFT_MODELS.get(log.data_type, ()):
        models = ", ".join(DRIFT_MODELS.get(log.data_type, ()))
        raise ParameterError(f"drift={prep.drift!r} is not a model for {log.data_type} data; use one of: {models}")
    channels: dict[str, np.ndarray] = {}
    records: dict[str, tuple[dict, ...]] = {}
    kept = None
    for name, x in log.channels.items():
        aux = log.group_of(name) in _AUXILIARY
        done = []
        if prep.part is not None:
            r = part(x, start=prep.part[0], stop=prep.part[1], rate=log.rate, unit="seconds")
            kept = r.details["range"]
            done.append(r)
        if prep.outliers is not None and not aux:
            done.append(outliers(done[-1].data if done else x, k=prep.outliers, action="gap",
                                 data_type=log.data_type))
        if prep.drift is not None and not aux:
            done.append(drift(done[-1].data if done else x, data_type=log.data_type, rate=log.rate,
                              model=prep.drift))
        if prep.average is not None:
            done.append(average(done[-1].data if done else x, factor=prep.average, data_type=log.data_type))
        channels[name] = done[-1].data if done else x
        records[name] = tuple(r.to_dict() for r in done)
    size = len(next(iter(channels.values())))
    return replace(log, channels=channels, timestamps=_timestamps(log.timestamps, kept, prep.average, size),
                   rate=log.rate / prep.average if prep.average else log.rate), records


def _timestamps(t: Optional[np.ndarray], kept: Optional[list[int]], m: Optional[int],
                size: int) -> Optional[np.ndarray]:
    if t is None:
        return None
    if kept is not None:
        t = t[kept[0]:kept[1]]
    if m:
        t = t[::m][:size]  # each average (or phase point kept) at the time of its first sample
    return t - t[0] if t.size else t
