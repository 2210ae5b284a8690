"""The weighted fit of the five-term model to the AVAR curve, its term selection and intervals.

How the fit works is described in :func:`sigmatau.imu.analyze` (*Fit*, *Intervals*):
a weighted non-negative least-squares fit (``irls_fit``, shared with ``fit_power_law``) with the sandwich
covariance of variance estimates correlated across τ (``_correlation``), a
model-discrepancy floor when the χ² says the curve departs from the model
(``_discrepancy``), backward term selection (``_select_terms``), the
unconstrained fit of every term behind the intervals (``_fit_free``,
``_fit_parameters``), the selection-aware intervals of the kept terms
(``_selection_aware_intervals``: the truncated normal's Neyman limits,
``_truncated_below_limits``) and the selection-aware upper bounds of the dropped
terms (``_selection_aware_bounds``: ``_truncated_upper``, its mirror image), both
from where the selection's decision flips (``_selection_edge``), the spread at a
candidate value (``_spread_at``) and one root finder (``_truncated_solve``).
``_dropped_bounds`` (a refit with the term forced in) serves the Gauss–Markov
term's bound.
"""

from __future__ import annotations

import math
from typing import Mapping, NamedTuple, Sequence

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
    significant = _significant(cols, dof, z, needed, min_significance)
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


def _significant(cols: list[int], dof: int, z: np.ndarray, needed: set, min_significance: float) -> bool:
    """Whether the model left by :func:`_select_terms` is reported: a degree of freedom left and
    every column significant or needed (else no term is reported as kept)."""
    return dof >= 1 and all(z[i] >= min_significance or cols[i] in needed for i in range(len(cols)))


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


class _Limits(NamedTuple):
    """Interval on ``c = P²`` of a kept term (:func:`_selection_aware_intervals`)."""

    low: float    # may be < 0 (clipped at 0 on P)
    high: float
    how: str      # "conditional", "score-at-edge" or "wald" (kept whatever ĉ: no selection to account for)
    edge: float   # ĉ below which the selection would drop the term (-inf: none)
    mid: float    # the median-unbiased estimate given the selection: the limit at level 0 (ĉ for "wald")


def _fit_parameters(fit: _Fit, conf: float, su: SensorUnit, terms: Sequence[str], taus: np.ndarray,
                    kept_limits: Mapping[str, _Limits], dropped: Mapping[str, float],
                    caps: Mapping[str, float]) -> dict[str, Parameter]:
    """Parameters of the fit: values, intervals and bounds from the unconstrained fit of
    every term, conditional on the term selection.

    The selected model's own covariance understates the uncertainty of a term
    that shares its region with a dropped one (K and R at the end of the
    record): the kept term absorbs the other's share, and the selection keeps
    it when its realisation is high. The unconstrained fit of all terms has
    neither effect; a kept term's interval on ``c = P²`` is from ``kept_limits``
    (:func:`_selection_aware_intervals`: the limits of its ``ĉ`` given that the
    selection kept the term), a dropped term's upper bound ``√U`` with ``U``
    from ``dropped`` (:func:`_selection_aware_bounds`, on c), or the curve's own
    bound from ``caps`` (on the coefficient) when lower. A kept term's value is
    chosen by :func:`_kept_parameter` and always lies in its interval.
    """
    out = {}
    for t in terms:
        j = TERMS.index(t)
        unit = su.term_unit(t)
        if t in fit.kept:
            out[t] = _kept_parameter(fit, t, conf, su, kept_limits[t])
        elif t == "Q" and fit.filter_time > 0:
            out[t] = Parameter(
                t, math.nan, 0.0, math.inf, unit, False, "fit", conf, su.kind,
                note=(f"masked: the 1/τ² term is negative (a low-pass filter, τ_f = {fit.filter_time:.3g} s),"
                      " which hides any quantisation"))
        else:
            cf, sf = float(fit.full_coef[j]), math.sqrt(max(float(fit.full_cov[j, j]), 0.0))
            c_bound = dropped.get(t, math.inf)
            bound = math.sqrt(max(c_bound, 0.0))
            cap = caps.get(t, math.inf)
            how = (f"the selection-aware bound (ĉ = {cf:.4g}, σ_c = {sf:.3g} from the unconstrained fit of every"
                   f" term, a normal truncated where the selection would keep {t})")
            if cap < bound:
                bound = cap
                how = "the curve's own bound (the read-off rule), lower than the selection-aware bound"
            out[t] = Parameter(
                t, math.nan, 0.0, bound, unit, False, "fit", conf, su.kind,
                note=(f"dropped by term selection (not significant over τ = {taus[0]:.3g}–{taus[-1]:.3g} s);"
                      f" upper bound at {50 * (1 + conf):.3g} % given the drop: {how}"))
    return out


