"""From a stream's sums to the batch's :class:`~sigmatau.core.result.StabilityResult`.

:data:`STATISTICS` names the streamable estimators and their batch
:class:`~sigmatau.core.driver.Statistic` (which gives the τ grid, the term
counts and the too-short error). :func:`raw_result` turns the running sums of
squares into variances with the batch kernels' normalisations
(SP1065 §5.2; numerics.md §1), :func:`totvar_edges` adds TOTDEV's reflected end
terms, and :func:`finish` attaches noise type, EDF and interval through the
batch's own :func:`~sigmatau.uncertainty.attach.attach`.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Callable, Optional

import numpy as np

from ..core.driver import Statistic
from ..core.kernels import AVAR, MVAR, OAVAR, TVAR
from ..core.result import StabilityResult
from ..core.taus import m_grid
from ..core.validate import unscale_variance
from ..errors import DataError
from ..stats.hadamard import HVAR, OHVAR
from ..stats.total import TOTVAR
from ..uncertainty.attach import attach
from ..uncertainty.confidence import EDF_STATISTICS

__all__ = ["STATISTICS", "rows", "raw_result", "totvar_edges", "finish", "check_length"]

#: The statistics a :class:`~sigmatau.stream.Stream` computes, by name.
STATISTICS: dict[str, Statistic] = {
    "adev": AVAR, "oadev": OAVAR, "mdev": MVAR, "tdev": TVAR, "hdev": HVAR, "ohdev": OHVAR, "totdev": TOTVAR,
}

#: Each statistic's sum of squares in the chain (TDEV is MDEV's, TOTDEV starts from OADEV's).
SUM_OF = {"adev": "adev", "oadev": "oadev", "mdev": "mdev", "tdev": "mdev", "hdev": "hdev", "ohdev": "ohdev",
          "totdev": "oadev"}


def check_length(name: str, n_samples: int, data_type: str) -> int:
    """Phase points N of ``n_samples``; the batch's DataError when the statistic needs more."""
    stat = STATISTICS[name]
    n_points = n_samples if data_type == "phase" else n_samples + 1
    if n_samples == 0 or n_points < stat.min_points:
        kind = "phase" if data_type == "phase" else "frequency"
        need = stat.min_points if data_type == "phase" else stat.min_points - 1
        raise DataError(f"{name} needs at least {need} {kind} samples, got {n_samples}")
    return n_points


