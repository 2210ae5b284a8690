"""The public statistics' common path: compute, then attach noise type, EDF and interval.

Every public statistic function is a thin wrapper: it describes its estimator
with a :class:`~sigmatau.core.driver.Statistic` and calls :func:`run`. In-memory
data go through :func:`sigmatau.core.driver.compute` and
:func:`sigmatau.uncertainty.attach.attach`; a record computed piecewise (a
:class:`~sigmatau.core.driver.StreamedSeries`: a ``ChunkedSeries``, a dask
array) computes itself through the protocol's methods, with the same result.
"""

from __future__ import annotations

from typing import Optional

import numpy as np

from ..core.driver import Statistic, compute, streamed, validated_samples
from ..core.result import StabilityResult
from ..core.validate import unscale_variance
from ..uncertainty.attach import attach, check_options
from ..uncertainty.confidence import ONE_SIGMA

__all__ = ["run", "finish", "id_factors"]


def run(
    stat: Statistic,
    data: object,
    *,
    rate: object,
    data_type: object,
    taus: object,
    m: object,
    points_per_decade: int = 10,
    alpha: object = None,
    confidence: object = ONE_SIGMA,
    ci: object = "chi2",
    raw: bool = False,
) -> StabilityResult:
    """Compute ``stat`` on ``data`` and return its result.

    The variance is the raw estimator (no bias correction). Unless ``ci`` is
    None, each row also gets its noise type, EDF and interval
    (:mod:`sigmatau.uncertainty.attach`); ``raw=True`` skips that step for callers
    that attach it themselves (after a bias correction, for instance).

    The kernel runs on the data scaled by an exact power of two, 2**-k, into
    [0.5, 1) and the variance is multiplied back by 4**k: every statistic is
    homogeneous of degree two (var(c·x) = c²·var(x)), so the result is the same
    while no intermediate square can overflow or underflow. A variance that
    float64 cannot hold is a DataError, never inf or 0.
    """
    src = streamed(data)
    if src is not None:
        # The streamed record scales its data by 2**-k and checks the variance itself.
        return src.__sigmatau_statistic__(stat, rate=rate, data_type=data_type, taus=taus, m=m,
                                          points_per_decade=points_per_decade, alpha=alpha,
                                          confidence=confidence, ci=ci, raw=raw)
    alpha_i, conf, ci_m = check_options(alpha, confidence, ci)
    result, given = compute(stat, data, rate=rate, data_type=data_type, taus=taus, m=m,
                            points_per_decade=points_per_decade)
    if raw:
        return result
    # Noise identification is scale-invariant: it gets the scaled samples.
    return attach(result, given, result.data_type, alpha=alpha_i, confidence=conf, ci=ci_m,
                  id_factors=id_factors(stat, result.m))


def id_factors(stat: Statistic, ms: np.ndarray) -> np.ndarray:
    """Averaging factors at which the noise type is identified: that of the τ reported."""
    if stat.tau_factor == 1.0:
        return ms
    return np.maximum(1, np.round(stat.tau_factor * ms)).astype(np.int64)


def finish(result: StabilityResult, data: object, data_type: str, *, alpha: object = None,
           confidence: object = ONE_SIGMA, ci: object = "chi2",
           identified: Optional[tuple[np.ndarray, np.ndarray]] = None) -> StabilityResult:
    """Attach noise type, EDF and interval to a result built with ``run(..., raw=True)``."""
    src = streamed(data)
    if src is not None:
        return src.__sigmatau_finish__(result, data_type, alpha=alpha, confidence=confidence, ci=ci,
                                       identified=identified)
    alpha_i, conf, ci_m = check_options(alpha, confidence, ci)
    # The variance was computed by the caller's kernel: refuse one float64 could not hold.
    unscale_variance(result.var, 0, result.statistic)
    # Scale-invariant noise identification on the scaled samples (no overflow at 1e±300).
    given, _ = validated_samples(data, remove_offset=True)
    return attach(result, given, data_type, alpha=alpha_i, confidence=conf, ci=ci_m,
                  id_factors=None if identified is not None else result.m, identified=identified)
