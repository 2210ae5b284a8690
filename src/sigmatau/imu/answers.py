"""The design tip's gyroscope answers: the angle error after integration and the best averaging time.

:func:`angle_error` (ARW·√t, with the rate random walk's K²t³/3) and the
numerical steps behind :func:`~sigmatau.imu.optimal_averaging`: the minimum of a
model curve (``_model_minimum``), Monte-Carlo minima from the fit's covariance
(``_minimum_draws``), their quantiles (``_draw_intervals``) and the range where
the curve stays near its minimum (``_flat_range``). The public
``optimal_averaging`` takes a :class:`~sigmatau.imu.NoiseModel` and lives beside
it (:mod:`sigmatau.imu.noisemodel`), whose method calls it.
"""

from __future__ import annotations

import math
from typing import Any, Optional, Union

import numpy as np

from ..errors import DataError, ParameterError
from .results import Parameter
from .terms import B_FACTOR, _design
from .units import convert, term_unit

__all__ = ["angle_error"]


def angle_error(t: Union[float, np.ndarray], *, arw: Union[float, Parameter],
                rrw: Optional[Union[float, Parameter]] = None) -> Any:
    """RMS angle (or velocity) error after integrating a sensor at rest for ``t`` seconds.

    Parameters
    ----------
    t : float or array_like
        Integration time in seconds.
    arw : float or Parameter
        Angle random walk N (°/√s = °/s/√Hz, rad/√s …; for an accelerometer
        the velocity random walk).
    rrw : float or Parameter, optional
        Rate random walk K in the same angle unit per s^1.5; adds ``K²t³/3``.

    Returns
    -------
    float, numpy.ndarray or Parameter
        ``sqrt(N²t + K²t³/3)`` in the angle unit of ``arw``·√s (° for °/√s);
        a :class:`Parameter` (with interval) when ``arw`` is one.

    Notes
    -----
    Integrating white rate noise of density N gives an angle random walk of
    variance N²t (ST DT0064, "Gyroscope noise": final angle error RMS =
    ARW·√time). A rate random walk K integrates to an angle variance K²t³/3.

    Examples
    --------
    >>> from sigmatau.imu import angle_error
    >>> round(angle_error(1000.0, arw=1.0), 1)       # the tip's example: 1 °/√s over 1000 s
    31.6
    """
    tt = np.asarray(t, dtype=float)
    if np.any(tt < 0) or not np.all(np.isfinite(tt)):
        raise ParameterError("t must be non-negative and finite")
    if isinstance(arw, Parameter):
        k = rrw if isinstance(rrw, Parameter) else None
        if not arw.resolved:
            raise DataError("N is not resolved: no angle error can be given")
        unit = term_unit(_rate_unit_of(arw.unit), "Q")
        def comb(n: float, kk: float) -> float:
            return float(np.sqrt(n * n * tt + kk * kk * tt**3 / 3.0))
        if k is not None:
            kk = float(convert(k.value if k.resolved else k.high, k.unit, _k_unit_like(arw.unit)))
            klo = float(convert(k.low if k.resolved else 0.0, k.unit, _k_unit_like(arw.unit)))
            khi = float(convert(k.high, k.unit, _k_unit_like(arw.unit)))
        else:
            kk = klo = khi = 0.0
        note = "N·√t" + (" ⊕ K·√(t³/3)" if k is not None else "") + f" at t = {float(tt):g} s"
        return Parameter("angle error", comb(arw.value, kk), comb(arw.low, klo), comb(arw.high, khi),
                         unit, bool(k is None or k.resolved), "derived", arw.confidence, arw.kind, note=note)
    n = float(arw)
    kv = 0.0 if rrw is None else float(rrw)  # type: ignore[arg-type]
    out = np.sqrt(n * n * tt + kv * kv * tt**3 / 3.0)
    return float(out) if out.ndim == 0 else out


def _rate_unit_of(n_unit: str) -> str:
    """Rate unit of a density unit: ``u/sqrt(Hz)`` → ``u``."""
    if n_unit.endswith("/sqrt(Hz)"):
        return n_unit[: -len("/sqrt(Hz)")]
    return f"({n_unit})*sqrt(Hz)"


