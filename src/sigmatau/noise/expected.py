"""Expected variances of power-law noise: the continuous-time formulas and the exact discrete ones.

:func:`expected_variance` gives the continuous-time formulas (numerics.md §6.3)
and :func:`expected_variance_discrete` the exact discrete-time expectations of
the series :func:`~sigmatau.generate.power_law_noise` draws with
``method="kasdin"`` (numerics.md §6.1), which tests should use at small
averaging factors. Public through :mod:`sigmatau.generate`.
"""

from __future__ import annotations

import math

import numpy as np

from ..core.validate import check_rate
from ..core.powerlaw import response
from ..errors import ParameterError
from .generate import ExpectedStatistic, NoiseType, _as_alpha, _check_level, _NAME, _STATISTICS

__all__ = ["expected_variance", "expected_avar", "expected_variance_discrete", "expected_oavar_discrete"]


def _check_statistic(statistic: object) -> str:
    if statistic not in _STATISTICS:
        raise ParameterError(f"statistic={statistic!r} must be one of {_STATISTICS}")
    return statistic  # type: ignore[return-value]


def _check_converges(statistic: str, alpha: int) -> None:
    lowest = -2 if statistic in ("adev", "oadev", "mdev", "tdev") else -4
    if alpha < lowest:
        raise ParameterError(
            f"{statistic} diverges for {_NAME[alpha]} (alpha={alpha}); it needs alpha >= {lowest}"
            + ("; use hdev or ohdev" if lowest == -2 else "")
        )


def _positive_array(values: object, name: str, integer: bool = False) -> np.ndarray:
    try:
        arr = np.atleast_1d(np.asarray(values, dtype=np.float64))
    except (TypeError, ValueError):
        raise ParameterError(f"{name}={values!r} must be numbers > 0") from None
    if arr.ndim != 1 or arr.size == 0 or not np.all(np.isfinite(arr)) or np.any(arr <= 0):
        raise ParameterError(f"{name}={values!r} must be a non-empty 1-D set of finite numbers > 0")
    if integer and np.any(arr != np.round(arr)):
        raise ParameterError(f"{name}={values!r} must be integers >= 1")
    return arr


def expected_variance(
    alpha: NoiseType, h: float, taus: object, *, statistic: ExpectedStatistic = "adev",
    rate: float = 1.0,
) -> np.ndarray:
    """Continuous-model expectation of a variance for ``S_y(f) = h_α f^α``.

    Parameters
    ----------
    alpha : int or str
        Noise type (α or name).
    h : float
        Level ``h_α``.
    taus : array_like
        Averaging times τ in seconds.
    statistic : {"adev", "oadev", "mdev", "tdev", "hdev", "ohdev"}
        Whose variance: AVAR (overlapped or not: same expectation), MVAR,
        TVAR (phase units², ``τ²/3·MVAR``) or HVAR.
    rate : float
        Sample rate in Hz; the high cut-off of WPM and FPM is ``f_h = rate/2``
        and MVAR of WPM uses τ0 = 1/rate.

    Returns
    -------
    numpy.ndarray
        Expected variance at each τ.

    Notes
    -----
    ``E[σ²(τ)] = ∫_0^{f_h} S_y(f) |H(f)|² df`` with
    ``|H_AVAR|² = 2 sin⁴(πfτ)/(πfτ)²`` and ``|H_HVAR|² = (8/3) sin⁶(πfτ)/(πfτ)²``,
    in closed form (numerics.md §6.3): e.g. AVAR = ``h_0/(2τ)`` (WFM),
    ``2 ln 2 · h_{−1}`` (FFM), ``(2π²/3) h_{−2} τ`` (RWFM); MVAR is the
    ``n ≫ 1`` limit. WPM and FPM assume a brick-wall cut-off with
    ``2π f_h τ ≫ 1``. Discrete series differ at small m; use
    :func:`expected_variance_discrete` for them.

    References
    ----------
    J. A. Barnes et al., "Characterization of frequency stability", IEEE Trans.
    Instrum. Meas. IM-20 (1971) 105–120; W. J. Riley, NIST SP 1065 (2008) §5.2;
    numerics.md §6.3 (constants re-derived by exact integration).

    Examples
    --------
    >>> from sigmatau.generate import expected_variance
    >>> [round(float(v), 6) for v in expected_variance("ffm", 1.0, [1.0], statistic="hdev")]
    [1.12467]
    """
    a = _as_alpha(alpha)
    h = _check_level(h)
    tau = _positive_array(taus, "taus")
    statistic = _check_statistic(statistic)
    rate = check_rate(rate)
    _check_converges(statistic, a)
    kind = {"adev": "avar", "oadev": "avar", "mdev": "mvar", "tdev": "tvar"}.get(statistic, "hvar")
    return h * response(kind, a, tau, rate)


def expected_avar(alpha: NoiseType, h: float, taus: object, *, rate: float = 1.0) -> np.ndarray:
    """Continuous-model Allan variance; ``expected_variance(..., statistic="adev")``.

    Examples
    --------
    >>> from sigmatau.generate import expected_avar
    >>> [float(v) for v in expected_avar("wfm", 2.0, [1.0, 4.0])]
    [1.0, 0.25]
    """
    return expected_variance(alpha, h, taus, statistic="adev", rate=rate)


_GL_NODES, _GL_WEIGHTS = np.polynomial.legendre.leggauss(16)


