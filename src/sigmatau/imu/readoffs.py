"""Fixed-slope read-offs of the IMU noise terms from the ADEV curve (IEEE 952 practice, automated).

How a region is chosen and read is described in :func:`sigmatau.imu.analyze`
(*Read-offs*). :func:`_readoffs` composes the steps: the local slopes
(``_local_slopes``), the region of each term (``_best_region``), and either a
line read in it (``_read_region``: the points, with the neighbouring terms'
share removed when a fit is given, ``_region_points``; the weighted level,
``_line_level``; its variance, ``_level_variance``) or an upper bound when no
region exists (``_upper_bound``).
"""

from __future__ import annotations

import math
from typing import NamedTuple, Optional, Sequence

import numpy as np

from ..uncertainty.confidence import deviation_interval
from .fitting import _correlation
from .results import Parameter, Region
from .terms import _ALPHA, _READ_TAU, _SLOPE, READ_FACTOR, _design
from .units import TERMS, SensorUnit

__all__: list[str] = []

#: Read-off region rules: the smoothed local slope within ``_SLOPE_TOL`` of the
#: nominal, its standard error below ``_SLOPE_ERR_MAX``, over at least one octave
#: (two for B, whose flat bottom must be wider than the ≈1.2 octaves within
#: which the crossing of a −½ and a +½ line looks flat).
_SLOPE_TOL = 0.15
_SLOPE_ERR_MAX = 0.2
_SMOOTH_DECADES = 0.31
_SLOPE_ERR_TARGET = 0.1
_SLOPE_TAPER = 0.05
_MIN_SPAN = {"Q": math.log(2.0), "N": math.log(2.0), "B": 2.0 * math.log(2.0), "K": math.log(2.0),
             "R": math.log(2.0)}


class _Curve(NamedTuple):
    """The OADEV curve as the read-offs use it (points with a positive EDF only)."""

    taus: np.ndarray    # τ (s)
    dev: np.ndarray     # deviation
    nu: np.ndarray      # EDF
    lt: np.ndarray      # ln τ
    ls: np.ndarray      # ln σ
    slope: np.ndarray   # smoothed local slope (_local_slopes)
    err: np.ndarray     # its standard error
    design: np.ndarray  # AVAR columns Q², N², B², K², R² at taus (_design)


def _readoffs(taus: np.ndarray, dev: np.ndarray, nu: np.ndarray, conf: float, su: SensorUnit,
              terms: Sequence[str], rate: float, coef: Optional[np.ndarray] = None,
              gain: Optional[np.ndarray] = None, var_cov: Optional[np.ndarray] = None
              ) -> tuple[dict[str, Parameter], dict[str, Region]]:
    """Fixed-slope read-offs; with ``coef``, ``gain`` and ``var_cov`` (the
    unconstrained fit's squared coefficients, its linear map from the AVAR points
    and their covariance) the neighbouring terms' share is removed from every
    point of a region before the line is read (see :func:`~sigmatau.imu.analyze`, *Read-offs*)."""
    lt, ls = np.log(taus), np.log(dev)
    slope, err = _local_slopes(lt, ls, nu)
    curve = _Curve(taus, dev, nu, lt, ls, slope, err, _design(taus, rate))
    params: dict[str, Parameter] = {}
    regions: dict[str, Region] = {}
    for term in terms:
        region = _best_region(term, curve)
        if region is not None:
            read = _read_region(term, region, curve, conf, su, coef, gain, var_cov)
        else:
            read = _upper_bound(term, curve, conf, su)
        params[term], regions[term] = read
    return params, regions