#: How each kind of kept-term interval is described in its note (:class:`_Limits`.how).
_KEPT_HOW = {
    "conditional": "the limits of ĉ given that the selection kept {t} (a normal truncated below at {edge:.4g},"
                   " where the selection would drop it; spread at the candidate value)",
    "score-at-edge": "the score limits of ĉ, not conditioned on the selection (ĉ lies at the edge where the"
                     " selection would drop {t}, {edge:.4g}, and the conditional limits are not positive)",
}


def _kept_parameter(fit: _Fit, t: str, conf: float, su: SensorUnit, limits: _Limits) -> Parameter:
    """The :class:`Parameter` of a kept term from ``limits`` on ``c = P²`` (clipped at 0).

    A term the selection keeps whatever its estimate (``how = "wald"``) has the selected model's
    value (more precise than the unconstrained fit's when terms are absent: N's scatter is 1.7×
    smaller) and ``ĉ ± zσ_c`` widened to include it. A term the selection could have dropped has,
    as its value, the median-unbiased estimate given the selection (the selected model's value is
    biased up by the selection: 1.2–1.8× the truth for a kept K or R at the end of the record);
    where that is not positive (an estimate at the selection's edge), the unconstrained estimate
    capped at the interval's upper end, so that the value always lies in the interval."""
    j = TERMS.index(t)
    cf, sf = float(fit.full_coef[j]), math.sqrt(max(float(fit.full_cov[j, j]), 0.0))
    c, sc = float(fit.coef[j]), math.sqrt(max(float(fit.cov[j, j]), 0.0))
    lo = math.sqrt(max(limits.low, 0.0))
    hi = math.sqrt(max(limits.high, 0.0)) if math.isfinite(limits.high) else math.inf
    if limits.how == "wald":
        value = math.sqrt(c)
        lo, hi = min(lo, value), max(hi, value)
        z = ndtri(0.5 + conf / 2.0)
        note = (f"interval: ĉ ± {z:.3g}σ_c on c = {t}² from the unconstrained fit of every term"
                f" (ĉ = {cf:.4g}, σ_c = {sf:.3g}), widened to include the selected model's value (the"
                f" selection keeps {t} whatever its estimate)")
    else:
        if limits.mid > 0:
            value = math.sqrt(limits.mid)
            what = f"the median of c = {t}² given the selection"
        else:
            value = min(math.sqrt(max(cf, 0.0)), hi)
            what = (f"the unconstrained estimate, capped at the interval's upper end (the median of c = {t}²"
                    " given the selection is not above zero: the estimate lies at the selection's edge)")
        note = (f"value: {what}; interval: {_KEPT_HOW[limits.how].format(t=t, edge=limits.edge)}; both from"
                f" the unconstrained fit of every term (ĉ = {cf:.4g}, σ_c = {sf:.3g}; the selected model drawn"
                f" over the curve has {t} = {math.sqrt(c):.4g})")
    if t in fit.needed:
        note += (f"; kept although c/σ_c = {c / sc:.2g} is below the significance asked for, because"
                 " the curve is not described without it")
    return Parameter(t, value, lo, hi, su.term_unit(t), True, "fit", conf, su.kind, note=note)


def _kept_terms(design: _Cols, var: np.ndarray, nu: np.ndarray, taus: np.ndarray, cols: list[int],
                eps: float, min_significance: float) -> set[int]:
    """The columns that :func:`_fit_model`'s selection reports as kept for the AVAR points ``var``."""
    try:
        left, h, _, _, dof, _, z, needed = _select_terms(design, var, nu, taus, cols, eps, min_significance)
    except DataError:
        return set()
    if not _significant(left, dof, z, needed, min_significance):
        return set()
    return {c for c, hc in zip(left, h) if hc > 0}


