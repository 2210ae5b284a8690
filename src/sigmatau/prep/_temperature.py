"""Temperature: fit the bias of a rate record against the sensor's temperature, and compensate it.

:func:`temperature_fit` fits a polynomial in temperature to block means (order chosen by
BIC), reports the coefficients and the temperature coefficient (tempco) at the mean
temperature with standard errors, and returns the record with the temperature-dependent
part of the bias removed.
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from ..errors import DataError, ParameterError, caller_stacklevel
from ._common import rate_of, series
from ._result import Estimate, PrepResult, PrepWarning

__all__ = ["temperature_fit"]

#: Blocks the record is cut into (uniform length ``n // _BLOCKS`` samples, at least 1).
_BLOCKS = 200
_MIN_BLOCKS = 5


def _check_order(max_order: object) -> int:
    if isinstance(max_order, (bool, np.bool_)) or not isinstance(max_order, (int, np.integer)):
        raise ParameterError(f"max_order={max_order!r} must be a whole number from 0 to 6")
    if not 0 <= int(max_order) <= 6:
        raise ParameterError(f"max_order={max_order!r} must lie from 0 to 6")
    return int(max_order)


def _block_means(v: np.ndarray, u: np.ndarray, ok: np.ndarray, order: int
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """Block means of the data and of ``u^k`` (k = 0 … order) over the jointly valid samples."""
    n = v.size
    m = max(1, n // _BLOCKS)
    nb = -(-n // m)
    idx = np.arange(n) // m
    counts = np.bincount(idx[ok], minlength=nb).astype(np.float64)
    used = counts > 0
    ybar = np.bincount(idx[ok], weights=v[ok], minlength=nb)[used] / counts[used]
    powers = np.column_stack([np.bincount(idx[ok], weights=u[ok] ** k, minlength=nb)[used] / counts[used]
                              for k in range(order + 1)])
    return ybar, powers, counts[used], m


def _wls(x: np.ndarray, y: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """Weighted least squares: coefficients, their unscaled covariance ``(XᵀWX)⁻¹`` and the weighted RSS."""
    sw = np.sqrt(w)
    q, r = np.linalg.qr(x * sw[:, None])
    beta = np.linalg.solve(r, q.T @ (y * sw))
    res = (y - x @ beta) * sw
    rinv = np.linalg.inv(r)
    return beta, rinv @ rinv.T, float(res @ res)


def temperature_fit(data: object, temperature: object, *, rate: float, unit: str | None = None,
                    max_order: int = 3) -> PrepResult:
    r"""Fit the bias against temperature and remove its temperature-dependent part.

    Parameters
    ----------
    data : array_like
        Rate samples (gyro, accelerometer); NaN marks a gap. Not modified.
    temperature : array_like
        The sensor's temperature at each sample (°C or K: only differences matter), as many
        values as ``data``; NaN where it is missing (those samples become gaps).
    rate : float
        Sample rate in Hz.
    unit : str, optional
        The data's unit (``"deg/s"``, ``"m/s^2"`` …), used to label the results: the tempco is
        in ``unit/K``. Convert with :func:`sigmatau.imu.units.convert`, e.g. to °/h/°C with
        ``convert(tc, unit, "deg/h")`` or mg/°C with ``convert(tc, unit, "mg")`` (a kelvin and a
        degree Celsius are the same step).
    max_order : int
        Highest polynomial order tried (0 … 6; default 3).

    Returns
    -------
    PrepResult
        ``data``: the compensated series ``y_i − Σ_{k≥1} c_k (T_i − T̄)^k`` (the bias at the mean
        temperature ``c_0`` stays; gaps where the data or the temperature are missing);
        ``estimates``: ``tempco`` (``dbias/dT`` at T̄, ``c_1``), ``bias_at_reference`` (``c_0``)
        and ``c1`` … ``cP`` of the order chosen, each ± standard error; ``details``: the order,
        the BIC of every order tried, the reference temperature T̄, the temperature range,
        the blocks; ``indices``: samples made gaps for a missing temperature.

    Raises
    ------
    ParameterError
        A bad rate or max_order.
    DataError
        Data or temperature not numeric, not 1-D, of different lengths, or all NaN; a
        temperature that does not vary; too few blocks with both data and temperature.

    Notes
    -----
    **Model** (IEEE Std 952-1997: the temperature-sensitive drift-rate term of its model
    equation, measured by its drift-rate temperature-sensitivity test):
    ``y_i = Σ_{k=0}^{P} c_k (T_i − T̄)^k + n_i`` with ``T̄`` the mean temperature of the valid
    samples. The record is cut into about 200 blocks of equal length, and the block means
    ``ȳ_b = Σ_k c_k ⟨(T − T̄)^k⟩_b`` are fitted by weighted least squares (weights: valid
    samples per block). Using the block means of the powers, not powers of the mean
    temperature, keeps the fit exact however much the temperature moves within a block;
    fitting block means rather than samples keeps the white noise from dominating the order
    selection (a million samples would make every tiny curvature "significant").

    **Order** by the Bayesian information criterion over K blocks,
    ``BIC_P = K·ln(RSS_P/K) + (P + 1)·ln K``, P = 0 … max_order: BIC is consistent (it finds
    the true order as the record grows) and penalises each extra term by ln K ≈ 5 rather than
    AIC's 2, which keeps the fit from bending to follow slow bias wander that happens to
    coincide with the temperature; a too-low order shows in the residual, a too-high one
    would hide noise. **Standard errors**: ``s²(XᵀWX)⁻¹``, ``s² = RSS/(K − P − 1)`` — exact
    when the block means scatter independently (white noise at the block length); with
    flicker or random-walk bias dominating at that length they are optimistic, and a single
    temperature ramp cannot tell a temperature effect from a drift in time (a cycle can).
    The tempco is ``dbias/dT`` at T̄, i.e. ``c_1``, even when a higher order is chosen; when
    BIC chooses order 0 the tempco of the order-1 fit is still reported (marked not
    significant in ``details``) and nothing is removed.

    References
    ----------
    IEEE Std 952-1997, *IEEE Standard Specification Format Guide and Test Procedure for
    Single-Axis Interferometric Fiber Optic Gyros*, Annex (model equation: the
    temperature-sensitive drift rate) and the drift-rate temperature-sensitivity test.
    G. Schwarz, "Estimating the dimension of a model", Ann. Statist. 6 (1978) 461–464 (BIC).

    Examples
    --------
    >>> import numpy as np
    >>> from sigmatau.prep import temperature_fit
    >>> temp = np.linspace(20.0, 40.0, 36000)
    >>> y = 0.002 * (temp - 30.0) + np.random.default_rng(1).normal(0.0, 0.05, temp.size)
    >>> r = temperature_fit(y, temp, rate=100.0, unit="deg/s")
    >>> r.details["order"], r.estimates["tempco"].unit
    (1, 'deg/s/K')
    >>> abs(r.estimates["tempco"].value - 0.002) < 3 * r.estimates["tempco"].stderr
    True
    """
    v = series(data)
    temp = series(temperature, "temperature")
    rate_f = rate_of(rate)
    order_max = _check_order(max_order)
    if unit is not None and not isinstance(unit, str):
        raise ParameterError(f"unit={unit!r} must be a unit name such as 'deg/s', or None")
    if temp.size != v.size:
        raise DataError(f"temperature has {temp.size} samples but data has {v.size}; they must match")
    ok = ~np.isnan(v) & ~np.isnan(temp)
    if not ok.any():
        raise DataError("no sample has both a value and a temperature")
    tv = temp[ok]
    if float(np.max(tv)) == float(np.min(tv)):
        raise DataError("the temperature does not vary: no temperature dependence can be fitted")
    made_gaps = np.flatnonzero(~np.isnan(v) & np.isnan(temp))
    if made_gaps.size:
        warnings.warn(f"temperature_fit: {made_gaps.size} sample(s) without a temperature become gaps",
                      PrepWarning, stacklevel=caller_stacklevel())
    t_ref = float(np.mean(tv))
    half = 0.5 * float(np.max(tv) - np.min(tv))
    u = (temp - t_ref) / half
    ybar, powers, w, m = _block_means(v, u, ok, order_max)
    # the fits run on the block means scaled by an exact power of two into [0.5, 1), so that no
    # square overflows or underflows at 1e±200; _result scales the coefficients back
    peak = float(np.max(np.abs(ybar))) if ybar.size else 0.0
    shift = math.frexp(peak)[1] if peak > 0 and math.isfinite(peak) else 0
    ybar = np.ldexp(ybar, -shift)
    k = ybar.size
    if k < _MIN_BLOCKS:
        raise DataError(f"temperature_fit: too few blocks with data and temperature ({k}; at least"
                        f" {_MIN_BLOCKS} are needed)")
    distinct = np.unique(np.round(powers[:, 1], 12)).size if order_max else 1
    top = min(order_max, k - 2, distinct - 1)
    fits = [_wls(powers[:, : p + 1], ybar, w) for p in range(top + 1)]
    with np.errstate(divide="ignore"):
        bic = [k * math.log(max(rss, 1e-300) / k) + (p + 1) * math.log(k) for p, (_, _, rss) in enumerate(fits)]
    order = int(np.argmin(bic))
    return _result(v, temp, ok, fits, order, bic, t_ref, half, unit, rate_f, order_max, made_gaps, k, m, shift)


def _result(v: np.ndarray, temp: np.ndarray, ok: np.ndarray, fits: list, order: int, bic: list[float],
            t_ref: float, half: float, unit: str | None, rate: float, order_max: int, made_gaps: np.ndarray,
            k: int, m: int, shift: int = 0) -> PrepResult:
    """Coefficients in powers of ``T − T̄``, the tempco, the compensated series and the record."""
    du = unit or "data"

    def coefficients(p: int) -> tuple[np.ndarray, np.ndarray]:
        """The coefficients in the data's unit and their standard errors (from the scaled fit)."""
        beta, cov_u, rss = fits[p]
        s2 = rss / max(k - p - 1, 1)
        scale = half ** -np.arange(p + 1)  # c_k = β_k / h^k
        se = np.sqrt(np.maximum(np.diag(s2 * cov_u), 0.0)) * np.abs(scale)
        return np.ldexp(beta * scale, shift), np.ldexp(se, shift)

    c, se = coefficients(order)
    estimates: dict[str, Estimate] = {}
    significant = order >= 1
    if significant:
        estimates["tempco"] = Estimate(float(c[1]), float(se[1]), f"{du}/K")
    elif len(fits) > 1:
        c1, se1 = coefficients(1)
        estimates["tempco"] = Estimate(float(c1[1]), float(se1[1]), f"{du}/K")
    estimates["bias_at_reference"] = Estimate(float(c[0]), float(se[0]), du)
    for j in range(1, order + 1):
        estimates[f"c{j}"] = Estimate(float(c[j]), float(se[j]), f"{du}/K^{j}" if j > 1 else f"{du}/K")
    dt = temp - t_ref
    correction = sum(c[j] * dt ** j for j in range(1, order + 1)) if order else np.zeros_like(v)
    out = np.where(ok, v - correction, np.nan)
    out.flags.writeable = False
    tc = estimates.get("tempco")
    notes = [f"bias versus temperature: order {order} chosen by BIC (of 0 … {len(fits) - 1}) on {k} block means"]
    if significant and tc is not None:
        notes.append(f"tempco {tc.value:.4g} ± {tc.stderr:.2g} {tc.unit} at {t_ref:.4g}°; the temperature-"
                     f"dependent bias is removed (the bias at {t_ref:.4g}° stays)")
    else:
        notes.append("no temperature dependence is significant (BIC chose order 0): nothing removed")
    if made_gaps.size:
        notes.append(f"{made_gaps.size} sample(s) without a temperature became gaps")
    details = {"order": order, "criterion": "BIC", "bic": bic, "significant": significant,
               "reference_temperature": t_ref,
               "temperature_range": [float(np.min(temp[ok])), float(np.max(temp[ok]))],
               "blocks": k, "block_samples": m, "gaps_from_temperature": int(made_gaps.size),
               "unit": unit, "coefficients_in": "powers of (T − reference_temperature)"}
    return PrepResult(step="temperature", data=out, data_type="freq",
                      parameters={"rate": rate, "unit": unit, "max_order": order_max},
                      estimates=estimates, indices=made_gaps.astype(np.int64), details=details,
                      notes=tuple(notes))