def _best_region(term: str, curve: _Curve) -> Optional[tuple[int, int]]:
    """First and last index of the term's region, or None when no run of τ qualifies.

    Candidates are the runs where the local slope is within ``_SLOPE_TOL`` of the
    term's and its standard error at most ``_SLOPE_ERR_MAX``; the widest in ln τ wins
    (ties: the most EDF), and it must span ``_MIN_SPAN`` of the term.
    """
    s0 = _SLOPE[term]
    cand = (np.abs(curve.slope - s0) <= _SLOPE_TOL) & (curve.err <= _SLOPE_ERR_MAX)
    best = None
    for a, b in _runs(cand):
        span = curve.lt[b] - curve.lt[a]
        key = (span, float(curve.nu[a:b + 1].sum()))
        if best is None or key > best[0]:
            best = (key, a, b)
    if best is not None and best[0][0] >= _MIN_SPAN[term] - 1e-9:
        return best[1], best[2]
    return None


def _read_region(term: str, region: tuple[int, int], curve: _Curve, conf: float, su: SensorUnit,
                 coef: Optional[np.ndarray], gain: Optional[np.ndarray], var_cov: Optional[np.ndarray]
                 ) -> tuple[Parameter, Region]:
    """Read the line of the term's slope in ``region``: value, χ² interval and the rule followed."""
    a, b = region
    s0, tr = _SLOPE[term], _READ_TAU[term]
    idx, corrected, net, var_i = _region_points(term, a, b, curve, coef)
    w, ell, gain_pt, delta = _line_level(term, idx, corrected, net, var_i, curve)
    level = float(np.sum(w * ell))
    if corrected and gain is not None and var_cov is not None:
        var_ln = _level_variance_propagated(term, idx, w, net, curve, gain, var_cov)
    else:
        var_ln = _level_variance(term, idx, w, gain_pt, curve)
    nu_eff = 1.0 / (2.0 * var_ln)
    value = math.exp(level) * READ_FACTOR[term]
    lo, hi = deviation_interval(value, nu_eff, conf)
    if corrected:
        allowance = 0.0
        how = ("the fitted neighbouring terms' share subtracted from each point's AVAR (points where it"
               " exceeds ¾ left out), weights EDF/(AVAR/net)²")
    else:
        # A point whose slope is off by δ holds a share ≈ 2δ of a term whose slope
        # differs by ½ and sits |½·ln(1 − 2δ)| off the line in ln σ (above it for a
        # neighbouring term, below it under a filter): the weighted mean of that
        # offset widens the interval on both sides.
        allowance = float(np.sum(w * -0.5 * np.log1p(-2.0 * delta)))
        how = "EDF weights tapered by the departure from the slope"
    lo, hi = lo * math.exp(-allowance), hi * math.exp(allowance)
    rule = (f"smoothed ADEV slope within ±{_SLOPE_TOL:g} of {s0:+g} (standard error ≤ {_SLOPE_ERR_MAX:g})"
            f" over {b - a + 1} τ; line of slope {s0:+g} read at τ = {tr:.4g} s ({how})"
            + ("; B = σ/0.6643" if term == "B" else "") + f"; interval: χ² with EDF {nu_eff:.3g}"
            + ("" if corrected else
               f", widened by the departure from the slope that the region shows (×{math.exp(allowance):.4g})"))
    param = Parameter(term, value, float(lo), float(hi), su.term_unit(term), True, "read-off", conf, su.kind,
                      note=rule)
    taus = curve.taus
    return param, Region(term, s0, float(taus[a]), float(taus[b]), tr, int(idx.size), True, rule)


def _region_points(term: str, a: int, b: int, curve: _Curve, coef: Optional[np.ndarray]
                   ) -> tuple[np.ndarray, bool, Optional[np.ndarray], Optional[np.ndarray]]:
    """Indices of the region's points to read, whether they are corrected, and their net and raw AVAR.

    With the fit's ``coef`` the neighbouring terms' share is subtracted from each
    point (``net``); if no point keeps more than ¼ of its variance the region is
    read uncorrected. Returns ``(idx, corrected, net, var_i)`` (the last two None
    when uncorrected).
    """
    idx = np.arange(a, b + 1)
    if coef is None:
        return idx, False, None, None
    own = _neighbour_share(curve.design[idx], coef, TERMS.index(term))
    var_i = curve.dev[idx] ** 2
    net = var_i - own
    # A point where the neighbours hold more than ¾ of the variance says
    # little about this term (and nothing when they hold all of it).
    use = net > 0.25 * var_i
    if not use.any():
        return idx, False, None, None
    return idx[use], True, net[use], var_i[use]


