"""Frequency drift: estimate it with Stable32's models and remove it.

The public :func:`drift` carries the defining equation, source and noise assumption of all
eight models in its docstring (what ``help()`` shows); the code of each model is a few lines.
"""

from __future__ import annotations

import warnings
from typing import Literal

import numpy as np

from ..errors import DataError, ParameterError, caller_stacklevel
from ._common import (count_valid, data_type_of, functional_variance, noise_level, noise_of, rate_of,
                      series)
from ._linear import block_fit, poly_fit, second_difference_mean
from ._nonlinear import fit_diffusion, fit_log
from ._result import Estimate, PrepResult, PrepWarning

__all__ = ["drift", "DRIFT_MODELS", "NOMINAL_NOISE"]

DriftModel = Literal["quadratic", "diff2", "3point", "greenhall", "linear", "bisection", "log", "diffusion"]

#: The models of each data type; the first is the default.
DRIFT_MODELS: dict[str, tuple[str, ...]] = {
    "phase": ("quadratic", "diff2", "3point", "greenhall"),
    "freq": ("linear", "bisection", "log", "diffusion"),
}

#: The noise each linear model's standard error assumes unless ``noise=`` says otherwise: the
#: noise for which SP1065 ("Drift analysis") calls the estimator optimal (Greenhall's: white FM here).
NOMINAL_NOISE: dict[str, str] = {
    "quadratic": "wpm", "diff2": "rwfm", "3point": "wfm", "greenhall": "wfm",
    "linear": "wfm", "bisection": "wfm",
}

#: Valid samples each model needs (its parameters plus at least one degree of freedom).
_MIN_VALID = {"quadratic": 4, "diff2": 4, "3point": 4, "greenhall": 10,
              "linear": 3, "bisection": 4, "log": 5, "diffusion": 5}

_DAY = 86400.0


def _check_model(model: object, data_type: str) -> str:
    allowed = DRIFT_MODELS[data_type]
    if model is None:
        return allowed[0]
    if model not in allowed:
        other = "freq" if data_type == "phase" else "phase"
        hint = f" ({model!r} is a {other} model)" if model in DRIFT_MODELS[other] else ""
        raise ParameterError(f"model={model!r} is not a drift model of {data_type} data{hint};"
                             f" use one of {allowed}")
    return str(model)


