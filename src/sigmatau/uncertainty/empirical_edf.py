"""Empirical EDF formulas: SP1065 Table 5 (OAVAR), Tables 7–8 (TOTVAR, MTOT, TTOT), HTOT, Theo1.

These are the rules :func:`sigmatau.uncertainty.confidence.edf` uses for the
total and Theo families and ``stdev`` (its Notes table says which applies
where); their sources, and what they were checked against:

TOTVAR (SP1065 Table 7): (b, c) = WFM (1.50, 0), FFM (1.17, 0.22),
RWFM (0.93, 0.36). Nothing is tabulated for WPM/FPM. For FPM the Table 5
closed form is used: Stable32 does the same (its TOTDEV intervals are
reproduced to 3e-4), and Monte Carlo of TOTVAR itself agrees (N = 513,
m = 4/16/64: MC 231/120/40, Table 5 225/123/39; the Greenhall OAVAR rule
gives 198/96/35). **WPM raises**: Stable32 uses the Table 5 WPM form, but
Monte Carlo shows it, and the OAVAR EDF, overstating the TOTVAR EDF up to 3×
(N = 513, m = 64: MC 74, Table 5 220), i.e. intervals too narrow; TOTVAR is
meant for FM noise — use an OADEV interval for white PM.

MTOT and TTOT (SP1065 Table 8): (b, c) = WPM (1.90, 2.10), FPM (1.20, 1.40),
WFM (1.10, 1.20), FFM (0.85, 0.50), RWFM (0.75, 0.31). Stable32 does not
follow this table: below m = 10 it uses the MDEV Greenhall EDF, above it a
rule giving ν about 20–45 % larger than the table (not identified).

HTOT (Howe et al. 2000) with ``M = N − 1`` frequency points: (b0, b1) =
WFM (0.559, 1.004), FFM (0.868, 1.140), RWFM (0.938, 1.696),
FWFM (2.554, 0.974), RRFM (3.149, 1.276). The FWFM/RRFM rows are kept as
published although Monte Carlo gives ν ≈ 2.5× larger: they are very
conservative. Below m = 16 the formula exceeds the number of samples
(ν = 1786 for M = 1000 at m = 1) and, as Stable32 does, the Table 5 closed
form takes over for α = 1 … −2 (reproduces Stable32's HTOT intervals to
7e-4; not checked by Monte Carlo). FPM uses Table 5 at every m (Stable32's
own values are 4–12 % higher at m ≥ 128). WPM raises, as for TOTVAR. At
m = 1 HTOT is OHVAR(τ0) (SP1065, Stable32 and :func:`sigmatau.htotdev`
report OHDEV there) and ``edf("htotdev", α, 1, N)`` is
``edf("ohdev", α, 1, N)``, for every α OHDEV has a rule for. (Stable32's
HTOT table prints the Table 5 interval at m = 1, ν = 666 for WFM at
N = 1001, while its OHDEV table prints Greenhall's ν = 609 for the same
value; Monte Carlo of OHVAR(τ0) on discrete white FM gives 493 ± 3 %
(2000 runs), and the N − 3 squared second differences of white y,
correlated at lags 1 and 2 by −4/6 and 1/6, give about
``(N−3)/(1 + 2(16+1)/36) = 513``: both rules overstate ν there.)

Theo1 (Howe & Tasset 2004), ``t = 0.75 m``, each first bracket
**multiplied** by the second:

* WPM ``0.86 (N+1)(N − 4t/3)/(N − t) · t/(t + 1.14)``
* FPM ``(4.798N² − 6.374Nt + 12.387t)/(√(t + 36.6)(N − t)) · t/(t + 0.3)``
* WFM ``[(4.1N + 0.8)/t − (3.1N + 6.5)/N] · t^{3/2}/(t^{3/2} + 5.2)``
* FFM ``(2N² − 1.3Nt − 3.5t)/(Nt) · t³/(t³ + 2.3)``
* RWFM ``(4.4N − 2)/(2.9t) · [(4.4N − 1)² − 8.6t(4.4N − 1) + 11.4t²]/(4.4N − 3)²``

TheoBR and the TheoBR part of TheoH use the Theo1 EDF (the AVAR part of
TheoH takes ``edf("oadev", ...)``). The RWFM formula
turns negative for ``t ≳ 0.63 N``; NaN is returned there.

MHTOT (:func:`sigmatau.stats.modhadamard.mhtotdev`): no EDF is published for
this construction, so ``ν = (N/m)/(b0 + b1·m/N)`` (the HTOT form, N phase
points) was fitted by weighted least squares to Monte-Carlo EDFs
``2·mean²/var`` of the raw estimator on Kasdin–Walter noise: N = 1025 (R = 400,
m = 2 … 256, seed 20261125) and N = 4097 (R = 300, m = 4, 16, 64, 256, seed
20261126). (b0, b1) = WPM (0.70, 0.82), FPM (0.95, 3.5), WFM (1.07, 3.3),
FFM (1.08, 3.1), RWFM (1.04, 5.2), FWFM (1.09, 7.5), RRFM (1.37, 9.6).
Residuals are within ±15 % (the Monte-Carlo scatter is about ±8 %) except at
m = 2 for WPM, where the fit overstates ν by 39 %, and at a few points
(≤ 24 %) of RRFM. ``tests/test_modhadamard.py`` checks the interval coverage
at N = 2049, a length not used in the fit. At m = 1 MHTOT is MHVAR(τ0) and
takes its Greenhall EDF.
"""