def _line_level(term: str, idx: np.ndarray, corrected: bool, net: Optional[np.ndarray],
                var_i: Optional[np.ndarray], curve: _Curve
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Normalised weights, the line's level at the read-off τ from each point, the
    relative-error gain ``AVAR/net`` of each point and its departure δ from the slope.

    Returns ``(w, ell, gain_pt, delta)``; the read-off's ln σ level is ``Σ w·ell``.
    """
    s0, tr = _SLOPE[term], _READ_TAU[term]
    nu, lt = curve.nu, curve.lt
    delta = np.minimum(np.abs(curve.slope[idx] - s0), 0.45)
    if corrected:
        gain_pt = var_i / net               # relative error of the net variance / of the raw one
        ell = 0.5 * np.log(net) + s0 * (math.log(tr) - lt[idx])
        w = nu[idx] / gain_pt**2
    else:
        gain_pt = np.ones(idx.size)
        ell = curve.ls[idx] + s0 * (math.log(tr) - lt[idx])
        # EDF weights, tapered by how far each point's slope is from the nominal:
        # the shortest τ carry most EDF but are the first to be pulled off the
        # line by a neighbouring term or the sensor's filter.
        w = nu[idx] * np.exp(-((delta / _SLOPE_TAPER) ** 2))
    w = w / w.sum()
    return w, ell, gain_pt, delta


def _level_variance_propagated(term: str, idx: np.ndarray, w: np.ndarray, net: np.ndarray, curve: _Curve,
                               gain: np.ndarray, var_cov: np.ndarray) -> float:
    """var(ln σ) of a corrected level, propagated from the fit's covariance of the AVAR points.

    The level is, to first order, linear in the AVAR points: through the
    region's points and through the subtracted coefficients, which the fit
    takes from the same points (ĉ = G·σ̂²). Its variance uses the fit's
    covariance of the points, so the two paths' correlation counts.
    """
    dl = np.zeros(curve.taus.size)
    dl[idx] = w / (2.0 * net)
    others = curve.design[idx] * (np.arange(5) != TERMS.index(term))
    dl -= (w / (2.0 * net)) @ others @ gain
    return float(dl @ var_cov @ dl)


def _level_variance(term: str, idx: np.ndarray, w: np.ndarray, gain_pt: np.ndarray, curve: _Curve) -> float:
    """var(ln σ) of the weighted level from the points' EDF, correlated across τ as the term's noise."""
    corr = _correlation(curve.taus[idx], np.full(idx.size, _ALPHA[term]))
    s = gain_pt / np.sqrt(2.0 * curve.nu[idx])
    return float(w @ (corr * np.outer(s, s)) @ w)


def _upper_bound(term: str, curve: _Curve, conf: float, su: SensorUnit) -> tuple[Parameter, Region]:
    """Upper bound of a term without a region (the *bound rule* of :func:`~sigmatau.imu.analyze`)."""
    taus, dev, nu, lt = curve.taus, curve.dev, curve.nu, curve.lt
    s0, tr = _SLOPE[term], _READ_TAU[term]
    ok = np.isfinite(nu) & (nu > 0)
    bound, where = math.inf, math.nan
    k = int(ok.sum())
    # One-sided level (1 + p)/2 for the bound as a whole (the upper end of a
    # two-sided p interval), Bonferroni-shared by the k points it is the
    # minimum of, so that picking the lowest point does not undercut it.
    p_pt = 1.0 - (1.0 - conf) / (2.0 * max(k, 1))
    if ok.any():
        _, hi = deviation_interval(dev[ok], nu[ok], p_pt, sided="upper")
        mapped = np.asarray(hi) * np.exp(s0 * (math.log(tr) - lt[ok])) * READ_FACTOR[term]
        j = int(np.argmin(mapped))
        bound, where = float(mapped[j]), float(taus[ok][j])
    rule = (f"no region of slope {s0:+g} spanning {_MIN_SPAN[term] / math.log(2):g} octave(s) in"
            f" τ = {taus[0]:.3g}–{taus[-1]:.3g} s; upper bound: the lowest one-sided upper limit of σ(τ)"
            f" over the {k} τ, each at {100 * p_pt:.3g} % (so the bound holds in at least"
            f" {50 * (1 + conf):.3g} % of records: it bounds the whole curve, of which the term is a share),"
            f" carried along slope {s0:+g} to τ = {tr:.4g} s"
            + (" and divided by 0.6643" if term == "B" else "") + f" (attained at τ = {where:.3g} s)")
    param = Parameter(term, math.nan, 0.0, bound, su.term_unit(term), False, "read-off", conf, su.kind,
                      note=rule)
    return param, Region(term, s0, math.nan, math.nan, tr, 0, False, rule)


def _local_slopes(lt: np.ndarray, ls: np.ndarray, nu: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """EDF-weighted least-squares slope of ln σ on ln τ around each τ, and its standard error.

    The window is ±0.31 decade (one octave each side on an octave grid), widened
    in steps of 0.1 decade up to ±0.81 decade while the slope's standard error
    exceeds 0.1 (the long-τ points carry few degrees of freedom). var(ln σ) ≈
    1/(2ν); the error ignores the positive correlation of neighbouring
    estimates, which makes it conservative for a slope.
    """
    slope = np.full(lt.size, np.nan)
    err = np.full(lt.size, np.nan)
    for i in range(lt.size):
        for widen in range(6):
            hw = (_SMOOTH_DECADES + 0.1 * widen) * math.log(10.0)
            j = np.abs(lt - lt[i]) <= hw
            if j.sum() < 2:
                continue
            w = 2.0 * nu[j]
            x, yv = lt[j], ls[j]
            xm = np.sum(w * x) / w.sum()
            sxx = np.sum(w * (x - xm) ** 2)
            if sxx <= 0:
                continue
            slope[i] = np.sum(w * (x - xm) * (yv - np.sum(w * yv) / w.sum())) / sxx
            err[i] = math.sqrt(1.0 / sxx)
            if err[i] <= _SLOPE_ERR_TARGET:
                break
    return slope, err


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    out, start = [], None
    for i, v in enumerate(mask):
        if v and start is None:
            start = i
        if not v and start is not None:
            out.append((start, i - 1))
            start = None
    if start is not None:
        out.append((start, mask.size - 1))
    return out


def _neighbour_share(design: np.ndarray, coef: np.ndarray, own: int) -> np.ndarray:
    """AVAR of every term but column ``own`` at the rows of ``design``: Σ_k≠own A_ik c_k.

    A negative 1/τ² coefficient (the sensor's low-pass filter) gives a negative
    share, which puts back what the filter took.
    """
    c = np.array(coef, float)
    c[own] = 0.0
    return design @ c



def _curve_bound(term: str, taus: np.ndarray, dev: np.ndarray, nu: np.ndarray, conf: float, su: SensorUnit
                 ) -> float:
    """The *bound rule*'s upper bound of ``term`` on the curve, whether or not a region exists: no
    term's line can lie above the whole curve. It caps the fit's selection-aware bound of a dropped
    term (:func:`sigmatau.imu.fitting._selection_aware_bounds`), which has no finite value when the
    few points that carry the term scatter as much as their level."""
    nan = np.full(taus.size, np.nan)
    curve = _Curve(taus, dev, nu, np.log(taus), np.log(dev), nan, nan, np.zeros((taus.size, 5)))
    return _upper_bound(term, curve, conf, su)[0].high
