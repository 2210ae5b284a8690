"""Shared checks of the preparation steps and the noise model behind their standard errors.

Every estimator of :mod:`sigmatau.prep` except the non-linear fits is a linear functional
``θ̂ = Σ c_i v_i`` of the samples ``v`` (phase or frequency). Its variance under a power-law
noise model follows from the weights alone, so the standard error is exact for that model
with only the noise level estimated from the data (from differences that ignore the
offset and the drift):

* ``"wpm"`` white phase: ``x_i`` independent, variance ``σx²``; estimated as ``⟨(Δ³x)²⟩/20``.
* ``"wfm"`` white frequency: ``y_i`` independent, variance ``σy²``; estimated as
  ``Var(Δy)/2`` (the Allan variance at τ0), i.e. ``Var(Δ²x)/(2τ0²)`` on phase.
* ``"rwfm"`` random-walk frequency: ``y_i − y_{i−1}`` independent, variance ``σw²``;
  estimated as ``Var(Δy)`` (``Var(Δ²x)/τ0²`` on phase).

``Var`` removes the mean of the differences (a linear frequency drift adds a constant to
Δy and Δ²x). Under random-walk models the variance is conditional on the state at the
first sample, which the drift estimators do not depend on.
"""

from __future__ import annotations

from typing import Literal

import numpy as np

from ..core.validate import as_series, check_data_type, check_rate
from ..errors import DataError, ParameterError

__all__ = [
    "Noise",
    "NOISE_MODELS",
    "series",
    "rate_of",
    "data_type_of",
    "noise_of",
    "count_valid",
    "noise_level",
    "functional_variance",
]

Noise = Literal["wpm", "wfm", "rwfm"]
NOISE_MODELS: tuple[str, ...] = ("wpm", "wfm", "rwfm")


def series(data: object, name: str = "data") -> np.ndarray:
    """``data`` as a new 1-D float64 array in which NaN marks a gap (masked values become NaN).

    The checks of every statistic (:func:`sigmatau.core.validate.as_series` with ``gaps=True``),
    on a copy: a step never writes into its input.

    Raises
    ------
    DataError
        Non-numeric, not 1-D, empty, holding ±inf, or without a single valid sample.
    """
    return np.array(as_series(data, name, gaps=True), dtype=np.float64, copy=True)


def rate_of(rate: object) -> float:
    """The sample rate (Hz), checked as everywhere else in sigmatau."""
    return check_rate(rate)


def data_type_of(data_type: object) -> str:
    """``"freq"`` or ``"phase"``, else ParameterError."""
    return check_data_type(data_type)


def noise_of(noise: object) -> str:
    """One of :data:`NOISE_MODELS`, else ParameterError."""
    if noise not in NOISE_MODELS:
        raise ParameterError(f"noise={noise!r} must be one of {NOISE_MODELS}")
    return str(noise)


def count_valid(v: np.ndarray) -> int:
    """The number of samples that are not gaps."""
    return int(np.count_nonzero(~np.isnan(v)))


def _diff_valid(v: np.ndarray, order: int) -> np.ndarray:
    """The order-th differences whose every sample is valid (a NaN anywhere in a window drops it)."""
    d = np.diff(v, n=order)
    return d[~np.isnan(d)]


def noise_level(v: np.ndarray, data_type: str, noise: str, tau0: float) -> tuple[float, int]:
    """The level of ``noise`` in ``v`` (σx², σy² or σw², see the module notes) and the terms used.

    Raises
    ------
    DataError
        When too few gap-free differences exist to estimate it.
    """
    phase = data_type == "phase"
    if noise == "wpm":
        d = _diff_valid(v, 3 if phase else 2)
        need = 1
    else:
        d = _diff_valid(v, 2 if phase else 1)
        need = 2
    if d.size < need:
        raise DataError(f"too few gap-free differences ({d.size}) to estimate the {noise} noise level")
    if noise == "wpm":
        # Δ³x of white phase: weights 1, −3, 3, −1 (Σ = 20); on frequency τ0·Δ²y = Δ³x.
        scale = 1.0 if phase else tau0
        return float(np.mean((d * scale) ** 2) / 20.0), int(d.size)
    var = float(np.var(d, ddof=1))
    if phase:
        var /= tau0 ** 2  # Δ²x/τ0 = Δy
    return (var / 2.0 if noise == "wfm" else var), int(d.size)


def _tail_sums(c: np.ndarray) -> np.ndarray:
    """``T_k = Σ_{i≥k} c_i`` for k = 1 … n−1 (the weight an increment between k−1 and k carries)."""
    return np.cumsum(c[::-1])[::-1][1:]


def functional_variance(c: np.ndarray, data_type: str, noise: str, level: float, tau0: float) -> float:
    """Variance of ``Σ c_i v_i`` (gaps carry weight 0) under ``noise`` of the given level.

    Notes
    -----
    Phase ``x``: WPM ``σx² Σc²``; WFM ``x_i = x_0 + τ0 Σ_{j<i} y_j`` gives ``τ0² σy² Σ_j C_j²``
    with ``C_j = Σ_{i>j} c_i``; RWFM adds one more summation, ``τ0² σw² Σ_l D_l²`` with
    ``D_l = Σ_{j≥l} C_j``. Frequency ``y``: WPM ``y_j = (x_{j+1} − x_j)/τ0`` gives
    ``σx²/τ0² Σ_i (c_{i−1} − c_i)²``; WFM ``σy² Σc²``; RWFM ``σw² Σ_l (Σ_{j≥l} c_j)²``.
    """
    c = np.nan_to_num(np.asarray(c, dtype=np.float64))
    if data_type == "phase":
        if noise == "wpm":
            s = float(np.dot(c, c))
        else:
            big_c = _tail_sums(c)  # C_j for j = 0 … n−2
            if noise == "wfm":
                s = tau0 ** 2 * float(np.dot(big_c, big_c))
            else:
                d = _tail_sums(big_c)
                s = tau0 ** 2 * float(np.dot(d, d))
    else:
        if noise == "wpm":
            e = np.diff(np.concatenate(([0.0], c, [0.0])))
            s = float(np.dot(e, e)) / tau0 ** 2
        elif noise == "wfm":
            s = float(np.dot(c, c))
        else:
            d = _tail_sums(c)
            s = float(np.dot(d, d))
    return level * s