#: Distances (in standard errors σ_c) from the observed ĉ, above it for a dropped term and below it
#: for a kept one, at which the selection is rerun to find where its decision flips, then
#: bisections between the last two; a decision that has not flipped at the last distance is taken
#: to hold whatever ĉ (a truncation 6 σ_c away leaves a limit about 1 σ_c from ĉ all but unchanged:
#: Φ(5) = 1 − 3·10⁻⁷).
_EDGE_STEPS = (0.5, 1.0, 1.5, 2.0, 3.0, 4.0, 6.0)
_EDGE_BISECTIONS = 5


def _selection_edge(fit: _Fit, design: _Cols, cols: list[int], var: np.ndarray, nu: np.ndarray,
                    taus: np.ndarray, j: int, min_significance: float, *, kept_now: bool) -> float:
    """Where the selection's decision on column ``j`` flips as ``ĉ_j`` moves away from its observed
    value: upwards for a dropped term, downwards for a kept one; ``±inf`` when it does not flip
    within ``_EDGE_STEPS[-1]`` standard errors.

    In the fit's linearised Gaussian model of the AVAR points (``v ~ N(Ac, V)``, ``V`` =
    ``fit.var_cov``, ``ĉ = g·v`` with ``g`` the row of ``fit.full_gain``), ``v = u + b ĉ_j`` with
    ``b = V gᵀ/(g V gᵀ)`` splits the points into ``ĉ_j`` and ``u``, uncorrelated with it (hence
    independent: jointly Gaussian). The selection is rerun on ``u + b t`` for ``t`` on the far side
    of the observed ``ĉ_j``; a trial with a point at or below zero is outside the model and counts
    as dropped.
    """
    g = fit.full_gain[j]
    s2 = float(g @ fit.var_cov @ g)
    sd, c_obs = math.sqrt(s2), float(fit.full_coef[j])
    b = fit.var_cov @ g / s2
    u = var - b * c_obs
    step = -sd if kept_now else sd

    def flips(t: float) -> bool:
        v = u + b * t
        kept = bool(np.all(v > 0)) and j in _kept_terms(design, v, nu, taus, cols, fit.eps, min_significance)
        return kept != kept_now

    far = c_obs + _EDGE_STEPS[-1] * step
    if not flips(far):
        return -math.inf if kept_now else math.inf
    near = c_obs
    for k in _EDGE_STEPS[:-1]:
        if flips(c_obs + k * step):
            far = c_obs + k * step
            break
        near = c_obs + k * step
    for _ in range(_EDGE_BISECTIONS):
        mid = 0.5 * (near + far)
        near, far = (near, mid) if flips(mid) else (mid, far)
    return 0.5 * (near + far)


def _spread_at(fit: _Fit, design: _Cols, j: int):
    """``s(c)``: the standard error of the unconstrained ``ĉ_j`` when the true ``c_j`` is ``c`` (the
    other coefficients at their estimates), each point's standard error scaled with its modelled
    AVAR (``s_i ∝ AVAR_i``, as ``√(2/ν)`` says) and the points' correlation kept."""
    model = design.mat @ fit.full_coef
    s = np.sqrt(np.clip(np.diag(fit.var_cov), 0.0, None))
    safe = np.where(s > 0, s, 1.0)
    corr = fit.var_cov / np.outer(safe, safe)
    pos = np.where(model > 0, model, 1.0)
    g, col, c_obs = fit.full_gain[j], design.mat[:, j], float(fit.full_coef[j])

    def spread(c: float) -> float:
        m = np.maximum(model + col * (c - c_obs), 1e-3 * np.abs(model))
        gs = g * s * m / pos
        return math.sqrt(max(float(gs @ corr @ gs), 0.0))

    return spread


