"""Missing samples (gaps, marked NaN) in the statistics.

A missing sample is NaN, Stable32's convention for gaps. Every statistic uses
each term whose samples are all present and only those:

* **phase data**: a term reads the phase points of its definition; it is used
  when every one of them is present. For the Allan and Hadamard variances, TIE
  rms, STDEV/OSTDEV and TOTDEV (on the record extended by reflection at its two
  ends) that is the 2 to 4 points ``x_i, x_{i+m}, …`` (as allantools'
  gap-resistant ``gradev``); the modified, MTOT/TTOT/HTOT and Theo families read
  every point of their window ``x_i … x_{i+L-1}``.
* **frequency data**: a missing frequency sample leaves the phase after it
  unknown by a constant, so a term is used only when the whole window of
  frequency samples it spans is present.

``n`` counts the terms used. The EDF is that of a contiguous record giving as
many terms (:func:`equivalent_points`), which is how the interval follows from
the terms actually used.

Two ways of computing this are provided here for the statistics' kernels:

* :func:`pooled_over_runs`: estimators whose terms read whole windows are
  evaluated on every gap-free run with their ordinary kernel and pooled,
  ``var = Σ_s var_s·n_s / Σ_s n_s`` (every estimator here is a mean of its terms
  times a factor that depends on m and τ0 only), or the largest value for MTIE.
  A window inside a run is exactly a window free of gaps, so this is the plain
  definition restricted to gap-free terms (MTOT, TTOT and HTOT included: each of
  their terms extends its own window). TOTDEV on frequency data, pooled this way,
  extends each run at its own ends: its extension exists to use every window of a
  record, and a gap ends the record it extends.
* statistic-specific kernels that let NaN propagate through the points a term
  reads (:func:`nan_terms_variance`), for the point-wise phase statistics and the
  non-overlapped estimators, whose blocks stay on the record's own grid.
"""

from __future__ import annotations

from typing import Callable, Iterable, Optional

import numpy as np

from .shared import derived

__all__ = [
    "GapKernel", "missing_mask", "present_runs", "pooled_over_runs", "nan_terms_variance",
    "equivalent_points", "detrended_phase", "point_kernel", "block_kernel", "window_mean_kernel",
]

#: ``kernel(series, ms, tau0) -> (var, n, n_equivalent)`` on samples holding NaN gaps.
GapKernel = Callable[[np.ndarray, np.ndarray, float], "tuple[np.ndarray, np.ndarray, np.ndarray]"]


def missing_mask(series: np.ndarray) -> Optional[np.ndarray]:
    """Boolean mask of the NaN samples of ``series``, or None when none is missing.

    Computed once per :func:`~sigmatau.core.shared.shared_record` scope for the scope's record.
    """
    def make() -> Optional[np.ndarray]:
        mask = np.isnan(series)
        return mask if mask.any() else None

    return derived(series, ("missing",), make)


