"""The weighted fit of the five-term model to the AVAR curve, its term selection and intervals.

How the fit works is described in :func:`sigmatau.imu.analyze` (*Fit*, *Intervals*):
a weighted non-negative least-squares fit (``irls_fit``, shared with ``fit_power_law``) with the sandwich
covariance of variance estimates correlated across τ (``_correlation``), a
model-discrepancy floor when the χ² says the curve departs from the model
(``_discrepancy``), backward term selection (``_select_terms``), upper bounds
of the dropped terms (``_dropped_bounds``) and the unconstrained fit of every
term behind the intervals (``_fit_free``, ``_fit_parameters``).
"""

from __future__ import annotations

import math
from typing import NamedTuple, Sequence

import numpy as np
from scipy.special import chdtrc, ndtri

from ..errors import DataError
from ..uncertainty.noiseid import OCTAVE_CORRELATION
from ..uncertainty.powerfit import irls_fit
from .results import Parameter
from .terms import _ALPHA, _design, _gm_alpha, _gm_column
from .units import TERMS, SensorUnit

__all__: list[str] = []


#: Exponent of the decay of the correlation with the distance in octaves (see _correlation).
_CORR_POWER = 1.5


def _correlation(taus: np.ndarray, alpha: np.ndarray) -> np.ndarray:
    """Correlation matrix of the variance estimates at ``taus`` (noise type α at each τ).

    The one-octave correlations are those of :func:`sigmatau.noiseid.fit_power_law`
    (0.5 white, 0.7 flicker, 0.88 random walk). Farther apart the correlation
    falls faster than an AR(1) in log₂τ would have it: Monte Carlo of
    octave-spaced OADEV (2¹⁶ points, 300 runs) gives at 2, 3 and 4 octaves
    0.19/0.08/0.05 (white), 0.30/0.13/0.05 (flicker) and 0.65/0.48/0.33
    (random walk), which ``ρ₁^(Δ^1.5)`` reproduces (0.14/0.03/0.00,
    0.36/0.16/0.06, 0.70/0.51/0.36) where the AR(1) ``ρ₁^Δ`` does not
    (0.25/0.13/0.06, 0.49/0.34/0.24, 0.77/0.68/0.60). With heterogeneous noise
    the distance is accumulated in a warped coordinate
    ``L = Σ a^(1/1.5)·Δlog₂τ`` (``a = −ln ρ₁`` of the noise at each step), and
    ``ρ_ij = exp(−|L_i − L_j|^1.5)``: a stationary positive-definite kernel
    in L, so the matrix is a valid correlation matrix.
    """
    rho = np.array([OCTAVE_CORRELATION[max(-2, min(0, int(a)))] for a in alpha])
    step = np.maximum(rho[:-1], rho[1:])
    rate = (-np.log(step)) ** (1.0 / _CORR_POWER)
    coord = np.concatenate(([0.0], np.cumsum(rate * np.diff(np.log2(taus)))))
    return np.exp(-np.abs(coord[:, None] - coord[None, :]) ** _CORR_POWER)


class _Cols(NamedTuple):
    """The AVAR columns of the fit at the τ of the curve: Q², N², B², K², R², and the variance σ²
    of a Gauss–Markov term of correlation time ``gm_tau`` as a sixth column when there is one."""

    mat: np.ndarray        # n × k columns
    alpha: np.ndarray      # n × k power-law α each column looks like at each τ (EDF, τ correlation)
    names: tuple           # TERMS, then "GM"
    gm_tau: float          # correlation time of the GM column (NaN without one)


def _columns(taus: np.ndarray, rate: float, gm_tau: float = math.nan) -> _Cols:
    """:class:`_Cols` of the five terms, plus the GM column when ``gm_tau`` is finite."""
    mat = _design(taus, rate)
    alpha = np.tile(np.array([_ALPHA[t] for t in TERMS]), (taus.size, 1))
    if not math.isfinite(gm_tau):
        return _Cols(mat, alpha, TERMS, math.nan)
    mat = np.column_stack([mat, _gm_column(taus, rate, gm_tau)])
    alpha = np.column_stack([alpha, _gm_alpha(taus, rate, gm_tau)])
    return _Cols(mat, alpha, TERMS + ("GM",), float(gm_tau))


def _dominant(design: _Cols, cols: list[int], sub_terms: np.ndarray) -> np.ndarray:
    """α at each τ of the column (among ``cols``) that holds most of the fitted AVAR there."""
    idx = np.asarray(cols)[np.argmax(sub_terms, axis=1)]
    return design.alpha[np.arange(sub_terms.shape[0]), idx]