from __future__ import annotations

import math

from ..errors import ParameterError
from .edfchecks import _check_alpha, _check_int

# nu = b·N/m − c (SP1065 Table 7 TOTVAR, Table 8 MTOT/TTOT).
_TOTVAR = {0: (1.50, 0.0), -1: (1.17, 0.22), -2: (0.93, 0.36)}
_MTOT = {2: (1.90, 2.10), 1: (1.20, 1.40), 0: (1.10, 1.20), -1: (0.85, 0.50), -2: (0.75, 0.31)}
# nu = (M/m)/(b0 + b1·m/M) with M = N − 1 frequency points (Howe et al., PTTI 2000).
_HTOT = {0: (0.559, 1.004), -1: (0.868, 1.140), -2: (0.938, 1.696),
         -3: (2.554, 0.974), -4: (3.149, 1.276)}
# MHTOT (sigmatau.stats.modhadamard.mhtotdev), m ≥ 2: nu = (N/m)/(b0 + b1·m/N), N phase points.
# No published coefficients exist; these are least-squares fits to Monte-Carlo EDFs
# (module docstring) and are replaced by measured ones if a publication appears.
_MHTOT = {2: (0.70, 0.82), 1: (0.95, 3.5), 0: (1.07, 3.3), -1: (1.08, 3.1), -2: (1.04, 5.2),
          -3: (1.09, 7.5), -4: (1.37, 9.6)}
# Below this factor Stable32 replaces the HTOT formula (which exceeds M there) by SP1065 Table 5.
_HTOT_MIN_M = 16


def _oadev_simple(alpha: int, m: int, N: int) -> float:
    """SP1065 Table 5 closed forms (unchecked arguments); NaN when undefined."""
    if N < 2 * m + 1:
        return math.nan
    if alpha == 2:
        nu = (N + 1) * (N - 2 * m) / (2.0 * (N - m))
    elif alpha == 1:
        a = math.log((N - 1) / (2.0 * m))
        b = math.log((2 * m + 1) * (N - 1) / 4.0)
        nu = math.exp(math.sqrt(a * b)) if a * b >= 0.0 else math.nan
    elif alpha == 0:
        nu = (3.0 * (N - 1) / (2.0 * m) - 2.0 * (N - 2) / N) * 4.0 * m * m / (4.0 * m * m + 5.0)
    elif alpha == -1:
        nu = 2.0 * (N - 2) / (2.3 * N - 4.9) if m == 1 else 5.0 * N * N / (4.0 * m * (N + 3 * m))
    else:
        nu = (N - 2) / (m * (N - 3.0) ** 2) * ((N - 1) ** 2 - 3.0 * m * (N - 1) + 4.0 * m * m)
    return nu if math.isfinite(nu) and nu > 0.0 else math.nan


def _theo1_edf(alpha: int, m: int, N: int) -> float:
    """Theo1 EDF of Howe & Tasset (formulas in the module docstring), t = 0.75 m."""
    t = 0.75 * m
    if alpha == 2:
        return 0.86 * (N + 1) * (N - 4.0 * t / 3.0) / (N - t) * (t / (t + 1.14))
    if alpha == 1:
        return ((4.798 * N * N - 6.374 * N * t + 12.387 * t) / (math.sqrt(t + 36.6) * (N - t))
                * (t / (t + 0.3)))
    if alpha == 0:
        t15 = t ** 1.5
        return ((4.1 * N + 0.8) / t - (3.1 * N + 6.5) / N) * (t15 / (t15 + 5.2))
    if alpha == -1:
        return (2.0 * N * N - 1.3 * N * t - 3.5 * t) / (N * t) * (t ** 3 / (t ** 3 + 2.3))
    u = 4.4 * N - 1.0
    return ((4.4 * N - 2.0) / (2.9 * t)
            * ((u * u - 8.6 * t * u + 11.4 * t * t) / (4.4 * N - 3.0) ** 2))


