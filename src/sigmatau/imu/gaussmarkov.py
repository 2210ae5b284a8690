"""A first-order Gauss–Markov (exponentially correlated) term in the IMU noise model.

:func:`gauss_markov_avar` is the Allan variance of the process. The rest serves
:func:`sigmatau.imu.analyze` (``gauss_markov="auto"|"never"|"always"``): the
profile of the fit's χ² over the correlation time T (``_profile``), the choice
between the five-term model and five terms + GM by the Bayesian information
criterion (``_choose``), and the two parameters with their intervals
(``_gm_result``): σ_GM from the fit's covariance at the chosen T, T_c from the
profile of the χ². The fit itself (weights, correlation across τ, discrepancy
floor, term selection, the unconstrained fit behind the intervals) is that of
:mod:`sigmatau.imu.fitting`, with the GM variance σ² as a sixth linear column.

Why BIC and not AIC: the GM term adds two parameters (σ², T) to a model that
already fits a curve of 15–25 correlated points; AIC's fixed penalty of 2 per
parameter keeps a spurious term at a fixed rate however long the record, and
the profile over T (a parameter that does not exist under the five-term model)
makes the null distribution of the χ² gain heavier than χ²₂. BIC's penalty
``ln n_eff`` per parameter grows with the information in the curve, and the
term is kept only when it wins by a margin (:data:`BIC_MARGIN`, "very strong"
on the scale of Kass & Raftery 1995), so that a record without GM gets one
rarely (the false-alarm rate is measured in ``tests/test_imu_gauss_markov.py``
and ``docs/gauss-markov.md``).
"""

from __future__ import annotations

import math
from typing import Literal, NamedTuple, Optional, Sequence, Union

import numpy as np
from scipy.special import ndtri

from ..errors import ParameterError
from ..uncertainty.powerfit import irls_fit
from .fitting import _chi2_expectation, _columns, _correlation, _dominant, _Fit, _normal_inverse
from .results import GaussMarkov, Parameter
from .terms import _gm_column
from .units import TERMS, SensorUnit

__all__ = ["gauss_markov_avar", "BIC_MARGIN", "GM_MODES"]

#: ΔBIC (five-term minus five-term + GM) above which the GM term is kept with ``"auto"``.
BIC_MARGIN = 10.0

#: The values of ``analyze(..., gauss_markov=)``.
GM_MODES = ("auto", "never", "always")

#: Points per decade of the grid of correlation times profiled before refining.
_GRID_PER_DECADE = 20


def gauss_markov_avar(taus: Union[float, Sequence[float], np.ndarray], *, sigma: float, tau_c: float,
                      rate: float = math.inf) -> np.ndarray:
    """Allan variance of a first-order Gauss–Markov process.

    Parameters
    ----------
    taus : float or array_like
        Averaging times (s), positive.
    sigma : float
        Stationary standard deviation σ of the process (the unit of the samples).
    tau_c : float
        Correlation time T (s): autocorrelation ``σ²·e^(−|t|/T)``.
    rate : float
        Sample rate (Hz). With a finite rate the variance is that of the sampled
        process (an AR(1) of coefficient ``φ = e^(−τ0/T)``, as
        :func:`sigmatau.imu.simulate` generates it) and differs from the
        continuous form at the shortest τ when T is within a few τ0.

    Returns
    -------
    numpy.ndarray
        σ²_A(τ) at each τ.

    Notes
    -----
    For the continuous process (IEEE Std 952-1997, Annex C, "correlated noise",
    written there as ``(q_c T)²/τ·[…]`` with the driving-noise amplitude
    ``q_c² = 2σ²/T``; El-Sheimy, Hou & Niu 2008, the same form):

    ``σ²_A(τ) = (2σ²T/τ)·[1 − (T/2τ)·(3 − 4e^(−τ/T) + e^(−2τ/T))]``

    which is white noise ``N² = 2σ²T`` for τ ≫ T and a rate random walk
    ``K² = 2σ²/T`` (σ² = K²τ/3) for τ ≪ T; the ADEV peaks at τ ≈ 1.89 T at
    ≈ 0.62 σ. It follows from the structure function of the integrated process,
    ``D(τ) = 2σ²T²(τ/T − 1 + e^(−τ/T))``, as ``σ²_A = (4D(τ) − D(2τ))/(2τ²)``;
    the sampled process has ``D(m) = τ0²σ²[m + 2φ(m(1 − φ) − (1 − φ^m))/(1 − φ)²]``.
    Checked against a Monte Carlo of ``simulate(gauss_markov=...)`` (40 records
    of 1 h at 100 Hz, T = 1 s: within 2.5 % up to τ = 80 s, within the scatter
    of the few averages beyond).

    References
    ----------
    IEEE Std 952-1997, Annex C; N. El-Sheimy, H. Hou, X. Niu, "Analysis and
    modeling of inertial sensors using Allan variance", IEEE Trans. Instrum.
    Meas. 57(1) (2008) 140–149.

    Examples
    --------
    >>> from sigmatau.imu.gaussmarkov import gauss_markov_avar
    >>> v = gauss_markov_avar([0.01, 1000.0], sigma=1.0, tau_c=1.0)
    >>> [round(float(x), 6) for x in v]         # ≈ 2τ/3T and ≈ 2T/τ
    [0.006617, 0.001997]
    """
    t = np.atleast_1d(np.asarray(taus, dtype=float))
    if t.size == 0 or np.any(~np.isfinite(t)) or np.any(t <= 0):
        raise ParameterError("taus must be positive and finite")
    s, tc, r = float(sigma), float(tau_c), float(rate)
    if not (math.isfinite(s) and s >= 0):
        raise ParameterError(f"sigma={sigma!r} must be a non-negative finite number")
    if not (math.isfinite(tc) and tc > 0):
        raise ParameterError(f"tau_c={tau_c!r} must be a positive finite number (s)")
    if not r > 0:
        raise ParameterError(f"rate={rate!r} must be positive (inf for the continuous process)")
    return s * s * _gm_column(t, r, tc)


