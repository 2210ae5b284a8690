"""Outlier check by the median absolute deviation (Stable32's Check function)."""

from __future__ import annotations

import math
from typing import Literal

import numpy as np

from ..errors import DataError, ParameterError
from ._common import data_type_of, series
from ._result import Estimate, PrepResult

__all__ = ["outliers", "MAD_SCALE"]

#: MAD/0.6745 estimates σ of normal data (0.6745 = Φ⁻¹(3/4)).
MAD_SCALE = 0.6745


def _check_k(k: object) -> float:
    if isinstance(k, (bool, np.bool_, str, bytes)):
        raise ParameterError(f"k={k!r} must be a positive number (a multiple of the MAD sigma)")
    try:
        value = float(k)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise ParameterError(f"k={k!r} must be a positive number (a multiple of the MAD sigma)") from None
    if not math.isfinite(value) or value <= 0.0:
        raise ParameterError(f"k={k!r} must be a positive finite number (a multiple of the MAD sigma)")
    return value


def outliers(data: object, *, k: float = 5.0, action: Literal["report", "gap"] = "report",
             data_type: Literal["freq", "phase"] = "freq") -> PrepResult:
    r"""Find outliers by the median absolute deviation; report them or replace them by gaps.

    Parameters
    ----------
    data : array_like
        Frequency or phase samples; NaN marks a gap (ignored). Not modified.
    k : float
        Threshold in MAD sigmas (Stable32's default is 5).
    action : {"report", "gap"}
        ``"report"`` returns the data unchanged; ``"gap"`` replaces the outliers by NaN.
    data_type : {"freq", "phase"}
        Phase data are checked on their first differences (see Notes).

    Returns
    -------
    PrepResult
        ``indices``: the outliers' indices into ``data``; ``details["values"]`` their values;
        ``estimates``: the median and the MAD sigma, each with its standard error.

    Raises
    ------
    ParameterError
        k ≤ 0 or not a number; an unknown action or data_type.
    DataError
        All NaN, fewer than 3 valid samples (differences for phase), or a MAD of 0 (at least
        half the samples equal the median, so there is no scale to judge by).

    Notes
    -----
    With ``m = median(y)`` and ``σ̂ = median(|y_i − m|)/0.6745`` (σ of normal data), sample i
    is an outlier when ``|y_i − m| > k·σ̂``.

    Phase data are checked on their differences ``y_i = x_{i+1} − x_i`` (the frequency, as
    Stable32 does), and each outlying difference is mapped back to a phase index by this
    rule: two consecutive outlying differences ``y_{j−1}``, ``y_j`` of opposite sign are one bad
    phase point, index j (a spike); an outlying first or last difference flags the end sample
    (x_0 or x_{N−1}); any other lone outlying difference ``y_i`` is a phase step between x_i and
    x_{i+1}: index i + 1 is flagged and listed in ``details["steps"]``. A gap removes a spike
    but not a step (the samples after it keep their offset): remove a step before the analysis.

    The standard errors are the large-sample ones for normal data: ``√(π/2)·σ̂/√n`` for the
    median and ``√1.3605·σ̂/√n`` for the MAD sigma (its efficiency is 37 % of the SD's).

    References
    ----------
    W. J. Riley, NIST SP 1065 (2008), §10.11 "Outlier recognition" (the MAD test); W. J. Riley,
    "Gaps, outliers, dead time, and uneven spacing in frequency stability data"; Stable32 User
    Manual, Check function.
    NIST/SEMATECH e-Handbook of Statistical Methods, §1.3.5.17 (detection of outliers).

    Examples
    --------
    >>> from sigmatau.prep import outliers
    >>> r = outliers([1.0, 1.1, 0.9, 1.0, 9.0, 1.05, 0.95], action="gap")
    >>> r.indices.tolist(), r.data.tolist()[4]
    ([4], nan)
    """
    v = series(data)
    kk = _check_k(k)
    if action not in ("report", "gap"):
        raise ParameterError(f"action={action!r} must be 'report' or 'gap'")
    data_type = data_type_of(data_type)
    checked = np.diff(v) if data_type == "phase" else v
    valid = ~np.isnan(checked)
    n = int(valid.sum())
    what = "gap-free differences" if data_type == "phase" else "valid samples"
    if n < 3:
        raise DataError(f"outliers needs at least 3 {what}, got {n}")
    med = float(np.median(checked[valid]))
    dev = np.abs(checked - med)
    mad = float(np.median(dev[valid]))
    if mad == 0.0:
        raise DataError(f"the median absolute deviation of the {what} is 0 (at least half equal the"
                        f" median {med:g}): there is no scale to judge outliers by")
    sigma = mad / MAD_SCALE
    with np.errstate(invalid="ignore"):
        flagged = np.flatnonzero(valid & (dev > kk * sigma))
    details: dict[str, object] = {"k": kk, "threshold": kk * sigma, "checked": n}
    if data_type == "phase":
        idx, steps = _phase_indices(flagged, checked, v.size)
        details["steps"] = steps
        details["outlying_differences"] = flagged
    else:
        idx = flagged
    idx = np.asarray(idx, dtype=np.int64)
    details["values"] = v[idx]
    out = v.copy()
    if action == "gap":
        out[idx] = np.nan
    out.flags.writeable = False
    estimates = {"median": Estimate(med, math.sqrt(math.pi / 2.0) * sigma / math.sqrt(n), "data"),
                 "sigma_mad": Estimate(sigma, math.sqrt(1.3605) * sigma / math.sqrt(n), "data")}
    done = "replaced by gaps" if action == "gap" else "reported"
    return PrepResult(step="outliers", data=out, data_type=data_type,
                      parameters={"k": kk, "action": action}, estimates=estimates, indices=idx,
                      details=details,
                      notes=(f"{idx.size} outlier(s) beyond {kk:g} MAD sigmas ({kk * sigma:.3g}) {done}",))


def _phase_indices(flagged: np.ndarray, d: np.ndarray, n: int) -> tuple[list[int], list[int]]:
    """Map outlying differences ``d_i = x_{i+1} − x_i`` to phase indices (rule in :func:`outliers`)."""
    marked = set(int(i) for i in flagged)
    out: list[int] = []
    steps: list[int] = []
    used: set[int] = set()
    for i in sorted(marked):
        if i in used:
            continue
        if i + 1 in marked and np.sign(d[i]) != np.sign(d[i + 1]):
            out.append(i + 1)  # spike at the shared point
            used.update((i, i + 1))
        elif i == 0:
            out.append(0)
        elif i == n - 2:
            out.append(n - 1)
        else:
            out.append(i + 1)
            steps.append(i + 1)
        used.add(i)
    return sorted(set(out)), steps