class _Fit(NamedTuple):
    coef: np.ndarray       # squared coefficients, all five (0 where dropped; Q may be < 0: filter), GM's σ² 6th
    cov: np.ndarray        # their covariance (5×5 or 6×6, zero rows for dropped terms)
    kept: tuple[str, ...]  # terms kept with a positive, significant coefficient
    chi2: float
    dof: int
    upper: dict            # term not kept -> (c, σ_c) of a refit with it forced in
    dominant: np.ndarray   # α of the dominant term at each τ
    eps: float             # relative model-discrepancy floor per τ (0 when the model fits)
    filter_time: float     # τ_f of a significant negative 1/τ² term (s), else 0
    raw_chi2_dof: float    # χ²/dof of the full fit before any discrepancy floor
    needed: tuple          # kept below min_significance because the curve needs them
    full_coef: np.ndarray  # squared coefficients of the unconstrained fit of every term (5, 0 if excluded; +GM)
    full_cov: np.ndarray   # their covariance (5×5, or 6×6 with GM)
    full_gain: np.ndarray  # 5×n (6×n) linear map from the AVAR points to full_coef (0 rows if excluded)
    var_cov: np.ndarray    # n×n modelled covariance of the AVAR points (statistical part)
    gm_tau: float = math.nan  # correlation time of the GM column of this fit (NaN: five-term model)


#: Tail probability of the fit's χ² (scaled-χ² approximation given the
#: correlation of the variance estimates across τ) below which the curve is
#: taken not to follow the model and a model-discrepancy floor is estimated.
#: 10⁻⁴: no trigger in 2 × 50 clean 3 h simulations, while real curves reach 10⁻¹⁰⁰.
_EPS_TRIGGER = 1e-4


def _chi2_tail(chi2: float, mean: float, sd: float) -> float:
    """P(χ² ≥ chi2) for a quadratic form of mean ``mean`` and sd ``sd`` (Satterthwaite)."""
    if not (mean > 0 and sd > 0):
        return 1.0
    nu = 2.0 * mean**2 / sd**2
    return float(chdtrc(nu, chi2 * nu / mean))


def _normal_inverse(aw: np.ndarray) -> np.ndarray:
    """``pinv(awᵀ·aw)`` with the columns equilibrated first.

    The columns (3/τ², 1/τ, 1, τ/3, τ²/2) differ by many orders of magnitude when τ is far
    from 1 s (a 1e5 Hz record: τ from 1e-5 s), and pinv's relative cut-off then drops the small
    singular values: bounds of unresolved terms came out 19–54 % off at 1e5 Hz. Scaling each
    column to unit norm makes the inverse independent of the rate's units:
    ``(A D)⁺ … = D⁻¹ (AᵀA)⁻¹ D⁻¹`` for the diagonal D.
    """
    norm = np.linalg.norm(aw, axis=0)
    norm[~(norm > 0)] = 1.0
    scaled = aw / norm
    return np.linalg.pinv(scaled.T @ scaled) / np.outer(norm, norm)


def _fit_once(design: _Cols, var: np.ndarray, nu: np.ndarray, taus: np.ndarray, cols: list[int],
              eps: float):
    sub = design.mat[:, cols]
    stat = np.sqrt(2.0 / nu)
    rel = np.sqrt(stat**2 + eps**2)
    signed = np.array([c == 0 for c in cols])
    h, sigma, chi2 = irls_fit(sub, var, rel, signed=signed)
    aw = sub / sigma[:, None]
    bread = _normal_inverse(aw)
    dominant = _dominant(design, cols, sub * np.abs(h))
    # Whitened residual correlation: the statistical part is correlated across τ,
    # the discrepancy floor is not.
    corr = (np.outer(stat, stat) * _correlation(taus, dominant) + np.diag(np.full(taus.size, eps**2)))
    corr /= np.outer(rel, rel)
    cov = bread @ (aw.T @ corr @ aw) @ bread
    dof = int(taus.size - len(cols))
    if dof > 0:
        cov = cov * max(1.0, chi2 / dof)
    return h, cov, chi2, dof, dominant