class _Choice(NamedTuple):
    """What the profile and the criterion decided."""

    tau: float           # correlation time of the profile's minimum (NaN: no GM could be fitted)
    chosen: bool         # the GM term enters the model
    delta_bic: float     # BIC(five terms) − BIC(five terms + GM); > 0 favours GM
    n_eff: float         # effective number of points behind the BIC penalty
    reason: str          # why it was (not) chosen


def _chi2_with(taus: np.ndarray, var: np.ndarray, nu: np.ndarray, rate: float, cols: list[int],
               tau_c: float, eps: float) -> tuple[float, float]:
    """χ² of the weighted fit of ``cols`` plus the GM column of correlation time ``tau_c``, and its σ²."""
    design = _columns(taus, rate, tau_c)
    sub = design.mat[:, cols + [5]]
    rel = np.sqrt(2.0 / nu + eps**2)
    signed = np.array([c == 0 for c in cols] + [False])
    h, _, chi2 = irls_fit(sub, var, rel, signed=signed)
    return chi2, float(h[-1])


def _profile(taus: np.ndarray, var: np.ndarray, nu: np.ndarray, rate: float, cols: list[int], eps: float
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """χ² and σ² of the fit with a GM term on a log grid of T spanning the τ of the curve."""
    decades = math.log10(taus[-1] / taus[0])
    grid = np.geomspace(taus[0], taus[-1], max(int(round(decades * _GRID_PER_DECADE)) + 1, 5))
    out = np.array([_chi2_with(taus, var, nu, rate, cols, float(t), eps) for t in grid])
    return grid, out[:, 0], out[:, 1]


def _refine(taus: np.ndarray, var: np.ndarray, nu: np.ndarray, rate: float, cols: list[int], eps: float,
            grid: np.ndarray, chi2: np.ndarray) -> tuple[float, float]:
    """The profile's minimum refined between the grid neighbours of its lowest point: (T, χ²)."""
    from scipy.optimize import minimize_scalar  # imported here: keeps `import sigmatau` light

    k = int(np.argmin(chi2))
    lo, hi = math.log(grid[max(k - 1, 0)]), math.log(grid[min(k + 1, grid.size - 1)])
    res = minimize_scalar(lambda lt: _chi2_with(taus, var, nu, rate, cols, math.exp(lt), eps)[0],
                          bounds=(lo, hi), method="bounded", options={"xatol": 1e-3})
    if res.fun < chi2[k]:
        return float(math.exp(res.x)), float(res.fun)
    return float(grid[k]), float(chi2[k])


def _choose(taus: np.ndarray, var: np.ndarray, nu: np.ndarray, rate: float, terms: Sequence[str],
            mode: Literal["auto", "always"]) -> _Choice:
    """Profile the GM term over T and weigh five terms + GM against five terms by BIC.

    Both fits use every term asked for (non-negative, the 1/τ² one signed) and no
    discrepancy floor: the floor is what a missing term would hide. The fit's χ²
    is a quadratic form of residuals correlated across τ; scaled by ``ν/E[χ²]``
    (the five-term fit's Satterthwaite EDF ν and mean, as in the discrepancy
    test) it is a χ² with ν degrees of freedom, and ``n_eff = ν + p`` (p the
    five-term model's columns) is the effective number of points:
    ``BIC = χ²·ν/E[χ²] + k·ln n_eff``. The GM term costs two parameters.
    """
    cols = [TERMS.index(t) for t in terms]
    if taus.size - len(cols) - 2 < 2 or taus[-1] / taus[0] < 8.0:
        return _Choice(math.nan, False, math.nan, math.nan, "too few τ for a Gauss–Markov term")
    design5 = _columns(taus, rate)
    chi2_5, mean_5, sd_5 = _chi2_expectation(design5, var, nu, taus, cols, 0.0)
    nu_5 = 2.0 * mean_5**2 / sd_5**2 if sd_5 > 0 else float(taus.size - len(cols))
    scale = nu_5 / mean_5 if mean_5 > 0 else 1.0
    n_eff = nu_5 + len(cols)
    grid, chi2, _ = _profile(taus, var, nu, rate, cols, 0.0)
    tau, chi2_6 = _refine(taus, var, nu, rate, cols, 0.0, grid, chi2)
    _, s2 = _chi2_with(taus, var, nu, rate, cols, tau, 0.0)
    delta = (chi2_5 - chi2_6) * scale - 2.0 * math.log(n_eff)
    edge = tau <= grid[1] or tau >= grid[-2]
    if not s2 > 0:
        return _Choice(tau, False, delta, n_eff, "the fit puts no variance in a Gauss–Markov term")
    if mode == "always":
        return _Choice(tau, True, delta, n_eff, "gauss_markov='always'")
    if edge:
        return _Choice(tau, False, delta, n_eff, (
            f"the best correlation time ({tau:.3g} s) is at the edge of the τ range: there a GM term is"
            " indistinguishable from white noise or a random walk"))
    if delta <= BIC_MARGIN:
        return _Choice(tau, False, delta, n_eff, f"ΔBIC = {delta:.3g} ≤ {BIC_MARGIN:g}: not supported")
    return _Choice(tau, True, delta, n_eff, f"ΔBIC = {delta:.3g} > {BIC_MARGIN:g}")


def _tau_interval(taus: np.ndarray, var: np.ndarray, nu: np.ndarray, rate: float, fit: _Fit, conf: float
                  ) -> tuple[float, float, float]:
    """Interval of T from the profile of the chosen model's χ²: ``Δχ² ≤ r·χ²₁(conf)``.

    The χ² is that of the kept terms with the fit's discrepancy floor. Its curvature
    gives the variance of ln T that independent points would have (the "bread" of the
    linearised fit, ln T's derivative column added); the variance estimates are
    correlated across τ, so the threshold is scaled by ``r``, the ratio of the sandwich
    variance of ln T (the correlation model of :func:`sigmatau.imu.fitting._correlation`)
    to that bread variance: the profile interval then has the width the sandwich gives
    to the other terms. Returns ``(low, high, r)``; an end where the profile does not
    rise enough within the τ range (widened 4×) is 0 or inf.
    """
    from scipy.optimize import brentq  # imported here: keeps `import sigmatau` light
    from scipy.stats import chi2 as chi2_dist

    cols = [TERMS.index(t) for t in fit.kept if t != "GM"]
    best = _chi2_with(taus, var, nu, rate, cols, fit.gm_tau, fit.eps)[0]
    r = _sandwich_ratio(taus, var, nu, rate, cols, fit.gm_tau, fit.eps)
    q = float(chi2_dist.ppf(conf, 1)) * r

    def excess(lt: float) -> float:
        return _chi2_with(taus, var, nu, rate, cols, math.exp(lt), fit.eps)[0] - best - q

    lt0 = math.log(fit.gm_tau)
    ends = []
    for far in (math.log(taus[0] / 4.0), math.log(taus[-1] * 4.0)):
        prev, found = lt0, None
        for lt in np.linspace(lt0, far, 41)[1:]:
            if excess(lt) > 0:
                found = brentq(excess, min(prev, lt), max(prev, lt), xtol=1e-4)
                break
            prev = lt
        ends.append(math.exp(found) if found is not None else (0.0 if far < lt0 else math.inf))
    return ends[0], ends[1], r


def _sandwich_ratio(taus: np.ndarray, var: np.ndarray, nu: np.ndarray, rate: float, cols: list[int],
                    tau_c: float, eps: float) -> float:
    """Sandwich over bread variance of ln T in the fit linearised at ``tau_c`` (see :func:`_tau_interval`)."""
    design = _columns(taus, rate, tau_c)
    sub = design.mat[:, cols + [5]]
    stat = np.sqrt(2.0 / nu)
    rel = np.sqrt(stat**2 + eps**2)
    signed = np.array([c == 0 for c in cols] + [False])
    h, sigma, _ = irls_fit(sub, var, rel, signed=signed)
    step = 1e-4
    deriv = h[-1] * (_gm_column(taus, rate, tau_c * math.exp(step))
                     - _gm_column(taus, rate, tau_c * math.exp(-step))) / (2.0 * step)
    aw = np.column_stack([sub, deriv]) / sigma[:, None]
    bread = _normal_inverse(aw)
    dominant = _dominant(design, cols + [5], sub * np.abs(h))
    corr = (np.outer(stat, stat) * _correlation(taus, dominant) + np.diag(np.full(taus.size, eps**2)))
    corr /= np.outer(rel, rel)
    sandwich = bread @ (aw.T @ corr @ aw) @ bread
    b = float(bread[-1, -1])
    return float(sandwich[-1, -1]) / b if b > 0 else 1.0


def _gm_result(taus: np.ndarray, var: np.ndarray, nu: np.ndarray, rate: float, fit: _Fit, choice: _Choice,
               conf: float, su: SensorUnit, mode: str) -> Optional[GaussMarkov]:
    """The GM term of the chosen model: σ_GM (interval from the unconstrained fit's covariance
    at the chosen T, as for the other terms) and T_c (interval from the χ² profile)."""
    if not math.isfinite(fit.gm_tau):
        return None
    z = ndtri(0.5 + conf / 2.0)
    unit = su.name
    kept = "GM" in fit.kept
    cf, sf = float(fit.full_coef[5]), math.sqrt(max(float(fit.full_cov[5, 5]), 0.0))
    t_lo, t_hi, r_t = _tau_interval(taus, var, nu, rate, fit, conf) if kept else (0.0, math.inf, 1.0)
    how = (f"chosen against the five-term model by BIC on the fit's χ² with n_eff = {choice.n_eff:.3g}"
           f" effective points: ΔBIC = {choice.delta_bic:.3g} (kept when > {BIC_MARGIN:g})")
    if mode == "always":
        how = f"gauss_markov='always' (ΔBIC = {choice.delta_bic:.3g})"
    if kept:
        c = float(fit.coef[5])
        value = math.sqrt(c)
        lo, hi = math.sqrt(max(cf - z * sf, 0.0)), math.sqrt(max(cf + z * sf, 0.0))
        sigma = Parameter("GM σ", value, min(lo, value), max(hi, value), unit, True, "fit", conf, su.kind,
                          note=(f"stationary σ of the Gauss–Markov term; interval ĉ ± {z:.3g}σ_c on c = σ² from"
                                f" the unconstrained fit of every term at T_c = {fit.gm_tau:.4g} s"
                                f" (ĉ = {cf:.4g}, σ_c = {sf:.3g}); {how}"))
        tau_c = Parameter("GM T_c", fit.gm_tau, min(t_lo, fit.gm_tau), max(t_hi, fit.gm_tau), "s", True, "fit",
                          conf, su.kind, note=(f"correlation time; interval where the profile of the fit's χ²"
                                               f" over T_c rises by less than {r_t:.3g}× the χ²₁ quantile (the"
                                               " sandwich-to-bread variance ratio of ln T_c: points correlated"
                                               " across τ)"))
    else:
        c, sc = fit.upper.get("GM", (0.0, math.inf))
        bound = max(math.sqrt(max(cf, 0.0) + z * sf), math.sqrt(c + z * sc) if math.isfinite(sc) else math.inf)
        sigma = Parameter("GM σ", math.nan, 0.0, bound, unit, False, "fit", conf, su.kind,
                          note=f"dropped by term selection at T_c = {fit.gm_tau:.4g} s; upper bound; {how}")
        tau_c = Parameter("GM T_c", math.nan, 0.0, math.inf, "s", False, "fit", conf, su.kind,
                          note="not resolved: the GM term was dropped by term selection")
    return GaussMarkov(sigma=sigma, tau_c=tau_c, delta_bic=choice.delta_bic, n_eff=choice.n_eff,
                       criterion="BIC", margin=BIC_MARGIN, note=how)
