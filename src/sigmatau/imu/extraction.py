"""Extract the IMU noise model of one channel: :func:`analyze` and :func:`from_curve`.

:func:`analyze` is a composition of named steps: check the options
(``_check_options``), get the OADEV curve from the samples with the data
checks (``_curve_of_samples``) or validate a given curve (``_check_result``),
settle the EDF of each τ (``_usable_points``), fit the model
(:mod:`~sigmatau.imu.fitting`), read the terms off the curve
(:mod:`~sigmatau.imu.readoffs`), compare both (``_compare``), add the model's own
flags (``_model_flags``) and warn (``_warn_flags``).

``analyze`` itself stays longer than the ~80-line goal: its docstring (~150
lines) is the method's public reference (``help()``, the API documentation), and
splitting it would scatter the description of one computation; its body is a
short composition of the steps above.
"""

from __future__ import annotations

import math
import warnings
from typing import Any, Literal, Mapping, Optional, Sequence, Union

import numpy as np

from ..core.result import StabilityResult
from ..core.validate import as_series, check_rate
from ..errors import DataError, ParameterError, caller_stacklevel
from ..stats.allan import oadev
from ..uncertainty.confidence import ONE_SIGMA, edf_array, white_mixture_edf
from . import checks as checks_module
from .checks import DataChecks, check_samples
from .fitting import _Fit, _fit_model, _fit_parameters, _selection_aware_bounds, _selection_aware_intervals
from .gaussmarkov import GM_MODES, _choose, _Choice, _gm_result
from .noisemodel import NoiseModel
from .readoffs import _curve_bound, _readoffs
from .results import Flag, Parameter, Region
from .terms import _NAMES, ImuWarning, _design, _gm_column
from .units import TERMS, SensorUnit, pretty, sensor_unit

__all__ = ["analyze", "from_curve", "DEVIATION_RANGE"]

#: Deviations (sample unit) within which the model's fit and covariance are computed in float64:
#: the covariance of c = σ² terms goes as the fourth power of the data's scale.
DEVIATION_RANGE = (1e-60, 1e60)


