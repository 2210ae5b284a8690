"""Frequency offset (normalisation): estimate the mean frequency and remove it."""

from __future__ import annotations

from typing import Literal

import numpy as np

from ..errors import DataError
from ._common import count_valid, data_type_of, functional_variance, noise_level, noise_of, rate_of, series
from ._linear import poly_fit
from ._result import Estimate, PrepResult

__all__ = ["frequency_offset"]


def frequency_offset(data: object, *, data_type: Literal["freq", "phase"], rate: float,
                     noise: Literal["wpm", "wfm", "rwfm"] | None = None) -> PrepResult:
    r"""Remove the frequency offset: the mean frequency, or on phase data the linear phase slope.

    Parameters
    ----------
    data : array_like
        Frequency or phase samples; NaN marks a gap. Not modified.
    data_type : {"freq", "phase"}
        What ``data`` holds.
    rate : float
        Sample rate in Hz (τ0 = 1/rate).
    noise : {"wpm", "wfm", "rwfm"}, optional
        The noise the standard error assumes; by default white FM for frequency data and
        white PM for phase data (the noises for which these estimators are optimal).

    Returns
    -------
    PrepResult
        ``data``: the series with the offset removed; ``estimates["frequency_offset"]`` ± its
        standard error (in the units of frequency data; on phase data in data/s, which is
        s/s for phase in seconds); for phase data also ``["phase_offset"]``, the fitted
        phase at the first sample.

    Raises
    ------
    ParameterError
        Bad data_type, rate or noise.
    DataError
        All NaN or too few valid samples (2 for frequency, 3 for phase).

    Notes
    -----
    Frequency data: ``ȳ = (1/n)·Σ y_i`` over the n valid samples, residual ``y_i − ȳ``.
    Phase data: the least-squares line ``x(t) = a + b·t``, residual ``x_i − a − b·t_i``; b is the
    frequency offset (Stable32's "Linear" frequency-offset method, optimal for white PM).
    The standard error is ``√(cᵀΣc)`` for the estimator's weights c under the chosen noise,
    with its level estimated from differences of the data (see :func:`sigmatau.prep.drift`).
    A constant frequency (linear phase) does not change any Allan-family statistic; remove it
    for plots, for the standard deviation and before a drift fit that ignores it.

    References
    ----------
    W. J. Riley, NIST SP 1065 (2008), §10.8 "Drift analysis" (frequency offset in phase data);
    Stable32 User Manual, Drift function (Linear, Avg of 1st Diff, Endpoints).

    Examples
    --------
    >>> from sigmatau.prep import frequency_offset
    >>> r = frequency_offset([1.0, 2.0, float("nan"), 2.0, 1.0], data_type="freq", rate=1.0)
    >>> r.estimates["frequency_offset"].value, r.data.tolist()
    (1.5, [-0.5, 0.5, nan, 0.5, -0.5])
    """
    v = series(data)
    data_type = data_type_of(data_type)
    tau0 = 1.0 / rate_of(rate)
    noise = noise_of(noise) if noise is not None else ("wfm" if data_type == "freq" else "wpm")
    valid = ~np.isnan(v)
    n = count_valid(v)
    need = 2 if data_type == "freq" else 3
    if n < need:
        raise DataError(f"frequency_offset of {data_type} data needs at least {need} valid samples, got {n}")
    level, n_level = noise_level(v, data_type, noise, tau0)
    t = np.arange(v.size) * tau0
    estimates: dict[str, Estimate] = {}
    if data_type == "freq":
        c = np.where(valid, 1.0 / n, 0.0)
        mean = float(np.mean(v[valid]))
        se = float(np.sqrt(functional_variance(c, data_type, noise, level, tau0)))
        estimates["frequency_offset"] = Estimate(mean, se, "data")
        out = v - mean
        note = f"mean frequency {mean:.6g} ± {se:.2g} removed"
    else:
        alpha, w = poly_fit(v, t, 1)
        ses = [float(np.sqrt(functional_variance(w[k], data_type, noise, level, tau0))) for k in range(2)]
        estimates["frequency_offset"] = Estimate(float(alpha[1]), ses[1], "data/s")
        estimates["phase_offset"] = Estimate(float(alpha[0]), ses[0], "data")
        out = v - (alpha[0] + alpha[1] * t)
        note = f"linear phase slope (frequency offset) {alpha[1]:.6g} ± {ses[1]:.2g} removed"
    out.flags.writeable = False
    return PrepResult(step="frequency_offset", data=out, data_type=data_type,
                      parameters={"rate": rate}, estimates=estimates,
                      details={"noise": noise, "noise_level": level, "noise_terms": n_level, "valid": n},
                      notes=(note + f" (standard error for {noise.upper()} noise)",))