def drift(data: object, *, data_type: Literal["freq", "phase"], rate: float,
          model: DriftModel | None = None,
          noise: Literal["wpm", "wfm", "rwfm"] | None = None) -> PrepResult:
    r"""Estimate the linear frequency drift with one of Stable32's models and remove it.

    Parameters
    ----------
    data : array_like
        Phase (time error, s) or frequency samples; NaN marks a gap. Not modified.
    data_type : {"freq", "phase"}
        What ``data`` holds.
    rate : float
        Sample rate in Hz (τ0 = 1/rate); time is ``t_i = i·τ0`` from the first sample.
    model : str, optional
        Phase: ``"quadratic"`` (default), ``"diff2"``, ``"3point"``, ``"greenhall"``.
        Frequency: ``"linear"`` (default), ``"bisection"``, ``"log"``, ``"diffusion"``.
    noise : {"wpm", "wfm", "rwfm"}, optional
        The noise the standard errors of a linear model assume (white PM, white FM,
        random-walk FM); by default the noise the model is optimal for (:data:`NOMINAL_NOISE`).
        Its level is estimated from the data. The log and diffusion fits assume white FM.

    Returns
    -------
    PrepResult
        ``data``: the residual series; ``estimates["drift"]``: the drift D, the change of
        frequency per second (1/s for phase in seconds or fractional frequency; unit
        ``"data/s²"`` on phase, ``"data/s"`` on frequency) and ``["drift_per_day"]`` (per day),
        each ± its standard error; the model's parameters with standard errors; ``details``: the noise assumed,
        its level and the samples used.

    Raises
    ------
    ParameterError
        Unknown model or noise, a model of the other data type, a bad rate.
    DataError
        All NaN, or fewer valid samples than the model needs.

    Notes
    -----
    With ``t_i = i·τ0``, the phase is modelled as ``x(t) = a + b·t + (D/2)·t²`` and the frequency
    as ``y(t) = a + D·t`` (SP1065 §10.8, "Drift analysis"; Stable32 manual, Drift function):

    * ``quadratic`` — least squares ``x(t) = a + b·t + c·t²``, ``D = 2c``; optimal for white PM.
    * ``diff2`` — mean of the second differences, ``D = ⟨x_{i+2} − 2x_{i+1} + x_i⟩/τ0²``;
      optimal for random-walk FM.
    * ``3point`` — first (s), middle (m) and last (e) points, ``D = 4(x_e − 2x_m + x_s)/T²`` with
      T the span from s to e; here written as the exact second divided difference
      ``D = 2·x[t_s, t_m, t_e]``, which is that formula when m lies mid-way and stays exact
      when it cannot (an even number of points, gaps). Good for white and random-walk FM.
    * ``greenhall`` — Greenhall's four-point estimator from the phase sums
      ``w(n) = Σ_{i<n} x_i`` at n = 0, n1, N − n1, N with ``n1 = ⌊N/10⌋``, ``r = n1/N``:
      ``D = 6/(N³τ0² r(1 − r))·[w(N) − (w(N − n1) − w(n1))/(1 − 2r)]``. It is the contrast of the
      means of the outer tenths and of the middle of the record that cancels a and b exactly;
      with gaps, the same three block means solved exactly for D. (n1 = ⌊N/10⌋ is Stable32's
      choice as transcribed by allantoolkit.)
    * ``linear`` — least squares ``y(t) = a + b·t``, ``D = b``; optimal for white FM.
    * ``bisection`` — ``D = (ȳ₂ − ȳ₁)/(t̄₂ − t̄₁)``, the means of the two halves (the middle point
      of an odd count left out), i.e. SP1065's ``2(ȳ₂ − ȳ₁)/(Mτ0)``; good for white and
      random-walk FM.
    * ``log`` — ``y(t) = a·ln(b·t + 1) + c`` (MIL-PRF-55310 aging model), drift reported as the
      slope at the last sample, ``D = a·b/(b·t_end + 1)``.
    * ``diffusion`` — ``y(t) = a + b·√(t + c)``, ``D = b/(2√(t_end + c))`` at the last sample.

    Blocks and points lie on the span from the first to the last valid sample, so gaps at
    the ends only shorten the record.

    The linear models are weighted sums ``D = Σ c_i v_i``; their standard error is
    ``√(cᵀΣc)`` under the chosen noise, exact for that noise with its level estimated from
    differences of the data (see :mod:`sigmatau.prep._common`). Under another noise it is not
    calibrated: name the noise (e.g. from :func:`sigmatau.noiseid.identify`) with ``noise=``.

    The residual: for the fits (quadratic, linear, log, diffusion) the data minus the fitted
    curve; for the others the data minus the drift alone, ``(D/2)(t − t_c)²`` on phase or
    ``D(t − t_c)`` on frequency with ``t_c`` the middle of the record, which leaves the mean
    frequency unchanged. Gaps stay gaps.

    References
    ----------
    W. J. Riley, *Handbook of Frequency Stability Analysis*, NIST SP 1065 (2008), §10.8
    "Drift analysis" (phase and frequency drift methods and models).
    W. J. Riley, *Stable32 User Manual* (2008), Drift function; "Frequency drift
    characterization in Stable32", Hamilton Technical Services.
    C. A. Greenhall, "A frequency-drift estimator and its removal from modified Allan
    variance", Proc. IEEE Int. Frequency Control Symp. (1997), 428–432.

    Examples
    --------
    >>> import numpy as np
    >>> from sigmatau.prep import drift
    >>> t = np.arange(1000.0)
    >>> y = 1e-9 * t + np.random.default_rng(1).normal(0, 1e-8, t.size)
    >>> r = drift(y, data_type="freq", rate=1.0)
    >>> d = r.estimates["drift"]
    >>> print(f"{d.value:.4e} ± {d.stderr:.1e} per second")
    1.0003e-09 ± 1.1e-12 per second
    """
    v = series(data)
    data_type = data_type_of(data_type)
    tau0 = 1.0 / rate_of(rate)
    model = _check_model(model, data_type)
    if model in ("log", "diffusion"):
        if noise not in (None, "wfm"):
            raise ParameterError(f"noise={noise!r}: the {model} fit assumes white FM residuals; leave noise unset")
    elif noise is not None:
        noise = noise_of(noise)
    valid = count_valid(v)
    if valid < _MIN_VALID[model]:
        raise DataError(f"drift model {model!r} needs at least {_MIN_VALID[model]} valid samples,"
                        f" got {valid}")
    t = np.arange(v.size) * tau0
    if model in ("log", "diffusion"):
        return _nonlinear(v, t, model, data_type, rate)
    noise = noise or NOMINAL_NOISE[model]
    level, n_level = noise_level(v, data_type, noise, tau0)

    def se(c: np.ndarray) -> float:
        return float(np.sqrt(functional_variance(c, data_type, noise, level, tau0)))

    params: dict[str, Estimate] = {}
    details: dict[str, object] = {}
    if model in ("quadratic", "linear"):
        deg = 2 if model == "quadratic" else 1
        alpha, w = poly_fit(v, t, deg)
        names = ("a", "b", "c")[: deg + 1]
        units = ("data", "data/s", "data/s²") if deg == 2 else ("data", "data/s")
        for k in range(deg + 1):
            params[names[k]] = Estimate(float(alpha[k]), se(w[k]), units[k])
        factor = 2.0 if deg == 2 else 1.0
        d_value, d_weights = factor * float(alpha[deg]), factor * w[deg]
        fitted = sum(alpha[k] * t ** k for k in range(deg + 1))
        residual = v - fitted
    else:
        d_value, d_weights, extra = _point_estimator(v, t, model, tau0)
        details.update(extra)
        residual = _remove_drift(v, t, d_value, data_type)
    d_se = se(d_weights)
    unit, per_day = ("data/s", "data/day") if data_type == "freq" else ("data/s²", "data/s/day")
    estimates = {"drift": Estimate(d_value, d_se, unit),
                 "drift_per_day": Estimate(d_value * _DAY, d_se * _DAY, per_day),
                 **params}
    details.update({"noise": noise, "noise_level": level, "noise_terms": n_level, "valid": valid})
    return _result(residual, data_type, model, rate, estimates, details,
                   f"drift {d_value:.6g} ± {d_se:.2g} {unit} removed ({model} model; standard error"
                   f" for {noise.upper()} noise)")


