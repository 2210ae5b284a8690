"""Stable32's non-linear frequency-drift models, fitted by least squares.

* log: ``y(t) = a·ln(b·t + 1) + c`` (b > 0), slope ``dy/dt = a·b/(b·t + 1)``;
* diffusion: ``y(t) = a + b·√(t + c)`` (c ≥ 0), slope ``dy/dt = b/(2√(t + c))``.

Both are linear in two parameters once the third (b, resp. c) is fixed, so the fit scans the
third on a logarithmic grid with the other two solved exactly (variable projection), then
polishes all three with :func:`scipy.optimize.least_squares`. Time runs from the first sample
and is scaled by the record length ``T`` inside the fit (``u = t/T``) so that the parameters
stay near 1 whatever the rate. Covariances are ``s²(JᵀJ)⁻¹`` at the optimum (white-noise
residuals, s² = RSS/(n − 3)); the slope's standard error follows by the delta method.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["NonlinearFit", "fit_log", "fit_diffusion"]

#: The scanned values of the non-linear parameter, in units of the record length.
_GRID = np.geomspace(1e-3, 1e4, 57)


@dataclass(frozen=True)
class NonlinearFit:
    """Parameters (a, b, c) in the user's time unit (seconds), their covariance, and the fit's status."""

    params: np.ndarray
    cov: np.ndarray
    model: np.ndarray
    slope_end: float
    slope_end_se: float
    rss: float
    at_bound: bool


def _two_linear(basis: np.ndarray, yv: np.ndarray) -> tuple[np.ndarray, float]:
    """Least squares of ``yv`` on ``[basis, 1]``: the two coefficients and the RSS."""
    a = np.column_stack([basis, np.ones_like(basis)])
    coef, *_ = np.linalg.lstsq(a, yv, rcond=None)
    r = yv - a @ coef
    return coef, float(r @ r)


def _cov(jac: np.ndarray, rss: float, n: int) -> np.ndarray:
    s2 = rss / max(n - 3, 1)
    try:
        return s2 * np.linalg.inv(jac.T @ jac)
    except np.linalg.LinAlgError:
        return np.full((3, 3), np.inf)


def _normalised(t: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, float, np.ndarray, np.ndarray, float, np.ndarray]:
    """The valid samples on a unit time span and at unit spread, as both curve fits start:
    ``(valid, span, u, y, scale, (y − ȳ)/scale)``, u = (t − t_first)/span over the valid samples."""
    valid = ~np.isnan(y)
    span = float(t[valid][-1] - t[valid][0]) or 1.0
    u = (t - t[valid][0]) / span
    uv, yv = u[valid], y[valid]
    scale = float(np.std(yv)) or 1.0
    return valid, span, uv, yv, scale, (yv - float(np.mean(yv))) / scale


def fit_log(t: np.ndarray, y: np.ndarray) -> NonlinearFit:
    """Fit ``y = a·ln(b·t + 1) + c`` to the valid samples (t ≥ 0 from the first sample)."""
    from scipy.optimize import least_squares  # loaded on first use: import sigmatau stays light
    valid, span, uv, yv, scale, ys = _normalised(t, y)

    best = min(((beta, *_two_linear(np.log1p(beta * uv), ys)) for beta in _GRID), key=lambda z: z[2])
    beta0, (a0, c0), _ = best

    def resid(p: np.ndarray) -> np.ndarray:
        return p[0] * np.log1p(np.exp(p[1]) * uv) + p[2] - ys

    sol = least_squares(resid, [a0, np.log(beta0), c0], method="lm")
    a_s, beta, c_s = sol.x[0], float(np.exp(sol.x[1])), sol.x[2]
    at_bound = not (_GRID[0] < beta < _GRID[-1])
    rss = float(sol.fun @ sol.fun) * scale ** 2
    # Jacobian in the user's parameters (a, b, c) with t in seconds: b = β/T.
    b = beta / span
    ts = (t[valid] - t[valid][0])
    a = a_s * scale
    c = c_s * scale + float(np.mean(yv))
    jac = np.column_stack([np.log1p(b * ts), a * ts / (b * ts + 1.0), np.ones_like(ts)])
    cov = _cov(jac, rss, yv.size)
    t_end = float(ts[-1])
    slope = a * b / (b * t_end + 1.0)
    grad = np.array([b / (b * t_end + 1.0), a / (b * t_end + 1.0) ** 2, 0.0])
    slope_se = float(np.sqrt(max(grad @ cov @ grad, 0.0))) if np.isfinite(cov).all() else np.inf
    with np.errstate(invalid="ignore", divide="ignore"):  # leading gaps: t < 0, residual NaN anyway
        model = a * np.log1p(b * (t - t[valid][0])) + c
    return NonlinearFit(np.array([a, b, c]), cov, model, slope, slope_se, rss, at_bound)


def fit_diffusion(t: np.ndarray, y: np.ndarray) -> NonlinearFit:
    """Fit ``y = a + b·√(t + c)`` (c ≥ 0) to the valid samples (t from the first sample)."""
    from scipy.optimize import least_squares  # loaded on first use: import sigmatau stays light
    valid, span, uv, yv, scale, ys = _normalised(t, y)

    grid = np.concatenate(([0.0], _GRID))
    best = min(((gam, *_two_linear(np.sqrt(uv + gam), ys)) for gam in grid), key=lambda z: z[2])
    gam0, (b0, a0), _ = best

    def resid(p: np.ndarray) -> np.ndarray:
        return p[0] + p[1] * np.sqrt(uv + p[2]) - ys

    sol = least_squares(resid, [a0, b0, gam0], bounds=([-np.inf, -np.inf, 0.0], [np.inf, np.inf, np.inf]))
    a_s, b_s, gam = sol.x
    at_bound = not (0.0 < gam < _GRID[-1])
    rss = float(sol.fun @ sol.fun) * scale ** 2
    # User parameters: y = a + b·√(t + c) with t in seconds: b = b_s·scale/√T, c = γ·T.
    a = a_s * scale + float(np.mean(yv))
    b = b_s * scale / np.sqrt(span)
    c = gam * span
    ts = t[valid] - t[valid][0]
    root = np.sqrt(ts + c)
    with np.errstate(divide="ignore"):
        jac = np.column_stack([np.ones_like(ts), root, b / (2.0 * root)])
    cov = _cov(jac, rss, yv.size) if np.isfinite(jac).all() else np.full((3, 3), np.inf)
    t_end = float(ts[-1])
    slope = b / (2.0 * np.sqrt(t_end + c))
    grad = np.array([0.0, 1.0 / (2.0 * np.sqrt(t_end + c)), -b / (4.0 * (t_end + c) ** 1.5)])
    slope_se = float(np.sqrt(max(grad @ cov @ grad, 0.0))) if np.isfinite(cov).all() else np.inf
    with np.errstate(invalid="ignore"):  # leading gaps: t < 0, residual NaN anyway
        model = a + b * np.sqrt(t - t[valid][0] + c)
    return NonlinearFit(np.array([a, b, c]), cov, model, float(slope), slope_se, rss, at_bound)