def rows(name: str, n_points: int, max_factor: int) -> np.ndarray:
    """The batch's octave grid for ``n_points`` phase points (:func:`sigmatau.core.taus.select_m`),
    less the factors above ``max_factor``."""
    stat = STATISTICS[name]
    default_max = min(stat.max_m(n_points), max(stat.min_m, int(n_points // stat.stop_ratio)))
    ms = m_grid("octave", default_max, m_min=stat.min_m)
    return ms[ms <= max_factor]


def term_counts(name: str, n_points: int, ms: np.ndarray) -> np.ndarray:
    """Terms of each estimator at N phase points (those of the batch kernels)."""
    counts: dict[str, Callable[[np.ndarray], np.ndarray]] = {
        "oadev": lambda m: n_points - 2 * m, "ohdev": lambda m: n_points - 3 * m,
        "mdev": lambda m: n_points - 3 * m + 1, "tdev": lambda m: n_points - 3 * m + 1,
        "totdev": lambda m: np.full(m.shape, n_points - 2), "adev": lambda m: (n_points - 1) // m - 1,
        "hdev": lambda m: (n_points - 1) // m - 2,
    }
    return np.asarray(counts[name](ms), dtype=np.int64)


def raw_result(name: str, sums: np.ndarray, ms: np.ndarray, *, n_points: int, rate: float, data_type: str,
               exponent: int, edges: Optional[np.ndarray] = None) -> StabilityResult:
    """The result of ``name`` (no noise type or interval) from the sums of squares at ``ms``.

    ``sums`` holds the chain's sum of squares of the statistic at each row (in the units of
    the scaled samples, 2**-exponent of the user's), ``edges`` TOTDEV's reflected terms.
    The divisors are those of the batch kernels: ``2m²k`` (OAVAR, AVAR), ``6m²k``
    (OHVAR, HVAR), ``2m⁴k`` (MVAR) on frequency samples, with ``m²`` read ``(mτ0)²`` for
    phase (the terms are then phase differences); TVAR = MVAR·τ²/3.
    """
    tau0 = 1.0 / rate
    n = term_counts(name, n_points, ms)
    scale = (ms * tau0) ** 2 if data_type == "phase" else ms.astype(float) ** 2
    if name in ("oadev", "adev"):
        var = sums / (2.0 * scale * n)
    elif name in ("ohdev", "hdev"):
        var = sums / (6.0 * scale * n)
    elif name == "totdev":
        var = (sums + edges) / (2.0 * scale * (n_points - 2))
    else:
        var = sums / (2.0 * ms.astype(float) ** 2 * scale * n)
        if name == "tdev":
            var = var * (ms * tau0) ** 2 / 3.0
    var = unscale_variance(np.where(var < 0.0, 0.0, var), exponent, name)
    return StabilityResult(statistic=name, taus=STATISTICS[name].tau_factor * ms * tau0, m=ms, var=var,
                           dev=np.sqrt(var), n=n, rate=rate, data_type=data_type, n_points=int(n_points))


def totvar_edges(head: np.ndarray, tail: np.ndarray, ms: np.ndarray, n_points: int) -> np.ndarray:
    """TOTVAR's reflected terms at each factor, ``Σ (x*_{i−m} − 2x*_i + x*_{i+m})²`` over
    ``i < m`` and ``i ≥ N − m`` (the terms ``m ≤ i < N − m`` are OAVAR's own).

    ``head`` holds the first and ``tail`` the last frequency samples (scaled, shifted) of the
    record, at least 2m − 1 of each for the largest m; the phase of each end is their running
    sum (a line's worth of offset is immaterial: TOTVAR extends a line as a line). The
    reflection is ``x*_{−j} = 2x_0 − x_j`` and ``x*_{N−1+j} = 2x_{N−1} − x_{N−1−j}``, and each
    term is formed as the batch's ``left − 2.0·mid + right`` (SP1065 §5.2.11). The running
    sums are taken in extended precision (``numpy.longdouble``, where the platform has it):
    a sequential sum of 2m − 1 samples would lose √(2m) roundings of its own size, 1e-13
    of a term at m = 2**13.
    """
    out = np.zeros(ms.size)
    head = head.astype(np.longdouble)
    tail = tail.astype(np.longdouble)
    zero = np.zeros(1, dtype=np.longdouble)
    for r, m in enumerate(ms.tolist()):
        if m < 2:
            continue  # no term reads outside the record
        x = np.concatenate((zero, np.cumsum(head[: 2 * m - 1])))  # x_0 … x_{2m-1}, x_0 = 0
        i = np.arange(1, m)
        left = ((2.0 * x[0] - x[m - i]) - 2.0 * x[i] + x[i + m]).astype(np.float64)
        z = np.concatenate((zero, np.cumsum(tail[tail.size - (2 * m - 1) :])))  # x_{N-2m} … x_{N-1}
        i = np.arange(m, 2 * m - 1)  # i = N-m … N-2, counted from N-2m
        right = ((z[i - m] - 2.0 * z[i]) + (2.0 * z[-1] - z[2 * (2 * m - 1) - i - m])).astype(np.float64)
        out[r] = np.einsum("i,i->", left, left) + np.einsum("i,i->", right, right)
    return out


def finish(result: StabilityResult, *, confidence: float, ci: Optional[str],
           identified: Callable[[], tuple[np.ndarray, np.ndarray]]) -> StabilityResult:
    """Noise type, EDF and interval by :func:`~sigmatau.uncertainty.attach.attach` from the
    stream's identification; when that fails, the batch's reason on every row."""
    if ci is None or len(result) == 0:
        return result
    try:
        alpha, estimate = identified()
    except DataError as exc:
        nan = np.full(len(result), np.nan)
        out = attach(result, np.empty(0), result.data_type, alpha=None, confidence=confidence, ci=ci,
                     identified=(nan, nan))
        if ci == "chi2" and result.statistic in EDF_STATISTICS:
            reason = f"noise type not identified ({exc}); give alpha= for an interval"
            out = replace(out, ci_reason=(reason,) * len(result))
        return out
    return attach(result, np.empty(0), result.data_type, alpha=None, confidence=confidence, ci=ci,
                  identified=(alpha, estimate))