def _point_estimator(v: np.ndarray, t: np.ndarray, model: str, tau0: float
                     ) -> tuple[float, np.ndarray, dict[str, object]]:
    """diff2, 3point, greenhall (phase) and bisection (frequency): D and its weights.

    Blocks and points are placed on the span from the first to the last valid sample.
    """
    idx = np.flatnonzero(~np.isnan(v))
    s, e = int(idx[0]), int(idx[-1])
    n = e - s + 1
    if model == "diff2":
        mean, w, count = second_difference_mean(v)
        return mean / tau0 ** 2, w / tau0 ** 2, {"terms": count}
    if model == "bisection":
        half = n // 2
        halves = [np.arange(s, s + half), np.arange(e + 1 - half, e + 1)]
        lead, w = block_fit(v, t, halves, 1, "drift model 'bisection'")
        return lead, w, {"halves": [[s, s + half], [e + 1 - half, e + 1]]}
    if model == "3point":
        m = int(idx[np.argmin(np.abs(idx - 0.5 * (s + e)))])
        if m in (s, e):
            raise DataError("drift model '3point' needs a valid sample between the first and the last")
        lead, w = block_fit(v, t, [np.array([s]), np.array([m]), np.array([e])], 2)
        return 2.0 * lead, 2.0 * w, {"points": [s, m, e]}
    n1 = max(1, n // 10)
    blocks = [np.arange(s, s + n1), np.arange(s + n1, e + 1 - n1), np.arange(e + 1 - n1, e + 1)]
    lead, w = block_fit(v, t, blocks, 2, "drift model 'greenhall'")
    return 2.0 * lead, 2.0 * w, {"n1": n1, "blocks": [[int(b[0]), int(b[-1]) + 1] for b in blocks]}


def _remove_drift(v: np.ndarray, t: np.ndarray, d: float, data_type: str) -> np.ndarray:
    valid = np.flatnonzero(~np.isnan(v))
    tc = 0.5 * (t[valid[0]] + t[valid[-1]])
    return v - (0.5 * d * (t - tc) ** 2 if data_type == "phase" else d * (t - tc))


def _nonlinear(v: np.ndarray, t: np.ndarray, model: str, data_type: str, rate: float) -> PrepResult:
    fit = fit_log(t, v) if model == "log" else fit_diffusion(t, v)
    cov = fit.cov
    units = ("data", "1/s", "data") if model == "log" else ("data", "data/√s", "s")
    params = {name: Estimate(float(fit.params[k]), float(np.sqrt(cov[k, k])) if np.isfinite(cov[k, k])
                             and cov[k, k] >= 0 else float("inf"), units[k])
              for k, name in enumerate(("a", "b", "c"))}
    if fit.at_bound or not np.isfinite(fit.slope_end_se):
        warnings.warn(f"the {model} model is poorly determined by these data (its curvature parameter"
                      " reached a bound): its uncertainties are not reliable; try model='linear'",
                      PrepWarning, stacklevel=caller_stacklevel())
    estimates = {"drift": Estimate(fit.slope_end, fit.slope_end_se, "data/s"),
                 "drift_per_day": Estimate(fit.slope_end * _DAY, fit.slope_end_se * _DAY, "data/day"),
                 **params}
    details = {"noise": "wfm", "rss": fit.rss, "valid": count_valid(v), "at_bound": fit.at_bound,
               "drift_at": "last sample"}
    residual = v - fit.model
    return _result(residual, data_type, model, rate, estimates, details,
                   f"{model} model fitted and removed; drift {fit.slope_end:.6g} ± {fit.slope_end_se:.2g}"
                   " data/s at the last sample")


def _result(residual: np.ndarray, data_type: str, model: str, rate: float,
            estimates: dict[str, Estimate], details: dict[str, object], note: str) -> PrepResult:
    residual = np.asarray(residual, dtype=np.float64)
    residual.flags.writeable = False
    return PrepResult(step="drift", data=residual, data_type=data_type,
                      parameters={"model": model, "rate": rate}, estimates=estimates,
                      details=details, notes=(note,))