def _spectral_integral(beta: int, m: int, d: int, smooth: int) -> float:
    """``(1/π) ∫_0^π s^β t^{2d} (t/s)^{2·smooth} dω`` with s = 2 sin(ω/2), t = 2 sin(mω/2).

    The integrand is analytic on [0, π] whenever it converges (``β + 2d > −1``:
    t/s is a Dirichlet kernel and the leftover power of s is a non-negative
    integer), so composite Gauss–Legendre with 16 nodes on each of ``4m``
    panels, an eighth of a period of t², is exact to rounding.
    """
    panels = max(16, 4 * m)
    width = math.pi / panels
    total = 0.0
    chunk = 1 << 15
    for lo in range(0, panels, chunk):
        left = width * np.arange(lo, min(lo + chunk, panels))
        w = (left[:, None] + (0.5 * width) * (_GL_NODES + 1.0)).ravel()
        s = 2.0 * np.sin(0.5 * w)
        t = 2.0 * np.sin(0.5 * m * w)
        f = s**beta * t ** (2 * d)
        if smooth:
            f *= (t / s) ** (2 * smooth)
        total += float((f.reshape(-1, _GL_NODES.size) @ _GL_WEIGHTS).sum())
    return total * 0.5 * width / math.pi


def expected_variance_discrete(
    alpha: NoiseType, h: float, m: object, *, statistic: ExpectedStatistic = "oadev",
    rate: float = 1.0,
) -> np.ndarray:
    """Exact expectation of a variance estimate on discrete power-law noise.

    The process is the one :func:`power_law_noise` generates with
    ``method="kasdin"`` (stationary limit): discrete phase spectrum
    ``2 Q_d τ0 |2 sin(π f τ0)|^{α−2}``. It also holds exactly for the
    design-tip constructions of WPM, WFM, RWFM and RRFM, which are the same
    series.

    Parameters
    ----------
    alpha : int or str
        Noise type (α or name).
    h : float
        Level ``h_α`` of ``S_y(f) = h_α f^α``.
    m : int or array_like of int
        Averaging factors.
    statistic : {"adev", "oadev", "mdev", "tdev", "hdev", "ohdev"}
        Estimator, with the library's normalisation (AVAR and OAVAR, HVAR and
        OHVAR have the same expectation).
    rate : float
        Sample rate in Hz.

    Returns
    -------
    numpy.ndarray
        ``E[σ̂²]`` at each m (phase units² for TVAR).

    Notes
    -----
    With ``Q_x = h_α / (2 (2π)^α τ0^{α−1})``, ``β = α − 2`` and
    ``Δ^d_m x_i = Σ_j (−1)^{d−j} C(d, j) x_{i+jm}``,

    .. math:: E[(Δ^d_m x)^2] = \\frac{Q_x}{π} \\int_0^π |2\\sin(ω/2)|^β
              (2\\sin(mω/2))^{2d} \\, dω,

    OAVAR = ``E[(Δ²_m x)²]/(2m²τ0²)``, OHVAR = ``E[(Δ³_m x)²]/(6m²τ0²)``, and
    MVAR = ``E[(Σ_{j<m} Δ²_m x_{i+j})²]/(2m⁴τ0²)``, whose moving sum multiplies
    the integrand by ``(sin(mω/2)/sin(ω/2))²``; TVAR = ``(mτ0)²/3 · MVAR``.
    The integral is evaluated by composite Gauss–Legendre quadrature on an
    integrand that is analytic on [0, π] (see numerics.md §6.1 for the ratios
    to the continuous formulas, e.g. 1.443 for FFM at m = 1).

    References
    ----------
    N. J. Kasdin & T. Walter (1992); numerics.md §6.1.

    Examples
    --------
    >>> from sigmatau.generate import expected_variance_discrete, expected_avar
    >>> ratio = expected_variance_discrete("ffm", 1.0, 1) / expected_avar("ffm", 1.0, 1.0)
    >>> round(float(ratio[0]), 3)
    1.443
    """
    a = _as_alpha(alpha)
    h = _check_level(h)
    ms = _positive_array(m, "m", integer=True).astype(np.int64)
    statistic = _check_statistic(statistic)
    rate = check_rate(rate)
    _check_converges(statistic, a)
    tau0 = 1.0 / rate
    qx = h / (2.0 * (2.0 * math.pi) ** a * tau0 ** (a - 1))
    d = 3 if statistic in ("hdev", "ohdev") else 2
    smooth = 1 if statistic in ("mdev", "tdev") else 0
    cache: dict[int, float] = {}
    out = np.empty(ms.size)
    for i, mi in enumerate(ms.tolist()):
        if mi not in cache:
            cache[mi] = _spectral_integral(a - 2, mi, d, smooth)
        integral = qx * cache[mi]
        if statistic in ("adev", "oadev"):
            out[i] = integral / (2.0 * mi**2 * tau0**2)
        elif statistic in ("hdev", "ohdev"):
            out[i] = integral / (6.0 * mi**2 * tau0**2)
        else:
            out[i] = integral / (2.0 * mi**4 * tau0**2)
            if statistic == "tdev":
                out[i] *= (mi * tau0) ** 2 / 3.0
    return out


def expected_oavar_discrete(alpha: NoiseType, h: float, m: object, *, rate: float = 1.0) -> np.ndarray:
    """Exact OAVAR expectation on discrete noise; ``expected_variance_discrete(..., "oadev")``.

    Examples
    --------
    >>> from sigmatau.generate import expected_oavar_discrete
    >>> [round(float(v), 4) for v in expected_oavar_discrete("rwfm", 3 / (2 * 3.14159265358979**2), [1, 4])]
    [1.5, 4.125]
    """
    return expected_variance_discrete(alpha, h, m, statistic="oadev", rate=rate)
