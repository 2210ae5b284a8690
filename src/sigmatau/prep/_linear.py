"""Estimators that are linear in the data: polynomial least squares and block-mean contrasts.

Each returns the estimate together with its weights over the whole record (zero at gaps),
from which :func:`sigmatau.prep._common.functional_variance` gives the standard error.
"""

from __future__ import annotations

from math import comb

import numpy as np

from ..errors import DataError

__all__ = ["poly_fit", "block_fit", "second_difference_mean"]


def _scaled_time(t: np.ndarray, valid: np.ndarray) -> tuple[np.ndarray, float, float]:
    """``u = (t − tc)/h`` on [−1, 1] over the valid samples, with its centre and half-span."""
    tv = t[valid]
    tc = 0.5 * (tv[0] + tv[-1])
    h = 0.5 * (tv[-1] - tv[0]) or 1.0
    return (t - tc) / h, tc, h


def poly_fit(v: np.ndarray, t: np.ndarray, deg: int) -> tuple[np.ndarray, np.ndarray]:
    """Least-squares polynomial ``v ≈ Σ_k α_k t^k`` over the valid samples.

    Returns
    -------
    alpha : numpy.ndarray
        ``deg + 1`` coefficients, constant first, in powers of ``t`` itself.
    weights : numpy.ndarray
        ``(deg + 1, n)``: ``alpha = weights @ v`` with gaps taken as 0.
    """
    valid = ~np.isnan(v)
    u, tc, h = _scaled_time(t, valid)
    a = np.vander(u[valid], deg + 1, increasing=True)
    q, r = np.linalg.qr(a)
    w_u = np.linalg.solve(r, q.T)  # β = w_u @ v_valid, β in powers of u
    # Σ_j β_j ((t − tc)/h)^j = Σ_k α_k t^k: α = L β.
    lmat = np.zeros((deg + 1, deg + 1))
    for j in range(deg + 1):
        for k in range(j + 1):
            lmat[k, j] = comb(j, k) * (-tc) ** (j - k) / h ** j
    weights = np.zeros((deg + 1, v.size))
    weights[:, valid] = lmat @ w_u
    alpha = weights @ np.where(valid, v, 0.0)
    return alpha, weights


def block_fit(v: np.ndarray, t: np.ndarray, blocks: list[np.ndarray], deg: int,
              name: str = "the estimator") -> tuple[float, np.ndarray]:
    """The coefficient of the highest power, exact for a polynomial of degree ``deg``, from block means.

    ``blocks`` are index arrays (``deg + 1`` of them); each block contributes the mean of its
    valid samples ``v̄_k = Σ_j α_j mean_k(t^j)``, and the ``deg + 1`` equations are solved for
    the leading coefficient: for a quadratic, ``v̄_k = a + b·t̄_k + (D/2)·mean_k(t²)`` gives D/2.

    Returns
    -------
    lead : float
        The leading coefficient (in powers of ``t``).
    weights : numpy.ndarray
        ``lead = weights @ v`` with gaps taken as 0.
    """
    valid = ~np.isnan(v)
    u, _tc, h = _scaled_time(t, valid)
    rows, means = [], []
    for k, block in enumerate(blocks):
        idx = block[valid[block]]
        if idx.size == 0:
            raise DataError(f"block {k + 1} of {name} (samples {int(block[0])} … {int(block[-1])})"
                            " holds no valid sample")
        rows.append([np.mean(u[idx] ** j) for j in range(deg + 1)])
        means.append(idx)
    inv = np.linalg.inv(np.array(rows))
    weights = np.zeros(v.size)
    for k, idx in enumerate(means):
        weights[idx] += inv[deg, k] / idx.size
    # The leading coefficient in u is h**deg times that in t.
    weights /= h ** deg
    lead = float(weights @ np.where(valid, v, 0.0))
    return lead, weights


def second_difference_mean(v: np.ndarray) -> tuple[float, np.ndarray, int]:
    """The mean of the gap-free second differences ``v_{i+2} − 2v_{i+1} + v_i``, its weights and count."""
    d = v[2:] - 2.0 * v[1:-1] + v[:-2]
    ok = ~np.isnan(d)
    n = int(ok.sum())
    if n == 0:
        raise DataError("no gap-free second difference (three consecutive valid samples) in data")
    weights = np.convolve(ok.astype(np.float64), [1.0, -2.0, 1.0]) / n
    return float(np.mean(d[ok])), weights, n
