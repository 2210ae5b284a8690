"""Built-in example data sets with published reference values.

* :func:`nbs1000` — the 1000-point NBS frequency test set of NIST SP 1065
  (W. J. Riley's test suite), generated from its Park–Miller congruential
  generator, so it needs no file.
* :func:`nbs9` — the 9-point frequency set of NBS Monograph 140 (SP 1065 Table 30).
"""

from __future__ import annotations

import numpy as np

__all__ = ["nbs1000", "nbs9"]

_LCG_MODULUS = 2147483647  # 2**31 - 1
_LCG_MULTIPLIER = 16807
_LCG_SEED = 1234567890


def nbs1000() -> np.ndarray:
    """The NBS 1000-point fractional-frequency test set (τ0 = 1 s).

    Notes
    -----
    Park–Miller "minimal standard" generator:
    ``n_0 = 1234567890``, ``n_{i+1} = 16807·n_i mod (2^31 − 1)``,
    ``y_i = n_i/(2^31 − 1)`` for i = 0 … 999 (``y_0`` uses the seed itself).

    References
    ----------
    W. J. Riley, NIST SP 1065 (2008), test suite, Table 31; numerics.md §7.1.

    Examples
    --------
    >>> from sigmatau.datasets import nbs1000
    >>> y = nbs1000()
    >>> y.size, round(float(y[1]), 10)
    (1000, 0.1841829699)
    """
    values = np.empty(1000, dtype=np.int64)
    n = _LCG_SEED
    for i in range(1000):
        values[i] = n
        n = (_LCG_MULTIPLIER * n) % _LCG_MODULUS
    return values / float(_LCG_MODULUS)


def nbs9() -> np.ndarray:
    """The NBS Monograph 140 9-point frequency set (τ0 = 1 s), SP 1065 Table 30.

    Examples
    --------
    >>> from sigmatau.datasets import nbs9
    >>> nbs9().tolist()
    [892.0, 809.0, 823.0, 798.0, 671.0, 644.0, 883.0, 903.0, 677.0]
    """
    return np.array([892, 809, 823, 798, 671, 644, 883, 903, 677], dtype=float)
