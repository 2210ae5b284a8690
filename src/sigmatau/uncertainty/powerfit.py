"""Reading noise off a computed deviation curve: local log–log slopes (§5.1) and a power-law fit (§6.3).

Public through :mod:`sigmatau.uncertainty.noiseid` (and :mod:`sigmatau.noiseid`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Mapping, Optional, Sequence, Union

import numpy as np

from ..core.powerlaw import response
from ..core.result import StabilityResult
from ..core.validate import check_rate
from ..errors import DataError, ParameterError
from .noisebase import NOISE_NAMES

# ------------------------------------------------------------ local slopes (§5.1)

_SLOPES_ALLAN = ((-1.0, (2, 1)), (-0.5, (0,)), (0.0, (-1,)), (0.5, (-2,)), (1.0, (-3,)), (1.5, (-4,)))
_SLOPES_MOD = ((-1.5, (2,)), (-1.0, (1,)), (-0.5, (0,)), (0.0, (-1,)), (0.5, (-2,)), (1.0, (-3,)), (1.5, (-4,)))
_SLOPES_TIME = tuple((s + 1.0, a) for s, a in _SLOPES_MOD)
_SLOPE_TABLES = {
    "adev": _SLOPES_ALLAN, "oadev": _SLOPES_ALLAN, "totdev": _SLOPES_ALLAN,
    "hdev": _SLOPES_ALLAN, "ohdev": _SLOPES_ALLAN, "htotdev": _SLOPES_ALLAN,
    "theo1": _SLOPES_ALLAN, "theobr": _SLOPES_ALLAN, "theoh": _SLOPES_ALLAN,
    "mdev": _SLOPES_MOD, "mtotdev": _SLOPES_MOD, "mhdev": _SLOPES_MOD, "mhtotdev": _SLOPES_MOD,
    "tdev": _SLOPES_TIME, "ttotdev": _SLOPES_TIME, "ldev": _SLOPES_TIME,
}


@dataclass(frozen=True, repr=False, eq=False)
class LocalSlopes:
    """Local log–log slopes of a deviation curve (see :func:`local_slopes`).

    Attributes
    ----------
    statistic : str
    taus : numpy.ndarray
        Geometric mean of each pair of neighbouring τ.
    slope, slope_err : numpy.ndarray
        ``Δ ln σ / Δ ln τ`` and its standard uncertainty.
    nominal : numpy.ndarray
        Nearest slope of the statistic's table.
    alpha : numpy.ndarray of int
        Noise type of that slope; where ADEV-like slopes of −1 cannot split WPM
        from FPM, α = 1 and ``ambiguous`` is True.
    ambiguous : numpy.ndarray of bool
    """

    statistic: str
    taus: np.ndarray
    slope: np.ndarray
    slope_err: np.ndarray
    nominal: np.ndarray
    alpha: np.ndarray
    ambiguous: np.ndarray

    def __post_init__(self) -> None:
        for name in ("taus", "slope", "slope_err", "nominal", "alpha", "ambiguous"):
            arr = np.array(getattr(self, name), copy=True)
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)

    def __len__(self) -> int:
        return int(self.taus.size)

    def __repr__(self) -> str:
        parts = ", ".join(
            f"{t:.3g}s:{s:+.2f}±{e:.2f}({'WPM/FPM' if amb else NOISE_NAMES.get(int(a), a)})"
            for t, s, e, a, amb in zip(self.taus, self.slope, self.slope_err, self.alpha, self.ambiguous)
        )
        return f"LocalSlopes({self.statistic}: {parts})"


def _independent_terms(result: StabilityResult) -> np.ndarray:
    """Terms of the estimator that are not overlapping: ``min(n, ⌊(N−1)/m⌋)``."""
    blocks = np.maximum((result.n_points - 1) // np.maximum(result.m, 1), 1)
    return np.maximum(np.minimum(result.n, blocks), 1).astype(float)


def local_slopes(result: StabilityResult) -> LocalSlopes:
    """Slope of log σ against log τ between neighbouring τ, and the noise it implies.

    Parameters
    ----------
    result : StabilityResult
        A deviation curve of ADEV, OADEV, MDEV, TDEV, HDEV or OHDEV (also
        TOTDEV, MTOT, TTOT, HTOT and the Theo family, read like their parent).

    Returns
    -------
    LocalSlopes

    Notes
    -----
    ``slope_i = (ln σ_{i+1} − ln σ_i)/(ln τ_{i+1} − ln τ_i)``. Uncertainty:
    with an EDF ν (``result.edf``), ``var(ln σ) ≈ 1/(2ν)``; without it the
    design tip's simple estimate, a relative deviation error ``1/√n``, with n
    the number of non-overlapping terms ``min(n, ⌊(N−1)/m⌋)`` (overlapped
    terms are not independent). The errors of the two ends are added in
    quadrature; the positive correlation of neighbouring estimates is ignored,
    which makes ``slope_err`` conservative.

    Deviation slopes (design tip table; numerics.md §5.1):

    ======  =====  =====  =====  =====  =====  =====  =====
    stat    WPM    FPM    WFM    FFM    RWFM   FWFM   RRFM
    ======  =====  =====  =====  =====  =====  =====  =====
    ADEV    −1     −1     −1/2   0      +1/2   +1     +3/2
    MDEV    −3/2   −1     −1/2   0      +1/2   +1     +3/2
    TDEV    −1/2   0      +1/2   +1     +3/2   +2     +5/2
    HDEV    −1     −1     −1/2   0      +1/2   +1     +3/2
    ======  =====  =====  =====  =====  =====  =====  =====

    The same rows serve OADEV (ADEV) and OHDEV (HDEV). Each slope is assigned
    to the nearest tabulated value. AVAR and MVAR do not converge for FWFM and
    RRFM: there the slopes are those of a finite record (as in the tip's
    table), and the Hadamard family should be used. ADEV/HDEV cannot separate
    WPM from FPM (use MDEV or TDEV); FPM's ADEV slope is also only close to −1
    (its logarithmic factor makes it about −0.9).

    References
    ----------
    ST DT0064 (A. Vitali, 2016), noise identification table; W. J. Riley,
    NIST SP 1065 (2008) §5.6; numerics.md §5.1.
    """
    if not isinstance(result, StabilityResult):
        raise ParameterError(f"result must be a StabilityResult, got {type(result).__name__}")
    table = _SLOPE_TABLES.get(result.statistic)
    if table is None:
        raise ParameterError(
            f"result.statistic={result.statistic!r} has no slope table; supported: {sorted(_SLOPE_TABLES)}"
        )
    if len(result) < 2:
        raise DataError(f"local slopes need at least 2 τ values, got {len(result)}")
    dev = np.asarray(result.dev, dtype=float)
    taus = np.asarray(result.taus, dtype=float)
    if np.any(dev <= 0) or np.any(np.diff(taus) <= 0):
        raise DataError("local slopes need positive deviations at strictly increasing τ")
    if result.edf is not None:
        sig = 1.0 / np.sqrt(2.0 * np.asarray(result.edf, dtype=float))
    else:
        sig = 1.0 / np.sqrt(_independent_terms(result))
    dlt = np.diff(np.log(taus))
    slope = np.diff(np.log(dev)) / dlt
    err = np.sqrt(sig[:-1] ** 2 + sig[1:] ** 2) / dlt
    nominal_slopes = np.array([s for s, _ in table])
    bounds = 0.5 * (nominal_slopes[:-1] + nominal_slopes[1:])
    idx = np.searchsorted(bounds, slope)
    cands = [table[i][1] for i in idx]
    alpha = np.array([1 if len(c) > 1 else c[0] for c in cands], dtype=np.int64)
    ambiguous = np.array([len(c) > 1 for c in cands], dtype=bool)
    return LocalSlopes(statistic=result.statistic, taus=np.sqrt(taus[:-1] * taus[1:]), slope=slope,
                       slope_err=err, nominal=nominal_slopes[idx], alpha=alpha, ambiguous=ambiguous)


# ----------------------------------------------------------- power-law fit (§6.3)

_FIT_FAMILY = {"adev": "avar", "oadev": "avar", "mdev": "mvar", "tdev": "tvar", "hdev": "hvar", "ohdev": "hvar"}
_FIT_ALPHAS = {"avar": (2, 1, 0, -1, -2), "mvar": (2, 1, 0, -1, -2), "tvar": (2, 1, 0, -1, -2),
               "hvar": (2, 1, 0, -1, -2, -3, -4)}


def _response(kind: str, alpha: int, tau: np.ndarray, rate: float) -> np.ndarray:
    """Variance produced by S_y = 1·f^α (unit h_α); continuous model, f_h = rate/2."""
    try:
        return response(kind, alpha, tau, rate, sampled=True)
    except KeyError:
        allowed = sorted(_FIT_ALPHAS[kind])
        raise ParameterError(f"alpha={alpha!r} is not supported by this statistic; allowed: {allowed}") from None


def power_law_variance(
    statistic: str,
    alpha: int,
    taus: Union[float, np.ndarray],
    *,
    rate: float = 1.0,
    h: float = 1.0,
) -> np.ndarray:
    """Expected variance of a statistic for one power-law noise ``S_y = h f^α``.

    Parameters
    ----------
    statistic : {"adev", "oadev", "mdev", "tdev", "hdev", "ohdev"}
        Statistic whose variance is wanted (overlapped and non-overlapped forms
        share their expectation).
    alpha : int
        Noise exponent: 2 … −2 (AVAR, MVAR, TVAR), 2 … −4 (HVAR).
    taus : float or array_like
        Averaging times in seconds.
    rate : float
        Sample rate; the WPM and FPM terms use the cut-off ``f_h = rate/2``.
    h : float
        Noise level ``h_α``.

    Returns
    -------
    numpy.ndarray
        σ²(τ) (for TDEV, the time variance TVAR = τ²/3·MVAR, in phase units²).

    Notes
    -----
    Continuous model with a sharp cut-off f_h (numerics.md §6.3), e.g.
    AVAR: WPM ``3 f_h h₂/(4π²τ²)``, FPM ``h₁[3γ − ln 2 + 3 ln(2πf_hτ)]/(4π²τ²)``,
    WFM ``h₀/(2τ)``, FFM ``2 ln 2·h₋₁``, RWFM ``(2π²/3) h₋₂ τ``;
    MVAR: ``3 f_h τ0 h₂/(4π²τ³)``, ``3 ln(256/27) h₁/(8π²τ²)``,
    ``h₀/(4τ)·(1 + 1/m²)``, ``[(27/8) ln 3 − 4 ln 2] h₋₁``, ``(11π²/20) h₋₂ τ``;
    HVAR: ``5 f_h h₂/(6π²τ²)``, ``h₁[10γ − 6 ln 2 + ln 3 + 10 ln(2πf_hτ)]/(12π²τ²)``,
    ``h₀/(2τ)``, ``[4 ln 2 − (3/2) ln 3] h₋₁``, ``(π²/3) h₋₂ τ``,
    ``(π²/6)(27 ln 3 − 32 ln 2) h₋₃ τ²``, ``(11π⁴/15) h₋₄ τ³``.
    The MVAR WPM term and the factor ``(1 + 1/m²)`` of its WFM term are exact
    for sampled data (the published ``h₀/(4τ)`` is their large-m limit).
    The other MVAR terms are large-m limits; FPM, FFM and RWFM also differ by a
    few per cent from the continuous model at m ≲ 4 (numerics.md §6.1).

    References
    ----------
    W. J. Riley, NIST SP 1065 (2008) §5.2, Table 9 (AVAR/MVAR in terms of h_α);
    numerics.md §6.3.

    Examples
    --------
    >>> from sigmatau.noiseid import power_law_variance
    >>> float(power_law_variance("oadev", 0, 10.0, h=2.0))    # h0/(2τ)
    0.1
    """
    kind = _FIT_FAMILY.get(statistic)
    if kind is None:
        raise ParameterError(f"statistic={statistic!r} must be one of {sorted(_FIT_FAMILY)}")
    rate_f = check_rate(rate)
    t = np.asarray(taus, dtype=float)
    if np.any(t <= 0) or not np.all(np.isfinite(t)):
        raise ParameterError("taus must be positive and finite")
    return h * _response(kind, int(alpha), t, rate_f)


@dataclass(frozen=True, repr=False, eq=False)
class PowerLawFit:
    """Sum of power-law asymptotes fitted to a variance curve (see :func:`fit_power_law`).

    Attributes
    ----------
    statistic : str
        Statistic the curve was computed with.
    rate : float
        Sample rate of the data (f_h = rate/2 for the WPM/FPM terms).
    h, h_err : dict of int to float
        Fitted level ``h_α`` of each kept term (S_y = Σ h_α f^α) and its
        standard uncertainty.
    kept, dropped : tuple of int
        Exponents kept and dropped (zero or not significant).
    chi2 : float
        Weighted residual sum of squares of the final fit.
    dof : int
        Number of τ used minus number of kept terms.
    taus : numpy.ndarray
        τ values used in the fit.
    """

    statistic: str
    rate: float
    h: Mapping[int, float]
    h_err: Mapping[int, float]
    kept: tuple[int, ...]
    dropped: tuple[int, ...]
    chi2: float
    dof: int
    taus: np.ndarray = field(default_factory=lambda: np.empty(0))

    def term(self, alpha: int, taus: Union[float, np.ndarray]) -> np.ndarray:
        """Variance contributed by the term α at ``taus`` (0 for a dropped term)."""
        t = np.asarray(taus, dtype=float)
        if alpha not in self.h:
            return np.zeros(t.shape)
        return power_law_variance(self.statistic, alpha, t, rate=self.rate, h=self.h[alpha])

    def terms(self, taus: Union[float, np.ndarray]) -> dict[int, np.ndarray]:
        """Each kept term's variance at ``taus``."""
        return {a: self.term(a, taus) for a in self.kept}

    def variance(self, taus: Union[float, np.ndarray]) -> np.ndarray:
        """The fitted variance curve at ``taus``."""
        t = np.asarray(taus, dtype=float)
        return sum((self.term(a, t) for a in self.kept), np.zeros(t.shape))

    def deviation(self, taus: Union[float, np.ndarray]) -> np.ndarray:
        """The fitted deviation curve ``sqrt(variance)`` at ``taus``."""
        return np.sqrt(self.variance(taus))

    def __repr__(self) -> str:
        terms = ", ".join(f"{NOISE_NAMES[a]} h{a}={self.h[a]:.4g}±{self.h_err[a]:.2g}" for a in self.kept)
        return f"PowerLawFit({self.statistic}: {terms}; chi2/dof={self.chi2:.3g}/{self.dof})"