def present_runs(missing: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Start and stop (exclusive) indices of the runs of present samples, in order.

    Examples
    --------
    >>> import numpy as np
    >>> s, e = present_runs(np.array([False, False, True, False, True, True, False]))
    >>> s.tolist(), e.tolist()
    ([0, 3, 6], [2, 4, 7])
    """
    present = np.concatenate(([False], ~missing, [False])).astype(np.int8)
    edges = np.diff(present)
    return np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)


def pooled_over_runs(
    kernel: Callable[[np.ndarray, np.ndarray, float], "tuple[np.ndarray, np.ndarray]"],
    runs: Iterable[np.ndarray],
    points_of: Callable[[int], int],
    max_m: Callable[[int], int],
    min_points: int,
    ms: np.ndarray,
    tau0: float,
    *,
    pooling: str = "mean",
    terms_per_point: Optional[Callable[[np.ndarray], np.ndarray]] = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """An estimator over the gap-free runs of a record, pooled.

    Parameters
    ----------
    kernel : callable
        ``kernel(run, ms, tau0) -> (var, n)``, the statistic's ordinary kernel.
    runs : iterable of numpy.ndarray
        The gap-free runs, each already in the form the kernel takes.
    points_of : callable
        Number of phase points N of a run of a given length (the length, or
        length + 1 for frequency samples).
    max_m, min_points
        The statistic's largest factor for N points and fewest points.
    ms : numpy.ndarray
        Averaging factors.
    pooling : {"mean", "max"}
        ``"mean"``: ``Σ var_s·n_s / Σ n_s``; ``"max"``: the largest (MTIE).
    terms_per_point : callable, optional
        Terms each added phase point brings at each factor, ``dn/dN`` (1 unless
        given; m/2 for Theo1, whose n counts the (i, δ) pairs).

    Returns
    -------
    var, n, n_equivalent : numpy.ndarray
        Pooled variance (NaN where no run holds a term), terms used, and the
        phase points of a contiguous record with as many terms,
        ``N_s + (n − n_s)/(dn/dN)`` for any run s that has terms at that factor
        (each estimator's n is affine in N).
    """
    total = np.zeros(ms.size)
    count = np.zeros(ms.size, dtype=np.int64)
    last_points = np.zeros(ms.size, dtype=np.int64)
    last_n = np.zeros(ms.size, dtype=np.int64)
    for run in runs:
        points = points_of(run.size)
        if points < min_points:
            continue
        use = np.flatnonzero(ms <= max_m(points))
        if use.size == 0:
            continue
        var, n = kernel(run, ms[use], tau0)
        var, n = np.asarray(var, dtype=float), np.asarray(n, dtype=np.int64)
        if pooling == "max":
            total[use] = np.maximum(total[use], var)
        else:
            total[use] += var * n
        count[use] += n
        last_points[use] = points
        last_n[use] = n
    with np.errstate(invalid="ignore", divide="ignore"):
        var = total / count if pooling == "mean" else np.where(count > 0, total, np.nan)
    slope = np.ones(ms.size) if terms_per_point is None else np.asarray(terms_per_point(ms), dtype=float)
    n_eq = np.rint(last_points + (count - last_n) / slope).astype(np.int64)
    return np.where(count > 0, var, np.nan), count, np.where(count > 0, n_eq, 0)


def nan_terms_variance(terms: np.ndarray, scale: float) -> tuple[float, int]:
    """``Σ t² / (scale·n)`` over the finite terms ``t`` (NaN marks a term that reads a gap), and n."""
    ok = terms[~np.isnan(terms)]
    n = int(ok.size)
    if n == 0:
        return float("nan"), 0
    return float(np.dot(ok, ok)) / (scale * n), n


def equivalent_points(n_points: int, n_candidates: int, n_used: int, stride: int = 1) -> int:
    """Phase points of a contiguous record giving ``n_used`` terms where ``n_points`` give
    ``n_candidates``: each term lost takes ``stride`` points (m for non-overlapped blocks)."""
    return int(n_points - (n_candidates - n_used) * stride)


def detrended_phase(x: np.ndarray) -> np.ndarray:
    """Phase with gaps minus the line through its first and last present points.

    The counterpart of :func:`~sigmatau.core.validate.remove_linear_phase` for a
    record with gaps: it removes the mean frequency, which the trend-invariant
    statistics ignore, to keep the phase and its round-off small.
    """
    present = np.flatnonzero(~np.isnan(x))
    if present.size < 2:
        return x - x[present[0]] if present.size else x
    i0, i1 = int(present[0]), int(present[-1])
    slope = (x[i1] - x[i0]) / (i1 - i0)
    return (x - x[i0]) - slope * (np.arange(x.size, dtype=float) - i0)


def point_kernel(coeffs: tuple[float, ...], scale: float, *, blocks: bool = False,
                 centred: bool = False, per_tau: bool = True) -> GapKernel:
    """Gap kernel of a phase estimator whose terms combine a few points ``m`` apart.

    The term at i is ``Σ_j c_j x_{i+jm}`` (``blocks=True``: only i = 0, m, 2m …,
    the non-overlapped estimators); it is NaN, and left out, when one of its points
    is missing. The variance is ``Σ t² / (scale·(mτ0)²·n)`` over the n terms present
    (``Σ t² / (scale·n)`` without ``per_tau``: TIE rms), or with ``centred`` the sample
    variance of the terms over ``scale·(mτ0)²`` (the standard deviation).
    """
    span = len(coeffs) - 1

    def kernel(x: np.ndarray, ms: np.ndarray, tau0: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        var, n, neq = np.empty(ms.size), np.zeros(ms.size, dtype=np.int64), np.zeros(ms.size, dtype=np.int64)
        for i, m in enumerate(ms.tolist()):
            xs, step = (x[: ((x.size - 1) // m) * m + 1 : m], 1) if blocks else (x, m)
            k = xs.size - span * step
            if k <= 0:
                var[i], n[i], neq[i] = np.nan, 0, 0
                continue
            t = sum(c * xs[j * step: j * step + k] for j, c in enumerate(coeffs))
            var[i], n[i] = _variance_of_terms(t, scale * (m * tau0) ** 2 if per_tau else scale, centred)
            neq[i] = equivalent_points(x.size, k, int(n[i]), m if blocks else 1)
        return var, n, neq

    return kernel


def block_kernel(coeffs: tuple[float, ...], scale: float, *, centred: bool = False) -> GapKernel:
    """Gap kernel of a non-overlapped estimator on frequency samples: the block sums of m
    samples on the record's own grid (a block holding a gap is missing), combined as
    ``Σ_j c_j S_{k+j}``; the variance is ``Σ t² / (scale·m²·n)`` (or the sample variance of
    the block sums with ``centred``)."""
    span = len(coeffs) - 1

    def kernel(y: np.ndarray, ms: np.ndarray, tau0: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        var, n, neq = np.empty(ms.size), np.zeros(ms.size, dtype=np.int64), np.zeros(ms.size, dtype=np.int64)
        for i, m in enumerate(ms.tolist()):
            nb = y.size // m
            b = y[: nb * m].reshape(nb, m).sum(axis=1)
            k = nb - span
            if k <= 0:
                var[i], n[i], neq[i] = np.nan, 0, 0
                continue
            t = sum(c * b[j: j + k] for j, c in enumerate(coeffs))
            var[i], n[i] = _variance_of_terms(t, scale * float(m) ** 2, centred)
            neq[i] = equivalent_points(y.size + 1, k, int(n[i]), m)
        return var, n, neq

    return kernel


def window_mean_kernel() -> GapKernel:
    """Gap kernel of the overlapped standard variance on frequency samples: the sample
    variance of the sums of every window of m samples free of gaps, over m²."""
    def kernel(y: np.ndarray, ms: np.ndarray, tau0: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        filled = np.where(np.isnan(y), 0.0, y)
        c = np.concatenate(([0.0], np.cumsum(filled)))
        g = np.concatenate(([0], np.cumsum(np.isnan(y))))
        var, n, neq = np.empty(ms.size), np.zeros(ms.size, dtype=np.int64), np.zeros(ms.size, dtype=np.int64)
        for i, m in enumerate(ms.tolist()):
            sums = np.where(g[m:] - g[:-m] == 0, c[m:] - c[:-m], np.nan)
            var[i], n[i] = _variance_of_terms(sums, float(m) ** 2, True)
            neq[i] = equivalent_points(y.size + 1, sums.size, int(n[i]))
        return var, n, neq

    return kernel


def _variance_of_terms(t: np.ndarray, scale: float, centred: bool) -> tuple[float, int]:
    if not centred:
        return nan_terms_variance(t, scale)
    ok = t[~np.isnan(t)]
    if ok.size < 2:
        return float("nan"), 0
    d = ok - ok.mean()
    return float(np.dot(d, d)) / (scale * (ok.size - 1)), int(ok.size)