def _truncated_solve(c_obs: float, spread, edge: float, prob: float) -> float:
    """The ``c`` with ``S(c) = prob`` for ``ĉ' ~ N(c, s(c)²)`` truncated below at ``edge`` (``-inf``: no
    truncation), where ``S(c) = P_c(ĉ' ≥ ĉ | ĉ' > edge) = Φ((c − ĉ)/s(c)) / Φ((c − edge)/s(c))``
    increases with ``c``; ``±inf`` when no finite ``c`` within 10⁴ spreads of ``ĉ`` does."""
    from scipy.optimize import brentq  # imported here: keeps `import sigmatau` light
    from scipy.special import log_ndtr

    s0 = spread(c_obs)
    target = math.log(prob)

    def excess(x: float) -> float:  # x = (c − ĉ)/s(ĉ)
        c = c_obs + x * s0
        s = spread(c)
        trunc = float(log_ndtr((c - edge) / s)) if math.isfinite(edge) else 0.0
        return float(log_ndtr((c - c_obs) / s)) - trunc - target

    lo, hi = -1.0, 1.0
    while excess(hi) < 0:
        lo, hi = hi, 2.0 * hi
        if hi > 1e4:
            return math.inf
    while excess(lo) > 0:
        lo, hi = 2.0 * lo, lo
        if lo < -1e4:
            return -math.inf
    return c_obs + s0 * brentq(excess, lo, hi, xtol=1e-6)


def _truncated_upper(c_obs: float, spread, edge: float, level: float) -> float:
    """The upper limit ``U`` with ``P_U(ĉ' ≤ ĉ | ĉ' < edge) = 1 − level`` for ``ĉ' ~ N(U, s(U)²)``:
    ``Φ((ĉ − U)/s(U)) = (1 − level)·Φ((edge − U)/s(U))`` (``inf`` when no finite U satisfies it).

    The mirror image of a truncation below (:func:`_truncated_solve` with ``c → −c``)."""
    return -_truncated_solve(-c_obs, lambda c: spread(-c), -edge, 1.0 - level)


def _truncated_below_limits(c_obs: float, spread, edge: float, level: float) -> tuple[float, float]:
    """The two-sided limits ``(L, U)`` at ``level`` for ``ĉ' ~ N(c, s(c)²)`` truncated below at ``edge``
    (the selection keeps the term exactly when ``ĉ' > edge``; ``-inf``: no truncation): ``S(L) =
    (1 − level)/2`` and ``S(U) = (1 + level)/2`` (:func:`_truncated_solve`); either is ``∓inf`` when
    no finite value solves it."""
    return (_truncated_solve(c_obs, spread, edge, 0.5 - level / 2.0),
            _truncated_solve(c_obs, spread, edge, 0.5 + level / 2.0))


def _selection_aware_intervals(fit: _Fit, taus: np.ndarray, var: np.ndarray, nu: np.ndarray, rate: float,
                               terms: Sequence[str], min_significance: float, conf: float
                               ) -> dict[str, _Limits]:
    """Interval ``(L, U)`` on ``c = P²`` of every term the selection kept, covering at ``conf`` *given
    that it was kept*, and how it was made (see :func:`sigmatau.imu.analyze`, *Intervals*).

    The counterpart of :func:`_selection_aware_bounds`: given ``u`` (the part of the data
    independent of the unconstrained ``ĉ``, :func:`_selection_edge`) the selection keeps the term
    exactly when ``ĉ > t*(u)``, so given the keep ``ĉ`` is a normal truncated below at ``t*``, and the
    Neyman limits of that truncated normal (:func:`_truncated_below_limits`), with the spread at the
    candidate value (:func:`_spread_at`), cover at ``conf`` for every ``u``. The selection keeps a
    term when its estimate came out high, and the estimate's spread grows with it: intervals that
    ignore both over-covered among the kept runs (kept K and R: 74–86 % at 68.3 %). When the upper
    limit is not positive (an estimate at the edge, which the truncated normal explains by a true
    value far below it: 1–7 % of kept K and R) the score limits that ignore the selection are given
    instead. A term the selection keeps whatever its estimate (``t* = -inf``: N in most records)
    has no selection to account for: ``ĉ ± zσ_c`` (``how = "wald"``, as when the spread is not
    positive), and :func:`_kept_parameter` keeps the selected model's value for it.
    """
    design = _columns(taus, rate, fit.gm_tau)
    cols = [design.names.index(t) for t in tuple(terms) + (("GM",) if math.isfinite(fit.gm_tau) else ())]
    z = ndtri(0.5 + conf / 2.0)
    out: dict[str, _Limits] = {}
    for t in terms:
        if t not in fit.kept:
            continue
        j = design.names.index(t)
        cf, sf = float(fit.full_coef[j]), math.sqrt(max(float(fit.full_cov[j, j]), 0.0))
        spread = _spread_at(fit, design, j)
        edge = (_selection_edge(fit, design, cols, var, nu, taus, j, min_significance, kept_now=True)
                if spread(cf) > 0 else -math.inf)
        if not math.isfinite(edge):
            out[t] = _Limits(cf - z * sf, cf + z * sf, "wald", edge, cf)
            continue
        trunc, how = edge, "conditional"
        lo, hi = _truncated_below_limits(cf, spread, trunc, conf)
        if not hi > 0:
            trunc, how = -math.inf, "score-at-edge"
            lo, hi = _truncated_below_limits(cf, spread, trunc, conf)
        out[t] = _Limits(lo, hi, how, edge, _truncated_solve(cf, spread, trunc, 0.5))
    return out