def _fit_free(design: _Cols, var: np.ndarray, nu: np.ndarray, taus: np.ndarray, cols: list[int],
              eps: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Unconstrained weighted fit of the columns ``cols`` (coefficients of either
    sign) and the sandwich covariance with the modelled correlation across τ,
    not scaled by χ²/dof.

    Free of term selection and of the non-negativity bound, ``ĉ`` is unbiased to
    first order and its covariance applies to every term, including two that
    share the end of the record (K and R): the basis of the intervals.

    Returns the coefficients, their covariance, the linear map G with
    ``ĉ = G·σ̂²`` (final weights held fixed) and the modelled covariance of the
    σ̂² points, ``diag(s)·C·diag(s)`` with ``s = σ²_model·√(2/ν)``.
    """
    sub = design.mat[:, cols]
    stat = np.sqrt(2.0 / nu)
    rel = np.sqrt(stat**2 + eps**2)
    h, sigma, _ = irls_fit(sub, var, rel, signed=np.ones(len(cols), bool))
    aw = sub / sigma[:, None]
    bread = _normal_inverse(aw)
    dominant = _dominant(design, cols, sub * np.abs(h))
    corr = (np.outer(stat, stat) * _correlation(taus, dominant) + np.diag(np.full(taus.size, eps**2)))
    corr /= np.outer(rel, rel)
    gain = bread @ aw.T / sigma[None, :]
    s_abs = sigma * stat / rel
    vcov = np.outer(s_abs, s_abs) * _correlation(taus, dominant)
    return h, bread @ (aw.T @ corr @ aw) @ bread, gain, vcov


def _chi2_expectation(design: _Cols, var: np.ndarray, nu: np.ndarray, taus: np.ndarray, cols: list[int],
                      eps: float) -> tuple[float, float, float]:
    """χ² of the fit and its mean and standard deviation when the residuals are
    correlated across τ as modelled (they are not χ²_dof then): with r = (I − H)e,
    e ~ N(0, C) in whitened units, E χ² = tr M and var χ² = 2 tr M², M = (I − H)C(I − H)ᵀ."""
    sub = design.mat[:, cols]
    stat = np.sqrt(2.0 / nu)
    rel = np.sqrt(stat**2 + eps**2)
    signed = np.array([c == 0 for c in cols])
    h, sigma, chi2 = irls_fit(sub, var, rel, signed=signed)
    aw = sub / sigma[:, None]
    hat = aw @ _normal_inverse(aw) @ aw.T
    dominant = _dominant(design, cols, sub * np.abs(h))
    corr = (np.outer(stat, stat) * _correlation(taus, dominant) + np.diag(np.full(taus.size, eps**2)))
    corr /= np.outer(rel, rel)
    proj = np.eye(taus.size) - hat
    m = proj @ corr @ proj.T
    return chi2, float(np.trace(m)), float(math.sqrt(2.0 * np.sum(m * m.T)))


def _discrepancy(design: _Cols, var: np.ndarray, nu: np.ndarray, taus: np.ndarray, cols: list[int]
                 ) -> tuple[float, float]:
    """Relative error floor ε per τ that brings the χ² of the full fit down to its
    expectation, when its tail probability is below ``_EPS_TRIGGER``; and χ²/dof
    without it."""
    from scipy.optimize import brentq  # imported here: keeps `import sigmatau` light

    chi2, mean, sd = _chi2_expectation(design, var, nu, taus, cols, 0.0)
    dof = taus.size - len(cols)
    raw = chi2 / dof if dof > 0 else math.nan
    if dof < 3 or _chi2_tail(chi2, mean, sd) >= _EPS_TRIGGER:
        return 0.0, raw

    def excess(log_eps: float) -> float:
        c, mu, _ = _chi2_expectation(design, var, nu, taus, cols, math.exp(log_eps))
        return c / mu - 1.0

    lo, hi = math.log(1e-5), math.log(3.0)
    if excess(hi) > 0:
        return 3.0, raw
    return float(math.exp(brentq(excess, lo, hi, xtol=1e-3))), raw


def _fit_model(taus: np.ndarray, var: np.ndarray, nu: np.ndarray, rate: float, terms: Sequence[str],
               min_significance: float, gm_tau: float = math.nan) -> _Fit:
    """Backward term selection: drop terms fitted at zero, then the least
    significant one while it is below ``min_significance`` or while fewer than
    one degree of freedom is left. The last term standing is kept in the curve
    but reported as resolved only if it is significant. The 1/τ² column may be
    negative (a sensor low-pass filter pulls the shortest τ below the white
    line); a positive one is quantisation. With a finite ``gm_tau`` the variance of a
    Gauss–Markov term of that correlation time is a sixth column, selected like the others."""
    design = _columns(taus, rate, gm_tau)
    if math.isfinite(gm_tau):
        terms = tuple(terms) + ("GM",)
    names = design.names
    cols = [names.index(t) for t in terms]
    eps, raw = _discrepancy(design, var, nu, taus, cols)
    cols, h, cov, chi2, dof, dominant, z, needed = _select_terms(design, var, nu, taus, cols, eps,
                                                                 min_significance)
    significant = dof >= 1 and all(z[i] >= min_significance or cols[i] in needed for i in range(len(cols)))
    kept_cols = [c for c, hc in zip(cols, h) if hc > 0] if significant else []
    filter_time = 0.0
    if significant and 0 in cols and h[cols.index(0)] < 0:
        n2 = h[cols.index(1)] if 1 in cols else 0.0
        filter_time = float(-3.0 * h[cols.index(0)] / n2) if n2 > 0 else math.inf
    k = len(names)
    coef = np.zeros(k)
    full = np.zeros((k, k))
    coef[cols] = h
    full[np.ix_(cols, cols)] = cov
    upper = _dropped_bounds(design, var, nu, taus, terms, cols, kept_cols, eps)
    full_coef, full_cov, full_gain, var_cov = _free_fit_of_every_term(design, var, nu, taus, terms, eps)
    return _Fit(coef, full, tuple(names[c] for c in kept_cols), chi2, dof, upper, dominant, eps, filter_time,
                raw, tuple(names[c] for c in needed if c in kept_cols), full_coef, full_cov,
                full_gain, var_cov, design.gm_tau)


def _select_terms(design: _Cols, var: np.ndarray, nu: np.ndarray, taus: np.ndarray, cols: list[int],
                  eps: float, min_significance: float) -> tuple:
    """The backward selection loop of :func:`_fit_model`.

    Returns
    -------
    tuple
        ``(cols, h, cov, chi2, dof, dominant, z, needed)``: the columns left, the
        last fit's coefficients, covariance, χ², degrees of freedom and dominant
        α per τ, each coefficient's significance ``|c|/σ_c``, and the columns
        kept because the curve needs them.
    """
    cols = list(cols)
    needed: set[int] = set()
    while True:
        h, cov, chi2, dof, dominant = _fit_once(design, var, nu, taus, cols, eps)
        zero = h == 0
        if zero.all():
            raise DataError("no term of the IMU model fits this curve")
        if zero.any():
            cols = [c for c, zr in zip(cols, zero) if not zr]
            continue
        err = np.sqrt(np.clip(np.diag(cov), 0.0, None))
        z = np.where(err > 0, np.abs(h) / np.where(err > 0, err, 1.0), np.inf)
        if len(cols) == 1:
            break
        crowded = len(cols) >= taus.size
        weak = [i for i in range(len(cols)) if cols[i] not in needed and (z[i] < min_significance or crowded)]
        if not weak:
            break
        worst = min(weak, key=lambda i: z[i])
        if not crowded:
            # A term whose removal leaves the curve undescribed (χ² beyond its 10⁻⁴
            # tail, and doubled) is needed even if its own level is uncertain:
            # dropping it would make the scaled covariance swamp the rest.
            trial = cols[:worst] + cols[worst + 1:]
            chi2_t, mean_t, sd_t = _chi2_expectation(design, var, nu, taus, trial, eps)
            if _chi2_tail(chi2_t, mean_t, sd_t) < _EPS_TRIGGER and chi2_t > 2.0 * chi2:
                needed.add(cols[worst])
                continue
        cols.pop(worst)
    return cols, h, cov, chi2, dof, dominant, z, needed


def _dropped_bounds(design: _Cols, var: np.ndarray, nu: np.ndarray, taus: np.ndarray,
                    terms: Sequence[str], cols: list[int], kept_cols: list[int], eps: float
                    ) -> dict[str, tuple[float, float]]:
    """For each term not kept: ``(c, σ_c)`` of a refit of the selected columns with it forced in
    (``c`` clipped at 0), from which :func:`_fit_parameters` builds its upper bound."""
    upper = {}
    for t in terms:
        c = design.names.index(t)
        if c in kept_cols:
            continue
        trial = sorted(set(cols) | {c})
        h2, cov2, *_ = _fit_once(design, var, nu, taus, trial, eps)
        k = trial.index(c)
        upper[t] = (max(float(h2[k]), 0.0), math.sqrt(max(float(cov2[k, k]), 0.0)))
    return upper


def _free_fit_of_every_term(design: _Cols, var: np.ndarray, nu: np.ndarray, taus: np.ndarray,
                            terms: Sequence[str], eps: float
                            ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`_fit_free` of all ``terms``, laid out on the five columns Q…R (zeros where excluded).

    Returns ``(full_coef, full_cov, full_gain, var_cov)`` as stored in :class:`_Fit`.
    """
    all_cols = [design.names.index(t) for t in terms]
    h_all, cov_all, gain_all, var_cov = _fit_free(design, var, nu, taus, all_cols, eps)
    k = len(design.names)
    full_gain = np.zeros((k, taus.size))
    full_gain[all_cols] = gain_all
    full_coef = np.zeros(k)
    full_cov = np.zeros((k, k))
    full_coef[all_cols] = h_all
    full_cov[np.ix_(all_cols, all_cols)] = cov_all
    return full_coef, full_cov, full_gain, var_cov


def _fit_parameters(fit: _Fit, conf: float, su: SensorUnit, terms: Sequence[str], taus: np.ndarray
                    ) -> dict[str, Parameter]:
    """Parameters of the fit: values from the selected model, intervals and bounds
    from the unconstrained fit of every term.

    The selected model's own covariance understates the uncertainty of a term
    that shares its region with a dropped one (K and R at the end of the
    record): the kept term absorbs the other's share, and the selection keeps
    it when its realisation is high. The unconstrained fit of all terms has
    neither effect: with ``ĉ`` and ``σ_c`` from it the interval on ``c = P²``
    is ``[max(ĉ − zσ_c, 0), ĉ + zσ_c]`` (z for the two-sided level), widened to
    include the selected model's value, and a dropped term's upper bound is
    ``√(max(ĉ, 0) + zσ_c)`` (one-sided at ``(1 + p)/2``).
    """
    z = ndtri(0.5 + conf / 2.0)
    out = {}
    for t in terms:
        j = TERMS.index(t)
        unit = su.term_unit(t)
        cf, sf = float(fit.full_coef[j]), math.sqrt(max(float(fit.full_cov[j, j]), 0.0))
        if t in fit.kept:
            c, sc = float(fit.coef[j]), math.sqrt(max(float(fit.cov[j, j]), 0.0))
            value = math.sqrt(c)
            lo = math.sqrt(max(cf - z * sf, 0.0))
            hi = math.sqrt(max(cf + z * sf, 0.0))
            lo, hi = min(lo, value), max(hi, value)
            note = (f"interval: ĉ ± {z:.3g}σ_c on c = {t}² from the unconstrained fit of every term"
                    f" (ĉ = {cf:.4g}, σ_c = {sf:.3g}), widened to include the selected model's value")
            if t in fit.needed:
                note += (f"; kept although c/σ_c = {c / sc:.2g} is below the significance asked for, because"
                         " the curve is not described without it")
            out[t] = Parameter(t, value, float(lo), float(hi), unit, True, "fit", conf, su.kind, note=note)
        elif t == "Q" and fit.filter_time > 0:
            out[t] = Parameter(
                t, math.nan, 0.0, math.inf, unit, False, "fit", conf, su.kind,
                note=(f"masked: the 1/τ² term is negative (a low-pass filter, τ_f = {fit.filter_time:.3g} s),"
                      " which hides any quantisation"))
        else:
            c, sc = fit.upper.get(t, (0.0, math.inf))
            # The larger of two bounds: the unconstrained fit's, and that of a refit of the
            # selected terms with this one forced in (non-negative), whose estimate is not
            # pulled below zero by a neighbour's realisation at the end of the record.
            free = math.sqrt(max(cf, 0.0) + z * sf) if math.isfinite(sf) else math.inf
            forced = math.sqrt(c + z * sc) if math.isfinite(sc) else math.inf
            bound = max(free, forced)
            out[t] = Parameter(
                t, math.nan, 0.0, bound, unit, False, "fit", conf, su.kind,
                note=(f"dropped by term selection (not significant over τ = {taus[0]:.3g}–{taus[-1]:.3g} s);"
                      f" upper bound: the larger of √(max(ĉ, 0) + {z:.3g}σ_c) from the unconstrained fit of"
                      f" every term and √(c + {z:.3g}σ_c) from a refit with {t} forced in"))
    return out