def from_curve(taus: Sequence[float], dev: Sequence[float], *, rate: float, n_samples: int,
               statistic: Literal["oadev", "adev"] = "oadev") -> StabilityResult:
    """Wrap an Allan-deviation curve computed elsewhere as a :class:`StabilityResult`.

    Parameters
    ----------
    taus, dev : array_like
        Averaging times (s) and deviations.
    rate : float
        Sample rate of the data behind the curve (Hz); ``m = round(τ·rate)``.
    n_samples : int
        Number of samples behind the curve (sets the EDF). When unknown, a
        lower bound keeps the intervals conservative.
    statistic : {"oadev", "adev"}
        Overlapping (default) or non-overlapping estimator.

    Returns
    -------
    StabilityResult
        Without EDF: :func:`analyze` fills it from the noise type its fit finds
        at each τ.

    Examples
    --------
    >>> from sigmatau.imu import from_curve
    >>> r = from_curve([0.01, 0.1, 1.0], [1e-3, 3.2e-4, 1e-4], rate=100.0, n_samples=100000)
    >>> r.m.tolist()
    [1, 10, 100]
    """
    rate_f = check_rate(rate)
    t = as_series(taus, "taus")
    d = as_series(dev, "dev")
    if t.size != d.size:
        raise DataError(f"taus ({t.size}) and dev ({d.size}) must have the same length")
    if np.any(t <= 0) or np.any(np.diff(t) <= 0) or np.any(d < 0):
        raise DataError("taus must be positive and increasing, dev non-negative")
    if statistic not in ("oadev", "adev"):
        raise ParameterError(f"statistic={statistic!r} must be 'oadev' or 'adev'")
    if isinstance(n_samples, bool) or not isinstance(n_samples, (int, np.integer)) or n_samples < 3:
        raise ParameterError(f"n_samples={n_samples!r} must be an integer >= 3")
    m = np.maximum(1, np.round(t * rate_f)).astype(np.int64)
    if np.any(2 * m > n_samples):
        raise DataError(f"τ up to {t[-1]:g} s needs more than n_samples={n_samples} samples")
    n_terms = n_samples + 1 - 2 * m if statistic == "oadev" else (n_samples // m) - 1
    return StabilityResult(statistic=statistic, taus=t, m=m, var=d * d, dev=d, n=n_terms, rate=rate_f,
                           data_type="freq", n_points=int(n_samples) + 1)


def analyze(
    samples: Union[StabilityResult, Sequence[float], np.ndarray],
    *,
    rate: Optional[float] = None,
    unit: str,
    scale: float = 1.0,
    increments: bool = False,
    taus: Any = "octave",
    confidence: float = ONE_SIGMA,
    terms: Sequence[str] = TERMS,
    min_significance: float = 3.0,
    checks: bool = True,
    lsb: Optional[float] = None,
    odr: Optional[float] = None,
    full_scale: Optional[float] = None,
    gauss_markov: Literal["auto", "never", "always"] = "auto",
) -> NoiseModel:
    """Extract the IMU noise model (Q, N, B, K, R) of one channel, with intervals.

    Parameters
    ----------
    samples : array_like or StabilityResult
        Static-log samples of one axis (rate for a gyroscope, specific force for
        an accelerometer), or an OADEV/ADEV curve already computed (with
        :func:`sigmatau.oadev` or :func:`from_curve`).
    rate : float
        Sample rate in Hz (taken from the result when one is given).
    unit : str
        Unit of the samples (after ``scale``), required: ``"rad/s"``,
        ``"deg/s"``, ``"deg/h"``, ``"mdps"``, ``"m/s^2"``, ``"g"``, ``"mg"`` …
        (:func:`sigmatau.units.sensor_unit`). It sets the sensor kind and the
        unit of every parameter; there is no default, so a wrong unit cannot
        slip through silently.
    scale : float
        Factor from raw samples (e.g. counts) to ``unit``.
    increments : bool
        The samples are delta-angle / delta-velocity increments per sample (in
        ``unit``·s); they are divided by τ0.
    taus : {"octave", "log", …} or array_like
        τ grid of the OADEV curve (see :func:`sigmatau.oadev`).
    confidence : float
        Two-sided coverage of the intervals (default ±1σ, 0.683).
    terms : sequence of str
        Terms of the model to consider (default all five).
    min_significance : float
        The fit keeps a term only if its squared coefficient is at least this
        many standard errors above zero.
    checks : bool
        Run :func:`sigmatau.checks.check_samples` (raw samples only).
    lsb, odr, full_scale : float, optional
        Passed to the data checks (known LSB, the sensor's own output rate,
        its full scale), all in ``unit``.
    gauss_markov : {"auto", "never", "always"}
        A first-order Gauss–Markov term (σ_GM, T_c) beside the five: kept when
        the Bayesian information criterion favours it by a clear margin
        (``"auto"``), never considered (``"never"``: the five-term model alone),
        or always fitted (``"always"``). See *Gauss–Markov* below.

    Returns
    -------
    NoiseModel

    Notes
    -----
    *Curve.* OADEV of the samples with χ² intervals from the Greenhall EDF at
    the noise type identified at each τ (:func:`sigmatau.oadev`, ``ci="chi2"``).
    A first fit gives the term dominant at each τ; the EDF under that noise
    type fills the τ without one (a curve given without EDF) and, where it is
    smaller than the EDF of the identified type, replaces it (the
    identification is unreliable with the few averages of the longest τ).

    *Read-offs.* The local log–log slope at each τ is the EDF-weighted
    regression slope over ±0.31 decade (widened up to ±0.81 decade where its
    standard error exceeds 0.1). A term's region is the longest run of τ where
    that slope is within ±0.15 of the term's slope with a standard error ≤ 0.2,
    spanning at least an octave (two for B, whose flat bottom must be wider
    than the ≈1.2 octaves over which the crossing of a −½ and a +½ line looks
    flat). A line of the fixed slope is fitted to ln σ and read at the term's τ
    (N at 1 s, K at 3 s, Q at √3 s, R at √2 s; B = level/0.6643), with EDF
    weights tapered by ``exp(−(δ/0.05)²)`` for a point whose slope is δ off.
    Its interval is the χ² interval of the effective EDF ``1/(2·var ln σ̂)``
    of that weighted mean, correlated τ accounted for (see *Fit*), widened on
    both sides by the weighted mean of ``|½ ln(1 − 2δ)|``: the offset from the
    line of a point that holds a share 2δ of a neighbouring term (or sits under
    a filter). That is the rule without a fit; :func:`analyze` first subtracts
    from each point of the region the share of the other terms of the
    unconstrained fit (below), ``net = σ² − Σ_{k≠term} A_k c_k``, leaves out the
    points where that share exceeds ¾, reads the line through ``½ ln net`` with
    weights ``ν/(σ²/net)²`` and adds the propagated covariance of the
    subtracted coefficients to the variance of the level (no widening then).
    The flat region of B holds N²/τ and K²τ/3 as well: without the subtraction
    its read-off came out 1.1–1.3× the truth. *Bound rule* when no region exists: the lowest one-sided upper
    limit of σ(τ) over the k τ of the curve, each at level ``1 − (1 − p)/(2k)``
    (so that the bound holds in at least ``(1 + p)/2`` of records however the lowest
    point was picked), carried along the term's slope to its read-off τ: in
    practice the longest τ for K and R, the shortest for Q and N, the lowest
    point for B (σ_min/0.6643). It is conservative by construction: it bounds
    the whole curve, of which the term is only a share, and the Bonferroni
    share ignores the correlation of neighbouring τ (it held in 97–100 % of
    the simulated records of ``tests/test_imu_coverage.py``, nominal 84.1 %).

    *Fit.* ``σ²(τ) = 3Q²/τ² + N²/τ + (2 ln 2/π)B² + K²(τ/3 + τ0²/(6τ)) + R²τ²/2``
    (the random-walk column is exact for point samples), weighted least
    squares with weights from the model variance's standard error
    ``σ²·√(2/ν)`` (three reweighting passes; ν the EDF of the noise that dominates
    at each τ, or, where Q and N hold 90 % of the AVAR, the exact EDF of their
    mixture, :func:`sigmatau.confidence.white_mixture_edf`), the squared coefficients
    non-negative except that of 3/τ²: a negative one is the sensor's low-pass
    filter, ``AVAR ≈ N²/τ·(1 − τ_f/τ)`` at the shortest τ, reported as
    ``filter_time`` and flagged (Q is then masked). When the full model leaves
    a χ² beyond the 10⁻⁴ tail of its distribution (a scaled χ² with the mean
    ``tr M`` and variance ``2 tr M²``, ``M = (I − H)C(I − H)ᵀ``, of residuals
    correlated across τ as modelled) — a real curve with features the model
    lacks — a relative discrepancy ε per τ is added in quadrature to every
    point's uncertainty, chosen to bring χ² to its expectation, and flagged.
    The covariance is the sandwich
    ``B AᵀW C W A B`` with the correlation of the variance estimates at
    neighbouring τ: one octave apart 0.5 (white), 0.7 (flicker), 0.88
    (random walk), as in :func:`sigmatau.noiseid.fit_power_law`, decaying as
    ``ρ₁^(Δ^1.5)`` with the distance Δ in octaves (Monte Carlo; see
    ``_correlation``), scaled by χ²/dof when above 1. Term selection is
    backward: terms at zero are dropped, then the least significant
    (``|c|/σ_c``) while below ``min_significance`` or while no degree of
    freedom is left — except a term whose removal would put χ² beyond that
    10⁻⁴ tail and double it: the curve needs it. Two terms that share a region
    (K and R at the end of the record) are each weak given the other, and one
    of them may be dropped although the curve supports both (a
    likelihood-ratio rule, Δχ² > ``min_significance²``, kept both in 22 of 30
    such records but a spurious B in 1 of 50 EuRoC accelerometer records, so
    it is not used); the intervals below do not depend on that choice. *Intervals* come from a second,
    unconstrained fit of every term (coefficients of either sign, same weights
    and sandwich covariance, not scaled): free of selection and of the
    non-negativity bound, its ``ĉ`` is unbiased and its ``σ_c`` holds for
    terms that share a region, where the selected model's covariance is too
    small (a kept K absorbed a dropped R and covered in 23–53 % of runs).
    Both kinds of statement are conditional on the selection, which keeps a
    term exactly when its estimate came out high and drops it when it came out
    low: statements built as if the term had not been selected over-cover
    among the runs that keep it (kept K and R: 74–86 % at 68.3 %, values
    1.2–1.8× the truth) and fall short among those that drop it (69 of 101
    instead of 84 % for the K of N+B+K+R). In the
    fit's linearised Gaussian model of the AVAR points, ``v ~ N(Ac, V)`` with
    ``V`` the modelled covariance above, the unconstrained ``ĉ = g·v`` and the
    part of the data independent of it, ``u = v − bĉ`` (``b = Vgᵀ/gVgᵀ``),
    separate; given ``u`` the selection keeps the term exactly when
    ``ĉ > t*(u)``, found by rerunning the selection on ``u + bt``. Given the
    keep, ``ĉ`` is a normal truncated below at ``t*``; with
    ``S(c) = Φ((c − ĉ)/s(c)) / Φ((c − t*)/s(c))``, the probability under ``c``
    of an estimate at least ``ĉ`` given the keep, a kept term's interval on
    ``c = P²`` is ``[L, U]`` with ``S(L) = (1 − p)/2`` and ``S(U) = (1 + p)/2``
    (``L`` clipped at 0), and its value the median-unbiased ``S(ĉ₅₀) = ½``
    (Lee, Sun, Sun & Taylor 2016; Fithian, Sun & Taylor 2014). A term kept
    whatever its estimate (``t* = −∞``: N in most records) has no selection to
    account for: its interval is ``[max(ĉ − zσ_c, 0), ĉ + zσ_c]`` (z for the
    two-sided level) widened to include the selected model's value, which is
    its value (the more precise: N's scatter is 1.7× smaller than the
    unconstrained fit's when terms are absent). When ``U ≤ 0`` (an estimate at the edge,
    which the truncated normal explains by a true value far below it: 1–7 % of
    the kept K and R) the interval not conditioned on the selection is given
    instead, and where the median is not positive the value is ``ĉ``, capped at
    ``U``. The value of a term the selection could have dropped is thus not the
    selected model's, which is the model drawn over the curve (``fit_terms``,
    the figure): there a term dropped beside it adds its share to it. Given the
    drop, ``ĉ`` is a normal truncated above at ``t*``, and a dropped term's
    upper bound ``U`` on ``c``, holding at ``(1 + p)/2`` given the drop, solves
    ``Φ((ĉ − U)/s(U)) = ((1 − p)/2)·Φ((t* − U)/s(U))``
    (when ``U ≤ 0``, the ``U``
    of ``ĉ = 0``, since ``c ≥ 0``). In both, the spread ``s(c)``
    of ``ĉ`` is evaluated at the candidate value, as in a score (Wilson)
    interval: the scatter of an AVAR point grows with its level, so a spread
    taken at a low estimate is too small exactly in the runs that drop the
    term, and one taken at a high estimate too large in the runs that keep it.
    When no finite ``U`` solves it (a term carried by a few points that
    scatter as much as their level), or when it is lower, the *bound rule* of
    the read-offs applied to the whole curve is printed instead: no term's line
    can lie above every point of the curve.

    *Gauss–Markov.* A first-order GM process (variance σ², correlation time
    T) adds ``σ²·(2T/τ)[1 − (T/2τ)(3 − 4e^(−τ/T) + e^(−2τ/T))]`` (exact form of
    the sampled process: :func:`sigmatau.imu.gaussmarkov.gauss_markov_avar`).
    The fit is linear in σ² and profiled over T on a log grid spanning the τ of
    the curve (20 per decade, then refined); the five-term model and five terms
    + GM (both without discrepancy floor) are compared by
    ``BIC = χ²·ν/E[χ²] + k·ln n_eff`` (χ² scaled to its Satterthwaite EDF ν,
    ``n_eff = ν + p``), the GM costing two parameters; it is kept when ΔBIC >
    10 and its T is not at an end of the grid, and (with ``"auto"``) only if
    the white noise N stays in the model: white noise through a first-order
    low-pass filter is itself a GM process, which would otherwise replace N on
    filtered sensors. The chosen model is then fitted
    as above (discrepancy, selection, the unconstrained fit behind every
    interval, so that N, B and K trade off against the GM term in their
    intervals). σ_GM's interval is from that fit's covariance at the chosen T,
    T_c's from the profile of the chosen model's scaled χ² (Δ below the χ²₁
    quantile). The read-offs are taken on the curve with the GM share
    subtracted.

    *Comparison.* Read-off and fit intervals that do not overlap, or a term
    resolved by one method above the other's bound, are flagged; so are
    unresolved terms, quantisation and other data problems, the filter term
    and a discrepancy floor. :class:`ImuWarning` is issued for disagreements,
    model discrepancy and an unresolved N or K (Q, B and R are unresolved in
    most records; their flags are enough).

    References
    ----------
    IEEE Std 952-1997 Annex C and IEEE Std 1554-2005 (Allan-variance noise
    terms); ST DT0064 ("Gyroscope noise"); N. El-Sheimy, H. Hou, X. Niu, IEEE
    Trans. Instrum. Meas. 57(1) (2008) 140–149; numerics.md §2, §3, §6.
    Selection-aware bounds: J. D. Lee, D. L. Sun, Y. Sun, J. E. Taylor, "Exact
    post-selection inference, with application to the lasso", Ann. Statist.
    44(3) (2016) 907–927; W. Fithian, D. L. Sun, J. E. Taylor, "Optimal
    inference after model selection", arXiv:1410.2597 (2014); E. B. Wilson,
    J. Am. Stat. Assoc. 22 (1927) 209–212 (the spread at the candidate value).

    Examples
    --------
    >>> from sigmatau.imu import simulate, analyze
    >>> y = simulate("euroc-gyro", duration=1800.0, rng=4)
    >>> model = analyze(y, rate=200.0, unit="rad/s")
    >>> round(model.N.value / 1.6968e-4, 2), model.N.resolved
    (1.0, True)
    >>> model.B.resolved, model.Q.resolved
    (False, False)
    """
    su, conf, terms = _check_options(unit, confidence, terms, min_significance)
    if gauss_markov not in GM_MODES:
        raise ParameterError(f"gauss_markov={gauss_markov!r} must be one of {GM_MODES}")
    if isinstance(samples, StabilityResult):
        result = samples
        rate_f, n_samples = _check_result(result, rate)
        data_checks: Optional[DataChecks] = None
        flags: list[Flag] = []
    else:
        result, rate_f, n_samples, data_checks, flags = _curve_of_samples(
            samples, rate=rate, unit=unit, scale=scale, increments=increments, taus=taus, conf=conf,
            checks=checks, lsb=lsb, odr=odr, full_scale=full_scale)
    if len(result) < 3:
        raise DataError(f"the curve has {len(result)} τ; the model needs at least 3 (a longer record)")
    _check_deviation_range(np.asarray(result.dev, float))
    t_s, d_s, nu_s = _usable_points(result, rate_f, terms, min_significance)

    fit, choice = _fit_with_gm(t_s, d_s**2, nu_s, rate_f, terms, min_significance, gauss_markov)
    gm = _gm_result(t_s, d_s**2, nu_s, rate_f, fit, choice, conf, su, gauss_markov) if choice.chosen else None
    ro_t, ro_d, ro_nu, ro_gain, ro_vcov = _without_gm(fit, t_s, d_s, nu_s, rate_f)
    readoff, regions = _readoffs(ro_t, ro_d, ro_nu, conf, su, terms, rate_f, fit.full_coef[:5], ro_gain, ro_vcov)
    dropped = _selection_aware_bounds(fit, t_s, d_s**2, nu_s, rate_f, terms, min_significance, conf)
    caps = {t: _curve_bound(t, ro_t, ro_d, ro_nu, conf, su) for t in dropped}
    kept = _selection_aware_intervals(fit, t_s, d_s**2, nu_s, rate_f, terms, min_significance, conf)
    fitted = _fit_parameters(fit, conf, su, terms, t_s, kept, dropped, caps)
    primary = _primary(fitted, su, conf)
    flags += _compare(readoff, fitted, regions, t_s)
    flags += _model_flags(fit, data_checks, primary, su)
    _warn_flags(flags)
    return NoiseModel(
        kind=su.kind, unit=su.name, rate=rate_f, n_samples=n_samples, confidence=conf,
        readoff=readoff, fit=fitted, regions=regions, fit_terms=fit.kept, fit_chi2=fit.chi2, fit_dof=fit.dof,
        discrepancy=fit.eps, filter_time=fit.filter_time,
        flags=tuple(flags), checks=data_checks, result=result, _coef=fit.coef[:5], _cov=fit.cov[:5, :5],
        gauss_markov=gm, gauss_markov_test=_gm_test(choice, gauss_markov, gm),
        _gm=(float(fit.coef[5]), fit.gm_tau) if gm is not None and gm.resolved else None,
        **primary,
    )


def _fit_with_gm(taus: np.ndarray, var: np.ndarray, nu: np.ndarray, rate: float, terms: Sequence[str],
                 min_significance: float, mode: str) -> tuple[_Fit, _Choice]:
    """The fit of the model chosen by :func:`~sigmatau.imu.gaussmarkov._choose`: five terms + GM when
    the GM wins (and survives term selection), the five-term fit exactly as without the option otherwise."""
    if mode == "never":
        return _fit_model(taus, var, nu, rate, terms, min_significance), _Choice(
            math.nan, False, math.nan, math.nan, "gauss_markov='never'")
    choice = _choose(taus, var, nu, rate, terms, mode)  # type: ignore[arg-type]
    if choice.chosen:
        fit = _fit_model(taus, var, nu, rate, terms, min_significance, gm_tau=choice.tau)
        if mode == "always":
            return fit, choice
        if "GM" not in fit.kept:
            choice = choice._replace(chosen=False, reason=choice.reason + "; then dropped by term selection")
        elif "N" in terms and "N" not in fit.kept:
            # White noise through a first-order low-pass filter is a GM process: a GM term that
            # takes the place of N is the sensor's filter (real accelerometer curves: T_c of
            # ~14 samples, N dropped), which the five-term model holds as N and its 1/τ² term.
            choice = choice._replace(chosen=False, reason=(
                choice.reason + f"; rejected: the GM term (T_c = {choice.tau:.3g} s) replaces the white"
                " noise N (filtered white noise is a GM process), N is kept instead"))
        else:
            return fit, choice
    return _fit_model(taus, var, nu, rate, terms, min_significance), choice


def _without_gm(fit: _Fit, taus: np.ndarray, dev: np.ndarray, nu: np.ndarray, rate: float
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The curve the read-offs see: with a kept GM term, its share subtracted from each point's AVAR,
    the points where it holds more than ¾ left out (as the read-offs leave out those of a neighbouring
    term) and the EDF scaled by ``(net/σ²)²`` (same absolute variance, smaller level).

    Returns ``(taus, dev, nu, gain, var_cov)`` of the points kept, the last two the fit's linear map to
    the five coefficients and the modelled covariance of the points, restricted to them.
    """
    gain, vcov = fit.full_gain[:5], fit.var_cov
    if "GM" not in fit.kept:
        return taus, dev, nu, gain, vcov
    var = dev**2
    net = var - fit.coef[5] * _gm_column(taus, rate, fit.gm_tau)
    keep = net > 0.25 * var
    if keep.sum() < 3:
        return taus, dev, nu, gain, vcov
    return (taus[keep], np.sqrt(net[keep]), nu[keep] * (net[keep] / var[keep]) ** 2, gain[:, keep],
            vcov[np.ix_(keep, keep)])


def _gm_test(choice: _Choice, mode: str, gm: Any) -> dict[str, Any]:
    """What was decided about a Gauss–Markov term, for results.json (also when it was not kept)."""
    return {"mode": mode, "criterion": "BIC", "chosen": gm is not None and gm.resolved,
            "delta_bic": None if not math.isfinite(choice.delta_bic) else float(choice.delta_bic),
            "n_eff": None if not math.isfinite(choice.n_eff) else float(choice.n_eff),
            "tau_c_best": None if not math.isfinite(choice.tau) else float(choice.tau),
            "reason": choice.reason}


def _check_options(unit: str, confidence: float, terms: Sequence[str], min_significance: float
                   ) -> tuple[SensorUnit, float, tuple[str, ...]]:
    """The sensor unit, the confidence as a float and the terms as a tuple, each checked."""
    su = sensor_unit(unit)
    conf = float(confidence)
    if not 0.0 < conf < 1.0:
        raise ParameterError(f"confidence={confidence!r} must be in (0, 1)")
    terms = tuple(terms)
    if not terms or any(t not in TERMS for t in terms) or len(set(terms)) != len(terms):
        raise ParameterError(f"terms={terms!r} must be distinct names among {TERMS}")
    if isinstance(min_significance, bool) or not float(min_significance) >= 0:
        raise ParameterError(f"min_significance={min_significance!r} must be a non-negative number")
    return su, conf, terms


def _check_result(result: StabilityResult, rate: Optional[float]) -> tuple[float, int]:
    """Rate and number of samples of a given OADEV/ADEV curve of rate samples (checked)."""
    if result.statistic not in ("oadev", "adev"):
        raise ParameterError(f"the result must be an OADEV or ADEV curve, got {result.statistic!r}")
    if result.data_type != "freq":
        raise ParameterError("the result must come from rate (frequency-type) samples, data_type='freq'")
    if rate is not None and abs(check_rate(rate) - result.rate) > 1e-9 * result.rate:
        raise ParameterError(f"rate={rate!r} differs from the result's rate {result.rate:g} Hz")
    return float(result.rate), int(result.n_points - 1)


def _curve_of_samples(samples: Any, *, rate: Optional[float], unit: str, scale: float, increments: bool,
                      taus: Any, conf: float, checks: bool, lsb: Optional[float], odr: Optional[float],
                      full_scale: Optional[float]
                      ) -> tuple[StabilityResult, float, int, Optional[DataChecks], list[Flag]]:
    """OADEV curve of raw samples (scaled, increments turned into rates), after the data checks.

    Returns
    -------
    result, rate, n_samples, data_checks, flags
        The curve (χ² intervals), the rate, the number of samples, the data
        checks (None when ``checks`` is false) and the flags they raise.
    """
    if rate is None:
        raise ParameterError("rate (Hz) is required with raw samples")
    rate_f = check_rate(rate)
    if isinstance(scale, bool):
        raise ParameterError(f"scale={scale!r} must be a positive number")
    sc = float(scale)
    if not (math.isfinite(sc) and sc > 0):
        raise ParameterError(f"scale={scale!r} must be a positive number")
    y = as_series(samples, "samples", gaps=True)  # NaN: missing samples, gaps every statistic skips
    if sc != 1.0:  # at scale 1 the caller's own array goes on (read, never written), shared with the
        y = y * sc  # other statistics of its channel (sigmatau.core.shared)
    if increments:
        y = y * rate_f
    n_samples = int(y.size)
    if n_samples < 16:
        raise DataError(f"an IMU noise model needs at least 16 samples, got {n_samples}")
    data_checks: Optional[DataChecks] = None
    flags: list[Flag] = []
    if checks:
        # warn=False and re-issued here (not catch_warnings): the warning filters are
        # process-wide, and channels are analysed in threads (analysis.analyze_log).
        data_checks = check_samples(y, rate=rate_f, unit=unit, lsb=None if lsb is None else lsb,
                                    odr=odr, full_scale=full_scale, warn=False)
        for cls_name, msg in data_checks.warned:
            # stacklevel 3: the caller of analyze(), as before this step was split out
            warnings.warn(msg, getattr(checks_module, cls_name), stacklevel=caller_stacklevel())
        for cls, msg in data_checks.warned:
            quantized = cls == "QuantizationWarning"
            flags.append(Flag("quantized" if quantized else "data", "N" if quantized else "", msg))
    if np.nanmax(y) == np.nanmin(y):
        raise DataError("all samples are equal: no noise to analyse")
    result = oadev(y, rate=rate_f, taus=taus, confidence=conf, ci="chi2")
    return result, rate_f, n_samples, data_checks, flags


def _usable_points(result: StabilityResult, rate_f: float, terms: Sequence[str], min_significance: float
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """τ, deviation and EDF of the points the model is extracted from (σ > 0, EDF > 0).

    The EDF is that under the noise type a first fit finds dominant at each τ.
    It fills the τ without an identified type, and where the identification
    says otherwise the smaller EDF is kept: at the longest τ, with a handful of
    averages, the identification is unreliable and an overstated EDF would
    make the few points there look more precise than they are.
    """
    taus_a = np.asarray(result.taus, float)
    dev = np.asarray(result.dev, float)
    good = dev > 0
    if result.edf is not None:
        nu = np.asarray(result.edf, float).copy()
    else:
        nu = np.full(taus_a.size, np.nan)
    missing = ~(np.isfinite(nu) & (nu > 0))
    first = np.where(missing, np.maximum(result.n_points / np.maximum(result.m, 1) - 1.0, 1.0), nu)
    pre = _fit_model(taus_a[good], dev[good] ** 2, first[good], rate_f, terms, min_significance)
    alpha = np.zeros(taus_a.size)
    alpha[good] = pre.dominant
    nu_model = _model_edf(result, alpha)
    ok_model = np.isfinite(nu_model) & (nu_model > 0)
    nu = np.where(missing, nu_model, np.where(ok_model, np.minimum(nu, nu_model), nu))
    nu = np.where(np.isfinite(nu) & (nu > 0), nu, first)
    nu[good] = _white_edf(result, good, nu[good], pre.coef, rate_f)
    sel = good & np.isfinite(nu) & (nu > 0)
    return taus_a[sel], dev[sel], nu[sel]


#: Share of the model's AVAR that white PM (Q) and white FM (N) must hold together at a τ for its EDF
#: to be their mixture's (:func:`_white_edf`).
_WHITE_SHARE = 0.9


def _white_edf(result: StabilityResult, good: np.ndarray, nu: np.ndarray, coef: np.ndarray, rate_f: float
               ) -> np.ndarray:
    """The EDF ``nu`` of the points ``good`` of ``result``, replaced by the white noises' exact one
    where Q and N hold at least ``_WHITE_SHARE`` of the model AVAR ``coef`` (the first fit's).

    The dominant type's EDF treats a point where Q and N share the variance as if one noise held it
    all; their contributions are only partly correlated, so the point scatters less
    (:func:`sigmatau.confidence.white_mixture_edf`, exact for white PM + white FM; the
    exact EDF of white FM alone is also 15 % below to 10 % above Greenhall–Riley's at m ≤ 8). With Q
    in the model the σ of N came out 1.23–1.35× its scatter, and its interval covered in
    77.5–82.5 % of 200 records (68.3 % nominal; two sets of seeds). The other terms' share
    ``1 − W`` (at most a tenth) keeps the point's previous EDF ν and is added as fully correlated
    with the white part, an upper bound on its scatter: ``2/ν' = (W·√(2/ν_W) + (1 − W)·√(2/ν))²``.
    """
    if not np.any(good):  # the curve is an OADEV or ADEV one (_check_result, _curve_of_samples)
        return nu
    taus = np.asarray(result.taus, float)[good]
    parts = _design(taus, rate_f) * np.maximum(np.asarray(coef, float)[:5], 0.0)
    model = parts.sum(axis=1)
    white = parts[:, 0] + parts[:, 1]
    share = np.divide(white, model, out=np.zeros_like(model), where=model > 0)
    use = (share >= _WHITE_SHARE) & np.isfinite(nu) & (nu > 0)
    if not np.any(use):
        return nu
    m = np.asarray(result.m, np.int64)[good][use]
    # With gaps, each τ's EDF is that of the contiguous record giving its number of terms.
    points = (np.full(m.size, float(result.n_points)) if result.n_effective is None
              else np.asarray(result.n_effective, float)[good][use])
    pm = parts[use, 0] / white[use]
    nu_w = np.array([float(white_mixture_edf(result.statistic, int(mi), int(ni), float(wi)))
                     if math.isfinite(ni) and ni >= 2 else math.nan for mi, ni, wi in zip(m, points, pm)])
    w = share[use]
    rel = w * np.sqrt(2.0 / nu_w) + (1.0 - w) * np.sqrt(2.0 / nu[use])
    out = nu.copy()
    out[use] = np.where(np.isfinite(nu_w) & (nu_w > 0), 2.0 / rel**2, nu[use])
    return out


def _primary(fitted: Mapping[str, Parameter], su: SensorUnit, conf: float) -> dict[str, Parameter]:
    """The five parameters of the model: the fit's, or an "excluded" placeholder for a term left out."""
    primary = {}
    for t in TERMS:
        if t in fitted:
            primary[t] = fitted[t]
        else:
            primary[t] = Parameter(t, math.nan, 0.0, math.inf, su.term_unit(t), False, "excluded", conf, su.kind,
                                   note="excluded by terms=")
    return primary


def _model_flags(fit: _Fit, data_checks: Optional[DataChecks], primary: Mapping[str, Parameter],
                 su: SensorUnit) -> list[Flag]:
    """Flags of the fit itself: a discrepancy floor, a low-pass filter term, and a quantiser
    floor that holds more than a tenth of N²."""
    flags = []
    if fit.eps > 0:
        gm = "GM" in fit.kept
        flags.append(Flag("model", "", (
            f"the curve departs from the {'five-term + Gauss–Markov' if gm else 'five-term'} model beyond its"
            f" statistical scatter (χ²/dof {fit.raw_chi2_dof:.3g}): "
            + ("a second correlated term, " if gm else "a Gauss–Markov hump, ")
            + "a sinusoid, filtering, temperature drift or"
            f" non-stationarity? A discrepancy of {100 * fit.eps:.2g} % per τ was added to the uncertainty of"
            " every point, which widens the intervals")))
    if fit.filter_time > 0:
        flags.append(Flag("data", "Q", (
            f"the shortest τ lie below the white-noise line, AVAR ≈ N²/τ·(1 − τ_f/τ) with τ_f ="
            f" {fit.filter_time:.3g} s: the sensor's low-pass (anti-alias) filter; quantisation Q cannot be"
            " measured under it")))
    if data_checks is not None and data_checks.quantization_density is not None and primary["N"].resolved:
        qd = data_checks.quantization_density
        share = (qd / primary["N"].value) ** 2
        if share > 0.1:
            flags.append(Flag("quantized", "N", (
                f"the quantiser's white floor LSB/√(12f) = {qd:.3g} {pretty(su.term_unit('N'))} is"
                f" {100 * share:.2g} % of N² (N without it:"
                f" {math.sqrt(max(primary['N'].value ** 2 - qd ** 2, 0)):.3g})")))
    return flags


def _warn_flags(flags: Sequence[Flag]) -> None:
    """Issue :class:`ImuWarning` for the flags a user must not miss (stacklevel: the caller of analyze)."""
    for f in flags:
        # Q, B and R are unresolved in most records: the flag is enough. N and K
        # feed navigation filters, so their absence is warned about.
        if f.code in ("disagreement", "model") or (f.code == "not-resolved" and f.term in ("N", "K")):
            warnings.warn(f.message, ImuWarning, stacklevel=caller_stacklevel())


def _compare(readoff: Mapping[str, Parameter], fit: Mapping[str, Parameter], regions: Mapping[str, Region],
             taus: np.ndarray) -> list[Flag]:
    flags = []
    for t in TERMS:
        if t not in fit:
            continue
        ro, ft = readoff[t], fit[t]
        if not ft.resolved and not ro.resolved:
            if t in ("K", "R", "B", "Q"):
                flags.append(Flag("not-resolved", t, (
                    f"{t} ({_NAMES[t]}) is not resolved by the record (τ {taus[0]:.3g}–{taus[-1]:.3g} s):"
                    f" {t} < {min(ro.high, ft.high):.3g} {pretty(ft.unit)}")))
            else:
                flags.append(Flag("not-resolved", t, f"{t} ({_NAMES[t]}) is not resolved by the record"))
        elif ro.resolved and ft.resolved:
            if ro.high < ft.low or ft.high < ro.low:
                flags.append(Flag("disagreement", t, (
                    f"{t}: read-off {ro.format(3)} and fit {ft.format(3)} disagree beyond their intervals"
                    f" (read-off region {regions[t].tau_low:.3g}–{regions[t].tau_high:.3g} s)")))
        elif ro.resolved and not ft.resolved:
            if ro.low > ft.high:
                flags.append(Flag("disagreement", t, (
                    f"{t}: the read-off finds {ro.format(3)} but the fit drops the term (bound {ft.high:.3g})")))
        else:
            if ft.low > ro.high:
                flags.append(Flag("disagreement", t, (
                    f"{t}: the fit finds {ft.format(3)} above the read-off bound {ro.high:.3g}")))
    return flags


def _model_edf(result: StabilityResult, fit_alpha: np.ndarray) -> np.ndarray:
    """EDF of each point of ``result`` under the power-law noise α (clipped to −2…2) found at it."""
    alpha = np.clip(fit_alpha, -2, 2).astype(np.int64)
    return np.asarray(edf_array(result.statistic, alpha, result.m, result.n_points, unsupported="nan"), float)


def _check_deviation_range(dev: np.ndarray) -> None:
    """Refuse, in one line, a curve whose scale the fit cannot carry (it gave zero-width intervals
    at 1e100 and a LinAlgError at 1e-100 in the sample unit)."""
    pos = dev[np.isfinite(dev) & (dev > 0)]
    lo, hi = DEVIATION_RANGE
    if pos.size and (pos.min() < lo or pos.max() > hi):
        raise DataError(
            f"the Allan deviation spans {pos.min():.3g} … {pos.max():.3g} in the sample unit; the IMU model "
            f"is fitted for deviations within {lo:g} … {hi:g}: give the samples in a unit that brings them "
            "into that range (scale= in Python, --gyro-unit/--accel-unit on the command line)")
