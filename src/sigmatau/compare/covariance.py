"""Groslambert covariance: the Allan-type covariance of two series that share a clock.

Two difference series ``a = x_A − x_B`` and ``b = x_B − x_C`` measured against a
common device B have a cross Allan covariance whose expectation is ``−σ_B²(τ)``
when the clocks are independent: the noise of the shared device, seen through
the same filter as the Allan variance. Every statistic here is a sum of squares
of one linear filter of the phase (the second difference for the Allan family,
the third for the Hadamard family); the covariance replaces each square by the
product of the filtered ``a`` and filtered ``b``, so it costs O(N) per τ.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal, Sequence

import numpy as np

from ..core.taus import STOP_RATIOS, select_m
from ..core.validate import (
    DataType, as_series, check_data_type, check_rate, remove_linear_phase, scale_to_unit, to_phase,
)
from ..errors import DataError, ParameterError

__all__ = ["CovarianceResult", "CovStatistic", "COV_STATISTICS", "gcodev", "covariance_matrices"]

CovStatistic = Literal["adev", "oadev", "mdev", "hdev", "ohdev"]
#: Statistics whose covariance form is available (each is Σ z_a·z_b / normalisation).
COV_STATISTICS: tuple[str, ...] = ("adev", "oadev", "mdev", "hdev", "ohdev")

# Mathematical largest averaging factor for N phase points and fewest phase points.
_MAX_M = {"adev": lambda n: (n - 1) // 2, "oadev": lambda n: (n - 1) // 2, "mdev": lambda n: (n - 1) // 3,
          "hdev": lambda n: (n - 1) // 3, "ohdev": lambda n: (n - 1) // 3}
_MIN_POINTS = {"adev": 3, "oadev": 3, "mdev": 4, "hdev": 4, "ohdev": 4}


@dataclass(frozen=True, eq=False)
class CovarianceResult:
    """Signed Allan-type covariance of two series at each τ.

    Attributes
    ----------
    statistic : str
        The variance whose covariance form was used (``"oadev"`` for GCoDev).
    tau, m : numpy.ndarray
        Averaging times (s) and factors.
    cov : numpy.ndarray
        Signed covariance (units of a variance); may be negative.
    dev : numpy.ndarray
        ``sign(cov)·sqrt(|cov|)``, the signed deviation SigmaTheta prints as GCoDev.
    n : numpy.ndarray
        Number of filtered terms summed at each τ.
    """

    statistic: str
    tau: np.ndarray
    m: np.ndarray
    cov: np.ndarray
    dev: np.ndarray
    n: np.ndarray

    def __repr__(self) -> str:
        return f"CovarianceResult({self.statistic}, {self.tau.size} τ from {self.tau[0]:g} s to {self.tau[-1]:g} s)"

    def to_rows(self) -> list[dict]:
        """One dict per τ: ``tau, m, n, cov, dev``."""
        return [{"tau": float(t), "m": int(k), "n": int(c), "cov": float(v), "dev": float(d)}
                for t, k, c, v, d in zip(self.tau, self.m, self.n, self.cov, self.dev)]


def check_statistic(statistic: object) -> str:
    """The statistic name if its covariance form exists, else :class:`ParameterError`."""
    if statistic not in COV_STATISTICS:
        raise ParameterError(f"statistic={statistic!r} must be one of {COV_STATISTICS}")
    return str(statistic)


def filtered(x: np.ndarray, m: int, statistic: str) -> tuple[np.ndarray, float]:
    """``(z, c)``: the filtered phase whose mean square times ``c`` is the statistic at τ = m·τ0.

    The variance is ``c·Σ z_i²/n`` with ``c`` holding the τ-free normalisation
    (``1/2`` Allan, ``1/(2m²)`` modified Allan, ``1/6`` Hadamard); divide by τ²
    afterwards. Linear in ``x``, so the covariance of two series is ``c·Σ z_a z_b/n``.
    """
    if statistic == "oadev":
        return x[2 * m:] - 2.0 * x[m:-m] + x[:-2 * m], 0.5
    if statistic == "adev":
        xs = x[: ((x.size - 1) // m) * m + 1: m]
        return xs[2:] - 2.0 * xs[1:-1] + xs[:-2], 0.5
    if statistic == "mdev":
        d = x[2 * m:] - 2.0 * x[m:-m] + x[:-2 * m]
        c = np.concatenate(([0.0], np.cumsum(d)))
        return c[m:] - c[:-m], 0.5 / m**2
    if statistic == "hdev":
        xs = x[: ((x.size - 1) // m) * m + 1: m]
        return xs[3:] - 3.0 * xs[2:-1] + 3.0 * xs[1:-2] - xs[:-3], 1.0 / 6.0
    # ohdev
    return x[3 * m:] - 3.0 * x[2 * m:-m] + 3.0 * x[m:-2 * m] - x[:-3 * m], 1.0 / 6.0


def checked_records(records: Sequence[object], names: Sequence[str], rate: object,
                    data_type: object, statistic: str) -> tuple[list[np.ndarray], list[int], float, str, int]:
    """Validate simultaneous records: ``(phases scaled by 2**-k, ks, rate, data_type, N phase points)``.

    Each phase has its linear trend removed (the filters ignore it) to keep round-off small.
    """
    rate_f = check_rate(rate)
    dtype = check_data_type(data_type)
    series = [as_series(r, name) for r, name in zip(records, names)]
    sizes = {s.size for s in series}
    if len(sizes) > 1:
        listing = ", ".join(f"{n}: {s.size}" for n, s in zip(names, series))
        raise DataError(f"the records must have the same length, got {listing}")
    n_points = series[0].size + (dtype == "freq")
    if n_points < _MIN_POINTS[statistic]:
        raise DataError(f"{statistic} covariance needs at least {_MIN_POINTS[statistic]} phase points, got {n_points}")
    phases, ks = [], []
    for s in series:
        v, k = scale_to_unit(s)
        x = to_phase(v - v.mean(), rate_f, dtype) if dtype == "freq" else remove_linear_phase(v)
        phases.append(x)
        ks.append(k)
    return phases, ks, rate_f, dtype, n_points


def factors(statistic: str, n_points: int, rate: float, taus: object, m: object, points_per_decade: int) -> np.ndarray:
    """Averaging factors for the τ grid, as every statistic of sigmatau chooses them."""
    return select_m(statistic, n_points=n_points, rate=rate, taus=taus, m=m, points_per_decade=points_per_decade,
                    m_min=1, m_max=_MAX_M[statistic](n_points), stop_ratio=STOP_RATIOS[statistic])


def covariance_matrices(phases: Sequence[np.ndarray], ms: np.ndarray, tau0: float,
                        statistic: str) -> tuple[np.ndarray, np.ndarray]:
    """``(S, n)``: the K×K matrix of statistic (co)variances of K phase series at each factor.

    ``S[j, p, q] = c·Σ_i z_p,i z_q,i / (n_j τ_j²)``, O(N·K²) per τ. Scaling (the 2**-k of
    :func:`checked_records`) is left to the caller.
    """
    k = len(phases)
    out = np.empty((ms.size, k, k))
    counts = np.empty(ms.size, dtype=np.int64)
    for j, mm in enumerate(ms):
        parts = [filtered(x, int(mm), statistic) for x in phases]
        z = np.stack([p[0] for p in parts], axis=1)
        n = z.shape[0]
        out[j] = parts[0][1] * (z.T @ z) / (n * (mm * tau0) ** 2)
        counts[j] = n
    return out, counts


def gcodev(
    a: object,
    b: object,
    *,
    rate: float = 1.0,
    data_type: DataType = "phase",
    taus: object = "octave",
    m: object = None,
    points_per_decade: int = 10,
    statistic: CovStatistic = "oadev",
) -> CovarianceResult:
    r"""Groslambert covariance (GCoDev) of two simultaneous series, signed.

    Parameters
    ----------
    a, b : array_like
        Two records of equal length, typically differences ``x_A − x_B`` and
        ``x_B − x_C`` that share device B (NaN refused).
    rate : float
        Sample rate in Hz (τ0 = 1/rate).
    data_type : {"phase", "freq"}
        Phase (time error, s) or fractional frequency.
    taus, m, points_per_decade
        τ grid, as for every statistic (:func:`sigmatau.core.taus.select_m`).
    statistic : {"oadev", "adev", "mdev", "hdev", "ohdev"}
        Whose covariance form to use; the default is Groslambert's (overlapping Allan).

    Returns
    -------
    CovarianceResult

    Notes
    -----
    With second differences of the phase at lag m, ``Δ²x_i = x_{i+2m} − 2x_{i+m} + x_i``,

    .. math::

        \operatorname{GCov}(τ) = \frac{1}{2τ^2(N-2m)}\sum_{i=0}^{N-2m-1} Δ^2a_i\,Δ^2b_i ,

    and ``dev = sign(GCov)·sqrt(|GCov|)``. ``gcodev(a, a)`` is OAVAR of ``a``.
    For independent clocks, ``E[GCov(x_A − x_B, x_B − x_C)] = −σ_B²(τ)``: the
    covariance isolates the shared device without the negative variances of
    the three-cornered hat's differences, but it is itself a signed estimate.
    The other statistics use their own filters (third differences for the
    Hadamard family, the m-sample moving sum of second differences for MDEV).

    References
    ----------
    F. Vernotte, C. E. Calosso, E. Rubiola, "Three-cornered hat versus
    Allan covariance", Proc. IFCS 2016. F.-X. Lantz, C. E. Calosso, E. Rubiola,
    V. Giordano, F. Vernotte, "KLTS: a rigorous method to compute the confidence
    intervals for the three-cornered hat and for Groslambert covariance",
    IEEE TUFFC 66(12), 2019.

    Examples
    --------
    >>> import numpy as np
    >>> x = np.array([0.0, 1.0, 0.0, 1.0, 0.0])
    >>> r = gcodev(x, -x, m=1)
    >>> float(r.cov[0]), float(r.dev[0])
    (-2.0, -1.4142135623730951)
    """
    stat = check_statistic(statistic)
    (xa, xb), (ka, kb), rate_f, _, n_points = checked_records([a, b], ["a", "b"], rate, data_type, stat)
    ms = factors(stat, n_points, rate_f, taus, m, points_per_decade)
    if ms.size == 0:
        raise DataError(f"{stat}: no averaging factor fits {n_points} phase points")
    s, n = covariance_matrices([xa, xb], ms, 1.0 / rate_f, stat)
    cov = np.ldexp(s[:, 0, 1], ka + kb)
    dev = np.sign(cov) * np.sqrt(np.abs(cov))
    return CovarianceResult(stat, ms / rate_f, ms, cov, dev, n)