def irls_fit(design: np.ndarray, var: np.ndarray, rel: np.ndarray, *, signed: Optional[np.ndarray] = None,
             iterations: int = 3) -> tuple[np.ndarray, np.ndarray, float]:
    """Iteratively reweighted least squares of ``var`` on the columns of ``design``.

    The coefficients are non-negative except those of the ``signed`` columns. The
    weights come from the model variance, σ_i = model_i·rel_i (the first pass from
    the data), with ``iterations`` reweighting passes; the columns are scaled to
    unit norm for the solver. Shared by :func:`fit_power_law` (rel = √(2/ν):
    var(σ²) ≈ 2σ⁴/ν) and the IMU model's fit.

    Returns
    -------
    h : numpy.ndarray
        The coefficients.
    sigma : numpy.ndarray
        The per-τ standard errors used as weights in the last pass.
    chi2 : float
        The weighted sum of squared residuals.
    """
    from scipy.optimize import lsq_linear, nnls  # imported here: keeps `import sigmatau` light

    sigma = var * rel
    bounded = signed is None or not np.any(signed)
    lower = None if bounded else np.where(signed, -np.inf, 0.0)
    for it in range(iterations + 1):
        a = design / sigma[:, None]
        scale = np.linalg.norm(a, axis=0)
        scale[scale == 0] = 1.0
        if bounded:
            hs, _ = nnls(a / scale, var / sigma)
        else:
            hs = lsq_linear(a / scale, var / sigma, bounds=(lower, np.inf), method="bvls").x
        h = hs / scale
        model = design @ h
        if it < iterations:
            sigma = np.where(model > 0, model, var) * rel
    resid = (var - model) / sigma
    return h, sigma, float(np.einsum("i,i->", resid, resid))


