"""Small numeric building blocks shared by the estimator kernels."""

from __future__ import annotations

import numpy as np

__all__ = ["sumsq", "dot", "window_sums", "block_means"]


def sumsq(v: np.ndarray) -> float:
    """Σ v_i² without BLAS.

    ``np.dot`` dispatches to a threaded BLAS whose threads stall on a busy
    machine (9x slower than this on the 2-core reference machine); einsum runs
    in the calling thread.
    """
    return float(np.einsum("i,i->", v, v))


def dot(a: np.ndarray, b: np.ndarray) -> float:
    """Σ a_i·b_i without BLAS (see :func:`sumsq`)."""
    return float(np.einsum("i,i->", a, b))


def window_sums(v: np.ndarray, m: int) -> np.ndarray:
    """Sums of ``m`` consecutive values of ``v`` (``v.size - m + 1`` of them), in O(N).

    ``v`` is always a difference series in the kernels, so its running sum stays
    of the order of a few window sums and the subtraction loses no significant
    digits.
    """
    if m == 1:
        return v.copy()
    c = np.empty(v.size + 1)
    c[0] = 0.0
    np.cumsum(v, out=c[1:])
    return c[m:] - c[:-m]


def block_means(y: np.ndarray, m: int) -> np.ndarray:
    """Means of the ``⌊M/m⌋`` non-overlapped blocks of ``m`` samples starting at 0."""
    k = y.size // m
    return y[: k * m].reshape(k, m).mean(axis=1)
