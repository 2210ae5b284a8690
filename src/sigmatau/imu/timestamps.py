"""Checks of a log's timestamps: out-of-order, duplicated and missing samples, and the rate they imply.

Reports without rejecting anything (:mod:`sigmatau.io` applies the policies
when it reads a log). Public through :mod:`sigmatau.checks`.
"""

from __future__ import annotations

import warnings
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from ..core.validate import as_series
from ..errors import ParameterError
from .checks import DataCheckWarning

__all__ = ["TimestampWarning", "TimestampChecks", "check_timestamps"]


class TimestampWarning(DataCheckWarning):
    """Time stamps out of order, duplicated or missing."""


@dataclass(frozen=True)
class TimestampChecks:
    """Findings of :func:`check_timestamps`.

    Attributes
    ----------
    n_samples : int
    rate : float
        Sample rate from the median interval (robust to gaps).
    mean_rate : float
        ``(n − 1)/(t_last − t_first)`` as some tools compute it; lower than
        ``rate`` when samples are missing.
    backwards : int
        Intervals that go back in time.
    duplicates : int
        Intervals of zero length.
    gaps : int
        Intervals longer than 1.5 median intervals.
    missing : int
        Samples missing in those gaps (estimate).
    jitter : float
        Standard deviation of the intervals over their median (forward ones).
    order : numpy.ndarray
        Indices that sort the time stamps (stable), to reorder rather than drop.
    findings : tuple of str
    """

    n_samples: int
    rate: float
    mean_rate: float
    backwards: int
    duplicates: int
    gaps: int
    missing: int
    jitter: float
    order: np.ndarray = field(repr=False)
    findings: tuple[str, ...] = ()

    def to_dict(self) -> dict[str, Any]:
        """Plain dictionary without ``order`` (JSON-ready)."""
        out = asdict(self)
        out.pop("order")
        out["findings"] = list(self.findings)
        return out


def check_timestamps(t: object, *, scale: float = 1.0, warn: bool = True) -> TimestampChecks:
    """Out-of-order, duplicated and missing time stamps, and the rate they imply.

    Parameters
    ----------
    t : array_like
        Time stamps, in seconds times ``scale`` (``scale=1e-9`` for the
        nanoseconds of a EuRoC ``data.csv``).
    scale : float
        Factor from the stamps' unit to seconds.
    warn : bool
        Issue a :class:`TimestampWarning` when anything is found.

    Returns
    -------
    TimestampChecks
        Nothing is dropped: ``order`` sorts the samples, and the caller decides
        what to do with duplicates and gaps.

    Examples
    --------
    >>> import numpy as np
    >>> from sigmatau.checks import check_timestamps
    >>> t = np.arange(1000) * 0.005
    >>> t = np.delete(t, range(100, 120))          # 20 dropped samples
    >>> c = check_timestamps(t, warn=False)
    >>> round(c.rate, 6), c.gaps, c.missing
    (200.0, 1, 20)
    """
    ts = as_series(t, "t") * float(scale)
    if ts.size < 3:
        raise ParameterError(f"check_timestamps needs at least 3 time stamps, got {ts.size}")
    dt = np.diff(ts)
    forward = dt[dt > 0]
    if forward.size == 0:
        raise ParameterError("the time stamps never increase")
    med = float(np.median(forward))
    backwards = int(np.count_nonzero(dt < 0))
    duplicates = int(np.count_nonzero(dt == 0))
    long = forward > 1.5 * med
    gaps = int(long.sum())
    missing = int(np.sum(np.round(forward[long] / med) - 1))
    span = float(ts.max() - ts.min())
    mean_rate = (ts.size - 1) / span if span > 0 else float("nan")
    jitter = float(np.std(forward[~long]) / med) if (~long).any() else 0.0
    findings = []
    if backwards:
        findings.append(f"{backwards} time stamp(s) go backwards: sort the samples (order) instead of dropping them")
    if duplicates:
        findings.append(f"{duplicates} duplicated time stamp(s)")
    if gaps:
        findings.append(f"{gaps} gap(s) with about {missing} missing samples; the rate from the mean interval"
                        f" ({mean_rate:.6g} Hz) is lower than from the median ({1.0 / med:.6g} Hz)")
    if warn and findings:
        warnings.warn("; ".join(findings), TimestampWarning, stacklevel=2)
    return TimestampChecks(n_samples=int(ts.size), rate=1.0 / med, mean_rate=mean_rate, backwards=backwards,
                           duplicates=duplicates, gaps=gaps, missing=missing, jitter=jitter,
                           order=np.argsort(ts, kind="stable"), findings=tuple(findings))