def _selection_aware_bounds(fit: _Fit, taus: np.ndarray, var: np.ndarray, nu: np.ndarray, rate: float,
                            terms: Sequence[str], min_significance: float, conf: float) -> dict[str, float]:
    """Upper bound on ``c = P²`` of every term the selection dropped, holding at ``(1 + conf)/2``
    given that it was dropped (see :func:`sigmatau.imu.analyze`, *Intervals*).

    Returns
    -------
    dict
        Term → bound on c (``inf``: none finite; the caller caps it by the curve's bound).

    Notes
    -----
    Post-selection inference by conditioning on the selection event (Lee, Sun, Sun & Taylor 2016;
    Fithian, Sun & Taylor 2014): with ``ĉ`` the unconstrained estimate and ``u`` the part of the
    data independent of it (:func:`_selection_edge`), the selection drops the term exactly when
    ``ĉ < t*(u)``, so given the drop and ``u``, ``ĉ`` is a normal truncated above at ``t*``. The
    bound ``U`` solves ``Φ((ĉ − U)/s(U)) = ((1 − conf)/2)·Φ((t* − U)/s(U))``: for every ``u`` the
    probability that ``c ≤ U`` given the drop is ``(1 + conf)/2``, hence also given the drop alone.
    The spread ``s(U)`` is evaluated at the candidate (:func:`_spread_at`), as in a score (Wilson)
    interval: the AVAR points' scatter grows with their level, and a spread taken at a low estimate
    is too small exactly in the runs that the selection drops. When ``U ≤ 0`` (an estimate far
    below zero, 1–3 % of the dropped runs) the bound of ``ĉ = 0`` is given instead: ``c ≥ 0``, and a
    record should not print ``K < 0``; ``U`` increases with ``ĉ``, so this only adds coverage.
    """
    design = _columns(taus, rate, fit.gm_tau)
    cols = [design.names.index(t) for t in tuple(terms) + (("GM",) if math.isfinite(fit.gm_tau) else ())]
    out: dict[str, float] = {}
    for t in terms:
        if t in fit.kept or (t == "Q" and fit.filter_time > 0):
            continue
        j = design.names.index(t)
        spread = _spread_at(fit, design, j)
        if not spread(float(fit.full_coef[j])) > 0:
            out[t] = math.inf
            continue
        edge = _selection_edge(fit, design, cols, var, nu, taus, j, min_significance, kept_now=False)
        bound = _truncated_upper(float(fit.full_coef[j]), spread, edge, 0.5 + conf / 2.0)
        if bound <= 0:
            # An estimate so far below zero that the limit is not positive (1–3 % of the dropped
            # runs): the bound at the physical boundary ĉ = 0 is printed instead of "K < 0".
            bound = _truncated_upper(0.0, spread, edge if edge > 0 else math.inf, 0.5 + conf / 2.0)
        out[t] = bound
    return out