_EMPIRICAL_ALPHAS = {
    "totdev": (1, 0, -1, -2),
    "mtotdev": (2, 1, 0, -1, -2),
    "ttotdev": (2, 1, 0, -1, -2),
    "htotdev": (1, 0, -1, -2, -3, -4),
    "mhtotdev": (2, 1, 0, -1, -2, -3, -4),
    "theo1": (2, 1, 0, -1, -2),
    "theobr": (2, 1, 0, -1, -2),
    "theoh": (2, 1, 0, -1, -2),
    "stdev": (0,),
}



def _empirical_edf(statistic: str, alpha: int, m: int, N: int) -> tuple[float, str]:
    """ν of a total, Theo or ``stdev`` statistic (checked arguments), or ``(nan, reason)``."""
    if statistic == "stdev":
        K = (N - 1) // m
        if K < 2:
            return math.nan, f"N={N} phase points give {K} average(s) of m={m}; need 2"
        return float(K - 1), ""
    if statistic in ("totdev", "mtotdev", "ttotdev"):
        need = 2 * m + 1 if statistic == "totdev" else 3 * m + 1
        if N < need:
            return math.nan, f"N={N} phase points is fewer than {need} needed at m={m}"
        if statistic == "totdev" and alpha == 1:
            nu = _oadev_simple(1, m, N)
        else:
            b, c = (_TOTVAR if statistic == "totdev" else _MTOT)[alpha]
            nu = b * N / m - c
    elif statistic == "htotdev":
        M = N - 1
        if M < 3 * m:
            return math.nan, f"M={M} frequency points is fewer than 3m={3 * m}"
        if alpha == 1 or (m < _HTOT_MIN_M and alpha >= -2):
            nu = _oadev_simple(alpha, m, N)
        else:
            b0, b1 = _HTOT[alpha]
            nu = (M / m) / (b0 + b1 * m / M)
    elif statistic == "mhtotdev":
        if N < 4 * m:
            return math.nan, f"N={N} phase points is fewer than 4m={4 * m}"
        b0, b1 = _MHTOT[alpha]
        nu = (N / m) / (b0 + b1 * m / N)
    else:  # Theo1 family
        if N < m + 1:
            return math.nan, f"N={N} phase points is fewer than m+1={m + 1}"
        nu = _theo1_edf(alpha, m, N)
    if not (math.isfinite(nu) and nu > 0.0):
        return math.nan, f"the {statistic} EDF formula gives nu={nu:.3g} <= 0 at m={m}, N={N}"
    return nu, ""


def edf_oadev_simple(alpha: int, m: int, N: int) -> float:
    r"""Closed-form EDF approximation for the overlapped Allan variance.

    Parameters
    ----------
    alpha : {2, 1, 0, -1, -2}
        Dominant noise exponent.
    m : int
        Averaging factor.
    N : int
        Number of phase points.

    Returns
    -------
    float
        ν, NaN when ``N < 2m + 1`` (no OAVAR term) or the formula gives ν ≤ 0.

    Notes
    -----
    SP1065 Table 5 (after Howe, Allan & Barnes 1981 and Stein 1985):

    * WPM ``(N + 1)(N − 2m)/(2(N − m))``
    * FPM ``exp(√(ln((N − 1)/(2m)) · ln((2m + 1)(N − 1)/4)))``
    * WFM ``[3(N − 1)/(2m) − 2(N − 2)/N] · 4m²/(4m² + 5)``
    * FFM m = 1: ``2(N − 2)/(2.3N − 4.9)``; m ≥ 2: ``5N²/(4m(N + 3m))``
    * RWFM ``(N − 2)/(m(N − 3)²) · [(N − 1)² − 3m(N − 1) + 4m²]``

    :func:`greenhall_edf` is the more accurate rule and the one used for
    intervals.

    References
    ----------
    W. J. Riley, NIST SP 1065 (2008), §5.3, Table 5.

    Examples
    --------
    >>> round(edf_oadev_simple(0, 10, 1001), 1)
    146.2
    """
    alpha = _check_alpha(alpha)
    if alpha < -2:
        raise ParameterError(f"alpha={alpha} has no closed-form OAVAR EDF (needs -2 <= alpha <= 2)")
    m = _check_int(m, "m", 1)
    N = _check_int(N, "N", 1)
    return _oadev_simple(alpha, m, N)
