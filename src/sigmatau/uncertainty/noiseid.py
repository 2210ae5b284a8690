"""Noise identification: which power-law noise dominates at each averaging time.

Five tools, from the most automatic to the most descriptive:

* :func:`lag1_acf_noise_id` — Riley & Greenhall's lag-1 autocorrelation method,
  good from about 30 analysis points;
* :func:`b1_noise_id` (Barnes' B1 ratio) and :func:`rn_ratio` (R(n) = MVAR/AVAR),
  for the long averaging times where too few points remain;
* :func:`identify` — the Stable32-style per-τ decision between them;
* :func:`theo_noise_id` — the noise type from TheoBR's bias ratio κ;
* :func:`local_slopes` and :func:`fit_power_law` — the design tip's slope table,
  read off a computed deviation curve, and a whole-curve fit of power-law terms.

Noise types are named by the exponent α of the one-sided frequency PSD
``S_y(f) = h_α f^α`` (numerics.md §0): 2 WPM, 1 FPM, 0 WFM, −1 FFM, −2 RWFM,
−3 FWFM, −4 RRFM.

The tools live in sibling modules — :mod:`.noisebase` (names, checks),
:mod:`.lag1`, :mod:`.ratios` (B1 and R(n)) and :mod:`.powerfit` (slopes and
the power-law fit); this module holds the per-τ decision and the Theo κ
table, and re-exports every name.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal, Optional, Sequence, Union

import numpy as np

from ..core.taus import STOP_RATIOS
from ..core.validate import as_series, check_data_type, check_rate
from ..errors import DataError, ParameterError
from .lag1 import LAG1_MIN_POINTS, Lag1Result, lag1_acf_noise_id, lag1_of_series
from .noisebase import NOISE_NAMES, Family, InsufficientDataError, _check_count, _check_m
# Public names outside __all__ that other modules import from here (the chunked
# driver: b1_classify, b1_observed; imu.model: OCTAVE_CORRELATION).
from .powerfit import OCTAVE_CORRELATION  # noqa: F401
from .powerfit import LocalSlopes, PowerLawFit, fit_power_law, local_slopes, power_law_variance
from .ratios import b1_classify, b1_observed  # noqa: F401
from .ratios import B1Result, b1_expected, b1_noise_id, b1_ratio, rn_expected, rn_ratio

__all__ = [
    "NOISE_NAMES",
    "InsufficientDataError",
    "Lag1Result",
    "lag1_acf_noise_id",
    "B1Result",
    "b1_ratio",
    "b1_expected",
    "b1_noise_id",
    "rn_ratio",
    "rn_expected",
    "b1_min_averages",
    "NoiseIdentification",
    "identify",
    "theo_noise_id",
    "LocalSlopes",
    "local_slopes",
    "power_law_variance",
    "PowerLawFit",
    "fit_power_law",
]


# -------------------------------------------------------------- decision logic (§5.5)

FAMILY_ALIASES: dict[str, str] = {
    "allan": "allan", "total": "allan", "theo": "allan",
    "modified": "modified", "hadamard": "hadamard",
    "stdev": "allan", "ostdev": "allan", "adev": "allan", "oadev": "allan", "totdev": "allan",
    "theo1": "allan", "theobr": "allan",
    "mdev": "modified", "tdev": "modified", "mtotdev": "modified", "ttotdev": "modified",
    "theoh": "modified",
    "hdev": "hadamard", "ohdev": "hadamard", "htotdev": "hadamard",
    "mhdev": "hadamard", "ldev": "hadamard", "mhtotdev": "hadamard",
    # PVAR separates white from flicker PM and converges for α ≥ −2, as MVAR does
    "pdev": "modified",
}

#: Range of α each family supports: (dmax, lowest α, highest α).
FAMILY_RULES = {"allan": (2, -2, 2), "modified": (2, -2, 2), "hadamard": (3, -4, 2)}


@dataclass(frozen=True, repr=False, eq=False)
class NoiseIdentification:
    """Per-τ noise identification (see :func:`identify`).

    Attributes
    ----------
    m, taus : numpy.ndarray
        Averaging factors and τ = m/rate.
    alpha : numpy.ndarray of int
        Identified α, clipped to the family's range.
    alpha_estimate : numpy.ndarray of float
        Fractional estimate before clipping (NaN where no method applied).
    method : tuple of str
        ``"lag1"``, ``"b1"``, ``"b1+rn"`` or ``"carried"`` (too few averages
        for B1, or no method applied: α of the nearest smaller identified m,
        else of the nearest one).
    family : str
        ``"allan"``, ``"modified"`` or ``"hadamard"``.
    data_type : str
    """

    m: np.ndarray
    taus: np.ndarray
    alpha: np.ndarray
    alpha_estimate: np.ndarray
    method: tuple[str, ...]
    family: str
    data_type: str

    def __post_init__(self) -> None:
        for name in ("m", "taus", "alpha", "alpha_estimate"):
            arr = np.array(getattr(self, name), copy=True)
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)

    def __len__(self) -> int:
        return int(self.m.size)

    def __repr__(self) -> str:
        names = ", ".join(f"{int(m)}:{NOISE_NAMES.get(int(a), a)}" for m, a in zip(self.m, self.alpha))
        return f"NoiseIdentification({self.family}, {self.data_type} data, m:type = {names})"


def identify(
    data: object,
    ms: Union[int, Sequence[int], np.ndarray],
    *,
    data_type: Literal["freq", "phase"] = "freq",
    family: Union[Family, str] = "allan",
    rate: float = 1.0,
    detrend: bool = False,
    acf: Literal["standard", "stable32"] = "standard",
    n_terms: Optional[Union[Sequence[int], np.ndarray]] = None,
) -> NoiseIdentification:
    """Stable32-style noise identification at each averaging factor.

    Parameters
    ----------
    data : array_like
        Phase or frequency samples (N of them).
    ms : int or sequence of int
        Averaging factors.
    data_type : {"freq", "phase"}
        Meaning of ``data``.
    family : str
        ``"allan"`` (also ``"total"``, ``"theo"``), ``"modified"`` or
        ``"hadamard"``, or a statistic name (``"oadev"``, ``"mdev"``,
        ``"tdev"``, ``"hdev"``, ``"ohdev"``, ``"totdev"``, ``"mtotdev"``,
        ``"ttotdev"``, ``"htotdev"``, ``"theo1"``, ``"theobr"``, ``"theoh"`` …).
    rate : float
        Sample rate in Hz, used only for the ``taus`` of the result.
    detrend, acf
        Passed to :func:`lag1_acf_noise_id`; ``acf="stable32"`` reproduces
        Stable32's α at rows where α̂ sits on a rounding boundary.
    n_terms : sequence of int, optional
        Number of terms of the statistic at each factor of ``ms`` (the "#"
        column of a Stable32 table, ``StabilityResult.n``). Where B1 decides,
        it is the N of the expectation ``B1(N, μ)``, as in Stable32; without
        it N is the number of averages ``Nb``. The statistic functions pass
        their own ``n``.

    Returns
    -------
    NoiseIdentification

    Notes
    -----
    At each m (numerics.md §5.5):

    1. if ``⌊N/m⌋ ≥ 30``, N the number of data points as given (phase or
       frequency): lag-1 autocorrelation (:func:`lag1_acf_noise_id`) with
       ``dmax = 2`` for the Allan, total and Theo families and ``dmax = 3``
       for the Hadamard family;
    2. otherwise B1 (:func:`b1_noise_id`, Hadamard mode for that family),
       compared with ``B1(N, μ)`` for N = ``n_terms`` when given; when B1
       finds μ = −2 (WPM or FPM), R(n) = MVAR/AVAR of the data splits WPM (R
       below the geometric mean of the WPM and FPM expectations) from FPM.
       Stable32's manual does this for the modified family only and reports
       α = 1 elsewhere; we do it for every family, because the EDF of OADEV or
       OHDEV for FPM is several times smaller than for WPM and calling white
       PM flicker PM made the 68.3 % intervals cover 99.9 % of the time
       (tests/test_confidence_mc.py). On the Stable32 tables we have, this
       changes no row;
    3. B1 is applied only while the ``Nb = ⌊M/m⌋`` averages of the M
       frequency samples number at least ``2·stop``, twice the Stable32 stop
       ratio of the statistic named by ``family`` (ADEV, HDEV, STDEV: 10;
       OADEV, MDEV, TDEV, OHDEV, OSTDEV: 8; MTOT, TTOT, HTOT: 6; TOTDEV: 4),
       and at least 3 averages for a family name. Past that — and wherever no
       method applies — α is carried from the nearest smaller identified
       factor (``method`` "carried").

    Rules 2 and 3 are those that reproduce Stable32's Alpha column (checked
    on 8138 rows of 115 Stable32 tables: octave, decade and all-τ grids of
    phase and frequency records from 1001 to 241218 points, 99.6 % agree).
    They also stop α from jumping between neighbouring τ where a handful of
    averages cannot tell noise types apart: with ``N = Nb`` the B1 boundaries
    are so close together at small Nb that sampling noise alone moves the
    ratio across them.

    α is clipped to what the family's variance supports: [−2, 2] for the
    Allan and modified families (AVAR and MVAR diverge for α ≤ −3) and
    [−4, 2] for the Hadamard family. ``alpha_estimate`` is left unclipped so
    that an out-of-range value (e.g. FWFM seen by an Allan statistic) stays
    visible.

    References
    ----------
    W. J. Riley, NIST SP 1065 (2008) §5.6; Riley & Greenhall, Proc. EFTF
    (2004); numerics.md §5.2–§5.5.

    Examples
    --------
    >>> import numpy as np
    >>> from sigmatau.noiseid import identify
    >>> x = np.random.default_rng(0).standard_normal(10_000)   # white phase
    >>> identify(x, [1, 10, 100], data_type="phase").alpha.tolist()
    [2, 2, 2]
    """
    dtype = check_data_type(data_type)
    rate_f = check_rate(rate)
    series = as_series(data, gaps=True)
    fam = _check_family(family)
    m_list = _check_factors(ms)
    dmax, lo, hi = FAMILY_RULES[fam]
    n_freq = series.size - 1 if dtype == "phase" else series.size
    min_averages = b1_min_averages(str(family).lower())
    terms = _check_terms(n_terms, len(m_list))
    if acf not in ("standard", "stable32"):
        raise ParameterError(f"acf={acf!r} must be 'standard' or 'stable32'")

    alpha = np.zeros(len(m_list), dtype=np.int64)
    est = np.full(len(m_list), np.nan)
    method: list[str] = []
    for i, m in enumerate(m_list):
        found = _lag1_at(series, m, dtype, dmax, detrend, acf)
        if found is None and n_freq // m >= min_averages:
            found = _b1_at(series, m, dtype, fam, None if terms is None else terms[i])
        if found is None:
            method.append("carried")
            continue
        alpha[i], est[i], tag = found
        method.append(tag)

    _fill_carried(alpha, method, m_list, series.size)
    alpha = np.clip(alpha, lo, hi)
    m_out = np.array(m_list, dtype=np.int64)
    return NoiseIdentification(m=m_out, taus=m_out / rate_f, alpha=alpha, alpha_estimate=est,
                               method=tuple(method), family=fam, data_type=dtype)


def _check_family(family: object) -> str:
    """The family (``"allan"``, ``"modified"``, ``"hadamard"``) of a family or statistic name."""
    fam = FAMILY_ALIASES.get(str(family).lower()) if isinstance(family, str) else None
    if fam is None:
        raise ParameterError(
            f"family={family!r} must be 'allan', 'modified', 'hadamard' or a statistic name"
            f" ({', '.join(sorted(k for k in FAMILY_ALIASES if k not in FAMILY_RULES))})"
        )
    return fam


def _check_factors(ms: object) -> list[int]:
    """The averaging factors of :func:`identify` as a list of positive ints."""
    m_arr = np.atleast_1d(np.asarray(ms))
    if m_arr.ndim != 1:
        raise ParameterError(f"ms must be an integer or a 1-D sequence of integers, got shape {m_arr.shape}")
    return [_check_m(v, "ms") for v in m_arr.tolist()]


def _lag1_at(series: np.ndarray, m: int, dtype: str, dmax: int, detrend: bool,
             acf: str) -> Optional[tuple[int, float, str]]:
    """Rule 1 of :func:`identify`: ``(α, α̂, "lag1")``, or None when fewer than 30 points remain."""
    if series.size // m < LAG1_MIN_POINTS:
        return None
    try:
        # The series is validated once by identify (not again at every m).
        r = lag1_of_series(series, m, data_type=dtype, dmin=0, dmax=dmax, detrend=detrend, acf=acf,
                           min_points=LAG1_MIN_POINTS)
    except InsufficientDataError:
        return None
    return r.alpha, r.alpha_estimate, "lag1"


def _b1_at(series: np.ndarray, m: int, dtype: str, fam: str,
           n_expected: Optional[int]) -> Optional[tuple[int, float, str]]:
    """Rule 2 of :func:`identify`: B1, with R(n) splitting WPM from FPM; None when B1 fails."""
    try:
        b = b1_noise_id(series, m, data_type=dtype, hadamard=(fam == "hadamard"), n_expected=n_expected)
    except DataError:
        return None
    if b.ambiguous:
        split = _rn_split(series, m, dtype)
        if split is not None:
            return split[0], split[1], "b1+rn"
    return b.alpha, b.alpha_estimate, "b1"


def _rn_split(series: np.ndarray, m: int, dtype: str) -> Optional[tuple[int, float]]:
    """WPM (2) or FPM (1) from R(n), and α̂ log-interpolated between their expectations.

    None when R(n) cannot be computed at ``m`` (B1's α = 1 then stands).
    """
    try:
        rn = rn_ratio(series, m, data_type=dtype)
    except DataError:
        return None
    return rn_alpha(rn, m)


def rn_alpha(rn: float, m: int) -> tuple[int, float]:
    """White PM (2) or flicker PM (1) from an observed R(n) = MVAR/OAVAR at ``m``, and α̂.

    α = 2 where R(n) is below the geometric mean of the two types' expectations
    (:func:`rn_expected`), else 1; α̂ = 2 − t with t the position of ln R(n) between
    ln R_WPM and ln R_FPM (0 at white PM, 1 at flicker PM). Used by :func:`identify` and by
    the streamed identification (:mod:`sigmatau.stream`), which has R(n) from its own sums.
    """
    wpm, fpm = float(rn_expected(m, 2)), float(rn_expected(m, 1))
    alpha = 2 if rn < math.sqrt(wpm * fpm) else 1
    # log-interpolated position between the two expectations
    t = (math.log(rn) - math.log(wpm)) / (math.log(fpm) - math.log(wpm)) if fpm != wpm else 0.0
    return alpha, 2.0 - t


def _fill_carried(alpha: np.ndarray, method: list[str], m_list: list[int], n_data: int) -> None:
    """Rule 3 of :func:`identify`: give each "carried" row the α of :func:`_carried_from`'s row, in place."""
    done = [i for i, tag in enumerate(method) if tag != "carried"]
    for i, tag in enumerate(method):
        if tag == "carried":
            if not done:
                raise InsufficientDataError(
                    f"no averaging factor in ms leaves enough data ({n_data} points) for any method"
                )
            alpha[i] = alpha[_carried_from(done, m_list, i)]


def b1_min_averages(statistic: str) -> int:
    """Fewest averages ``Nb = ⌊M/m⌋`` at which :func:`identify` applies B1 for ``statistic``.

    Parameters
    ----------
    statistic : str
        A statistic name (``"adev"``, ``"oadev"``, ``"totdev"`` …) or a
        family name.

    Returns
    -------
    int
        Twice the statistic's Stable32 stop ratio (the ``stop_ratio`` its
        keyword grids use): 10 for ADEV, HDEV and STDEV, 8 for OADEV, MDEV,
        TDEV, OHDEV and OSTDEV, 6 for MTOT, TTOT and HTOT, 4 for TOTDEV; 3, the
        least B1 can use, for family names and the Theo family.

    Notes
    -----
    Beyond this factor Stable32 carries the α of the preceding τ instead of
    computing B1: that rule reproduces its Alpha column on every dense grid
    we have (see :func:`identify`).

    Examples
    --------
    >>> from sigmatau.noiseid import b1_min_averages
    >>> b1_min_averages("oadev"), b1_min_averages("totdev"), b1_min_averages("allan")
    (8, 4, 3)
    """
    stop = STOP_RATIOS.get(statistic)
    return 3 if stop is None else max(3, int(round(2 * stop)))


def _check_terms(n_terms: object, size: int) -> Optional[list[int]]:
    """The ``n_terms`` of :func:`identify`: None, or one non-negative count per factor."""
    if n_terms is None:
        return None
    arr = np.atleast_1d(np.asarray(n_terms))
    if arr.shape != (size,):
        raise ParameterError(f"n_terms has shape {arr.shape}; it must give one count per averaging factor ({size})")
    return [_check_count(v, "n_terms") for v in arr.tolist()]


def _carried_from(done: list[int], m_list: list[int], i: int) -> int:
    """Index whose α row ``i`` takes: the largest identified factor below it, else the nearest."""
    below = [j for j in done if m_list[j] < m_list[i]]
    if below:
        return max(below, key=lambda j: m_list[j])
    return min(done, key=lambda j: (abs(math.log(m_list[j] / m_list[i])), -m_list[j]))


# ------------------------------------------------------------------ Theo κ (§3, §5.5)

_THEO_ALPHAS = (2, 1, 0, -1, -2)
_THEO_NOMINAL = (0.4, 0.6, 1.0, 1.71, 2.24)
#: Howe & Tasset (2004) Table 1: AVAR/Theo1 = a + b/t^c, t = 0.75 m.
_THEO_ABC = ((0.09, 0.74, 0.40), (0.14, 0.82, 0.30), (1.0, 0.0, 0.0), (1.87, -1.05, 0.79), (2.70, -1.53, 0.85))


def theo_noise_id(kappa: Union[float, np.ndarray], *, m: Optional[Union[int, np.ndarray]] = None) -> np.ndarray:
    """Noise type from TheoBR's bias ratio κ = AVAR/Theo1.

    Parameters
    ----------
    kappa : float or array_like
        Observed ratio(s) κ.
    m : int or array_like, optional
        Averaging factor(s). Without it the fixed nominal Theo1 bias factors
        0.4, 0.6, 1.0, 1.71, 2.24 (WPM, FPM, WFM, FFM, RWFM) are used; with it,
        the τ-dependent factors ``a + b/t^c``, t = 0.75 m, of Howe & Tasset.

    Returns
    -------
    numpy.ndarray of int
        α ∈ {2, 1, 0, −1, −2}, shaped like ``kappa`` (broadcast with ``m``).

    Notes
    -----
    κ is compared with the nominal factors; the thresholds are the geometric
    means of neighbouring factors (0.490, 0.775, 1.308, 1.957 for the fixed
    set).

    References
    ----------
    D. A. Howe and T. K. Peppler, "Very long-term frequency stability:
    estimation using a special-purpose statistic", Proc. IEEE FCS (2003);
    D. A. Howe and T. N. Tasset, "Theo1: characterization of very long-term
    frequency stability", Proc. EFTF (2004); numerics.md §3, §5.5.

    Examples
    --------
    >>> from sigmatau.noiseid import theo_noise_id
    >>> theo_noise_id([0.45, 0.7, 1.1, 1.6, 2.5]).tolist()
    [2, 1, 0, -1, -2]
    """
    k = np.asarray(kappa, dtype=float)
    if np.any(~np.isfinite(k)) or np.any(k <= 0):
        raise ParameterError(f"kappa={kappa!r} must be positive and finite")
    if m is None:
        factors = np.broadcast_to(np.array(_THEO_NOMINAL), k.shape + (5,))
    else:
        m_a = np.asarray(m, dtype=float)
        if np.any(m_a < 1):
            raise ParameterError(f"m={m!r} must be at least 1")
        k, m_a = np.broadcast_arrays(k, m_a)
        t = 0.75 * m_a[..., None]
        abc = np.array(_THEO_ABC)
        factors = abc[:, 0] + abc[:, 1] / t ** abc[:, 2]
    bounds = np.sqrt(factors[..., :-1] * factors[..., 1:])
    idx = np.sum(k[..., None] > bounds, axis=-1)
    return np.asarray(_THEO_ALPHAS)[idx]