#: Correlation of variance estimates one octave apart, by the dominant noise
#: (exponent counted from the statistic's convergence edge: α for the Allan
#: family, α + 2 for the Hadamard family). Monte-Carlo values for octave grids
#: (OADEV, ADEV, MDEV, OHDEV, N = 4096, 300 runs): ≈ 0.3–0.6 white, 0.6–0.7
#: flicker, 0.8–0.9 random walk.
OCTAVE_CORRELATION = {0: 0.5, -1: 0.7, -2: 0.88}


def _tau_correlation(taus: np.ndarray, dominant: np.ndarray) -> np.ndarray:
    """AR(1)-in-log2(τ) correlation matrix of the variance estimates."""
    rho_pt = np.array([OCTAVE_CORRELATION[max(-2, min(0, int(k)))] for k in dominant])
    octaves = np.diff(np.log2(taus))
    step = np.maximum(np.maximum(rho_pt[:-1], rho_pt[1:]) ** octaves, 1e-300)  # conservative end
    logc = np.concatenate(([0.0], np.cumsum(np.log(step))))
    return np.exp(-np.abs(logc[:, None] - logc[None, :]))


def fit_power_law(
    result: StabilityResult,
    *,
    alphas: Optional[Sequence[int]] = None,
    edf: Optional[Union[float, np.ndarray]] = None,
    min_significance: float = 2.0,
    tau_correlation: bool = True,
) -> PowerLawFit:
    """Fit the whole variance curve with non-negative power-law terms.

    Parameters
    ----------
    result : StabilityResult
        ADEV, OADEV, MDEV, TDEV, HDEV or OHDEV curve.
    alphas : sequence of int, optional
        Candidate exponents; default every one the statistic supports
        (2 … −2, and down to −4 for HDEV/OHDEV).
    edf : float or array_like, optional
        Equivalent degrees of freedom per τ; default ``result.edf`` or, without
        it, the number of non-overlapping terms ``min(n, ⌊(N−1)/m⌋)``.
    min_significance : float
        A term is kept only if ``h_α/σ(h_α)`` reaches this value.
    tau_correlation : bool
        Account for the correlation between the variance estimates at
        neighbouring τ in the uncertainties (see Notes). Off, the
        uncertainties of the long-τ terms are too small by a factor ≈ 2.

    Returns
    -------
    PowerLawFit

    Notes
    -----
    Model: ``σ²(τ) = Σ_α h_α R_α(τ)``, ``h_α ≥ 0``, with ``R_α`` the response
    of the statistic to ``S_y = f^α`` (:func:`power_law_variance`;
    f_h = rate/2 for WPM and FPM). Each τ is weighted by the standard error of
    its variance, ``σ²·√(2/ν)`` — taken from the fitted model, not the noisy
    observation, in three reweighting passes (an observation's own value would
    favour low points). The weighted system is solved by
    :func:`scipy.optimize.nnls` on scaled columns.

    Uncertainties: the estimates at neighbouring τ are strongly correlated
    (they share the slow part of the record), so the covariance of the
    coefficients is the sandwich ``B AᵀW C W A B``, ``B = (AᵀWA)⁻¹``, with
    ``C = D R D``, D the per-τ standard errors and R an AR(1) correlation in
    log₂τ whose one-octave value depends on the term dominating at that τ:
    0.5 for white, 0.7 for flicker and 0.88 for random-walk noise (counted
    from the statistic's convergence edge: FWFM and RRFM play FFM's and
    RWFM's parts for the Hadamard family). Those are Monte-Carlo values of the
    correlation of octave-spaced OADEV, ADEV, MDEV and OHDEV estimates; with
    them the z-scores of fitted levels have unit spread within about ±30 %
    (tests/test_noiseid.py). The result is multiplied by ``χ²/dof`` when that
    exceeds 1. Term selection is backward: terms at zero are dropped, then the
    least significant term while its ``h/σ(h)`` is below ``min_significance``,
    refitting each time.

    On ADEV/HDEV the WPM and FPM responses differ only by a logarithm, so
    their split is weak; fit MDEV or TDEV to separate them, or pass
    ``alphas`` without one of them.

    References
    ----------
    W. J. Riley, NIST SP 1065 (2008) §5.2 and Table 9; numerics.md §6.3;
    C. L. Lawson and R. J. Hanson, *Solving Least Squares Problems* (1974), NNLS.

    Examples
    --------
    >>> import numpy as np, sigmatau
    >>> from sigmatau.noiseid import fit_power_law
    >>> y = np.random.default_rng(3).standard_normal(20_000)   # WFM, h0 = 2
    >>> fit = fit_power_law(sigmatau.oadev(y))
    >>> fit.kept, round(fit.h[0], 1)
    ((0,), 2.0)
    """
    if not isinstance(result, StabilityResult):
        raise ParameterError(f"result must be a StabilityResult, got {type(result).__name__}")
    kind = _FIT_FAMILY.get(result.statistic)
    if kind is None:
        raise ParameterError(f"result.statistic={result.statistic!r} must be one of {sorted(_FIT_FAMILY)}")
    cand = _candidate_alphas(result.statistic, _FIT_ALPHAS[kind], alphas)
    if min_significance < 0:
        raise ParameterError(f"min_significance={min_significance!r} must be non-negative")
    taus, var, nu = _fit_points(result, edf)
    columns = {a: _response(kind, a, taus, result.rate) for a in cand}
    shift = 2 if kind == "hvar" else 0
    terms, h, err, chi2, dof, dropped = _backward_selection(
        columns, list(cand), taus, var, nu, shift, tau_correlation, min_significance)
    order = sorted(range(len(terms)), key=lambda i: -terms[i])
    kept = tuple(terms[i] for i in order)
    return PowerLawFit(
        statistic=result.statistic,
        rate=float(result.rate),
        h={terms[i]: float(h[i]) for i in order},
        h_err={terms[i]: float(err[i]) for i in order},
        kept=kept,
        dropped=tuple(sorted(dropped, reverse=True)),
        chi2=chi2,
        dof=dof,
        taus=taus,
    )