def _k_unit_like(n_unit: str) -> str:
    """Random-walk unit (``u/s/sqrt(Hz)``) matching the density unit ``n_unit``."""
    return f"({_rate_unit_of(n_unit)})/s/sqrt(Hz)"


def _model_minimum(c: np.ndarray, rate: float) -> tuple[float, float]:
    """τ and deviation at the minimum of the model AVAR with squared coefficients ``c``.

    Without a K or R term the curve keeps falling: ``(inf, B·0.6643)``. Otherwise
    the lowest of 400 log-spaced τ from 1/rate to 10¹² s brackets a bounded scalar
    minimisation in ln τ.
    """
    from scipy.optimize import minimize_scalar  # imported here: keeps `import sigmatau` light

    if c[3] <= 0 and c[4] <= 0:
        return math.inf, math.sqrt(max(c[2], 0.0)) * B_FACTOR

    def f(lt: float) -> float:
        return float(_design(np.array([math.exp(lt)]), rate)[0] @ c)
    lo, hi = math.log(1.0 / rate), math.log(1e12)
    grid = np.linspace(lo, hi, 400)
    vals = _design(np.exp(grid), rate) @ c
    i = int(np.argmin(vals))
    a, b = grid[max(i - 1, 0)], grid[min(i + 1, grid.size - 1)]
    res = minimize_scalar(f, bounds=(a, b), method="bounded", options={"xatol": 1e-6})
    return float(math.exp(res.x)), math.sqrt(max(float(res.fun), 0.0))


def _minimum_draws(coef: np.ndarray, cov: np.ndarray, rate: float, draws: int
                   ) -> tuple[list[float], list[float]]:
    """Minima (τ and deviation) of ``draws`` curves with coefficients redrawn from the fit's covariance.

    The draws come from a Gaussian with a fixed seed (reproducible answers),
    over every column of the fitted curve, including a negative (filter) 1/τ²
    term, which alone may stay negative; the others are clipped at zero.
    """
    gen = np.random.default_rng(12345)
    kept = [j for j in range(5) if coef[j] != 0.0]
    sub = cov[np.ix_(kept, kept)]
    samples = gen.multivariate_normal(coef[kept], sub, size=int(draws), method="eigh")
    floor = np.array([-np.inf if (j == 0 and coef[0] < 0) else 0.0 for j in kept])
    taus_mc, devs_mc = [], []
    for s in samples:
        c = np.zeros(5)
        c[kept] = np.maximum(s, floor)
        tm, dm = _model_minimum(c, rate)
        taus_mc.append(tm)
        devs_mc.append(dm)
    return taus_mc, devs_mc


def _draw_intervals(taus_mc: list[float], devs_mc: list[float], conf: float
                    ) -> tuple[float, float, float, float]:
    """Two-sided ``conf`` quantiles ``(t_lo, t_hi, d_lo, d_hi)`` of the drawn minima.

    The τ quantiles are order statistics (not interpolated), because a draw
    without a minimum has τ = inf, which sorts last and must come out as inf.
    """
    q = [(1.0 - conf) / 2.0, (1.0 + conf) / 2.0]
    t_lo, t_hi = (float(v) for v in np.sort(np.array(taus_mc))[
        np.clip((np.array(q) * (len(taus_mc) - 1)).round().astype(int), 0, len(taus_mc) - 1)])
    d_lo, d_hi = (float(v) for v in np.quantile(np.array(devs_mc), q))
    return t_lo, t_hi, d_lo, d_hi


def _flat_range(coef: np.ndarray, rate: float, tau: float, dev: float) -> tuple[float, float]:
    """τ range over which the model deviation stays within 5 % of its minimum ``dev`` at ``tau``."""
    grid = np.exp(np.linspace(math.log(1.0 / rate), math.log(tau * 1e4), 4000))
    within = np.sqrt(_design(grid, rate) @ coef) <= 1.05 * dev
    return float(grid[within][0]), float(grid[within][-1])