def _candidate_alphas(statistic: str, supported: Sequence[int], alphas: Optional[Sequence[int]]) -> list[int]:
    """The exponents :func:`fit_power_law` starts from: ``alphas`` checked and de-duplicated, else all supported."""
    if alphas is None:
        return list(supported)
    cand: list[int] = []
    for a in alphas:
        if isinstance(a, (bool, np.bool_)) or not isinstance(a, (int, np.integer)) or int(a) not in supported:
            raise ParameterError(f"alphas contains {a!r}; {statistic} supports {list(supported)}")
        if int(a) not in cand:
            cand.append(int(a))
    if not cand:
        raise ParameterError("alphas must name at least one exponent")
    return cand


def _fit_points(result: StabilityResult,
                edf: Optional[Union[float, np.ndarray]]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """τ, variance and EDF of the points fitted: those with a positive, finite variance and EDF."""
    taus = np.asarray(result.taus, dtype=float)
    var = np.asarray(result.var, dtype=float)
    if edf is not None:
        nu = np.broadcast_to(np.asarray(edf, dtype=float), taus.shape).copy()
    elif result.edf is not None:
        nu = np.asarray(result.edf, dtype=float).copy()
    else:
        nu = _independent_terms(result)
    ok = (var > 0) & np.isfinite(var) & (nu > 0) & np.isfinite(nu)
    taus, var, nu = taus[ok], var[ok], nu[ok]
    if taus.size < 2:
        raise DataError(f"fit_power_law needs at least 2 τ with a positive variance, got {taus.size}")
    return taus, var, nu


def _backward_selection(columns: Mapping[int, np.ndarray], terms: list[int], taus: np.ndarray,
                        var: np.ndarray, nu: np.ndarray, shift: int, tau_correlation: bool,
                        min_significance: float) -> tuple[list[int], np.ndarray, np.ndarray, float, int, list[int]]:
    """Refit, dropping terms at zero and then the least significant one, until all are kept.

    Returns
    -------
    terms : list of int
        Kept exponents, in fitting order.
    h, err : numpy.ndarray
        Their levels and standard uncertainties.
    chi2 : float
    dof : int
    dropped : list of int
        Dropped exponents, in the order they were dropped.
    """
    dropped: list[int] = []
    while True:
        design = np.column_stack([columns[a] for a in terms])
        h, sigma, chi2 = irls_fit(design, var, np.sqrt(2.0 / nu), iterations=3)
        pos = h > 0
        if not pos.any():
            raise DataError("no power-law term fits this curve")
        if not pos.all():
            dropped += [a for a, p in zip(terms, pos) if not p]
            terms = [a for a, p in zip(terms, pos) if p]
            continue
        dof = int(taus.size - len(terms))
        err = _level_errors(design, sigma, h, terms, taus, shift, tau_correlation, chi2, dof)
        with np.errstate(divide="ignore"):
            z = np.where(err > 0, h / err, np.inf)
        worst = int(np.argmin(z))
        if z[worst] < min_significance and len(terms) > 1:
            dropped.append(terms.pop(worst))
            continue
        return terms, h, err, chi2, dof, dropped


def _level_errors(design: np.ndarray, sigma: np.ndarray, h: np.ndarray, terms: list[int], taus: np.ndarray,
                  shift: int, tau_correlation: bool, chi2: float, dof: int) -> np.ndarray:
    """Standard uncertainties of the levels ``h``: the sandwich covariance of :func:`fit_power_law`'s Notes."""
    aw = design / sigma[:, None]
    bread = np.linalg.pinv(aw.T @ aw)
    if tau_correlation:
        dominant = np.array(terms)[np.argmax(design * h, axis=1)] + shift
        corr = _tau_correlation(taus, dominant)
        cov = bread @ (aw.T @ corr @ aw) @ bread
    else:
        cov = bread
    if dof > 0:
        cov *= max(1.0, chi2 / dof)
    return np.sqrt(np.clip(np.diag(cov), 0.0, None))
