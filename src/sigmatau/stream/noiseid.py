"""Noise identification of a stream: the rules of :func:`sigmatau.noiseid.identify`, from running state.

The batch identification reads the whole record at every averaging factor m
(numerics.md §5.2–§5.5). What it reads can be kept as the samples arrive:

* **lag-1 autocorrelation** of the analysis series (phase decimated, ``z_k = x_{km}``;
  frequency averaged over blocks of m) differenced d = 0 … dmax times: the
  running moments of :class:`Lag1Moments` give the batch's centred sums,
  ``Σ(z−z̄)² = S₂ − S₁z̄`` and ``Σ(z_k−z̄)(z_{k+1}−z̄) = S₁₁ − z̄(2S₁ − z_0 − z_{n−1}) + (n−1)z̄²``
  with every z less its series' first value (the provisional offset that keeps
  S₂ − S₁z̄ free of cancellation), and the batch's own
  :func:`~sigmatau.uncertainty.lag1.difference_until_white` and
  :func:`~sigmatau.uncertainty.lag1.lag1_alpha` decide;
* **B1** is applied only while fewer than 30 averages exist at m (the lag-1 method
  takes over from there): :class:`B1Blocks` keeps the first 30 block means of m
  samples (and of their differences, for the Hadamard family), computed from the raw
  samples exactly as the batch computes them, so the observed ratio is the batch's to
  the last bit;
* **R(n) = MVAR/OAVAR** comes from the stream's own sums (:func:`identify_rows`'s ``rn``).

:func:`identify_rows` then applies Stable32's per-τ decision, the carry-forward and
the family's α range exactly as :func:`sigmatau.noiseid.identify` does.
"""

from __future__ import annotations

import math
from typing import Callable, Optional, Sequence

import numpy as np

from ..errors import DataError
from ..uncertainty.lag1 import difference_until_white, lag1_alpha
from ..uncertainty.noiseid import (
    FAMILY_ALIASES, FAMILY_RULES, LAG1_MIN_POINTS, InsufficientDataError, b1_classify, b1_min_averages, b1_observed,
    rn_alpha,
)
from .buffers import CompensatedSums, Ring, rowdot

__all__ = ["Lag1Moments", "B1Blocks", "identify_rows", "B1_LIMIT"]

#: Block means kept per factor for B1: identify applies B1 only where fewer than
#: LAG1_MIN_POINTS (30) points remain, i.e. with at most 29 averages.
B1_LIMIT = LAG1_MIN_POINTS


class Lag1Moments:
    """Running moments of one factor's analysis series and of its differences (orders 0 … depth−1).

    Call with the new points of the order-0 series (``(channels, k)``), in order;
    :meth:`r1` returns the lag-1 autocorrelation of order d, as
    ``uncertainty.lag1`` computes it from the whole series.
    """

    def __init__(self, channels: int, depth: int) -> None:
        self.depth = depth
        self.shift = np.zeros((channels, depth))  # each order's first value
        self.last = np.zeros((channels, depth))  # each order's last value, less its shift
        self.tail = np.zeros((channels, depth))  # each order's last value, as is (to difference on)
        self.count = [0] * depth
        self.sums = CompensatedSums((channels, depth, 3))  # Σw, Σw², Σw_k·w_{k+1}

    def __call__(self, z: np.ndarray) -> None:
        parts = np.zeros(self.sums.hi.shape)
        new, below_had, below_tail = z, False, None
        for d in range(self.depth):
            if d:
                ext = np.concatenate((below_tail[:, None], new), axis=1) if below_had else new
                new = ext[:, 1:] - ext[:, :-1]
            had, tail = self.count[d] > 0, self.tail[:, d].copy()
            if new.shape[1]:
                self._moments(d, new, had, parts)
            below_had, below_tail = had, tail
        self.sums.add(parts)

    def _moments(self, d: int, v: np.ndarray, had: bool, parts: np.ndarray) -> None:
        if not had:
            self.shift[:, d] = v[:, 0]
        w = v - self.shift[:, d, None]
        parts[:, d, 0] = np.add.reduce(w, axis=1)
        parts[:, d, 1] = rowdot(w, w)
        lag = rowdot(w[:, :-1], w[:, 1:])
        if had:
            lag = lag + self.last[:, d] * w[:, 0]
        parts[:, d, 2] = lag
        self.last[:, d] = w[:, -1]
        self.tail[:, d] = v[:, -1]
        self.count[d] += v.shape[1]

    def r1(self, channel: int, d: int) -> float:
        """Lag-1 autocorrelation of the order-d series (DataError if it is constant)."""
        n = self.count[d]
        s1, s2, s11 = (float(v) for v in self.sums.total()[channel, d])
        mean = s1 / n
        den = s2 - s1 * mean
        if n < 2 or den <= 0.0:
            raise DataError("the series is constant at this averaging factor; its autocorrelation is undefined")
        # the first value, less the shift, is 0
        num = s11 - mean * (2.0 * s1 - float(self.last[channel, d])) + (n - 1) * mean * mean
        return num / den

    @property
    def nbytes(self) -> int:
        return int(self.shift.nbytes * 3 + self.sums.nbytes)


class B1Blocks:
    """The first :data:`B1_LIMIT` block means of m samples at each factor (and of their differences).

    Read from the raw frequency samples (phase data differenced) and averaged with
    the batch's own operation, ``reshape(k, m).mean(axis=1)``, so each mean carries
    the same bits as :func:`sigmatau.noiseid.b1_ratio`'s.
    """

    def __init__(self, channels: int, factors: Sequence[int], hadamard: bool) -> None:
        self.factors = list(factors)
        self.means = np.zeros((channels, len(self.factors), B1_LIMIT))
        self.count = [0] * len(self.factors)
        self.hadamard = hadamard
        self.dmeans = np.zeros_like(self.means) if hadamard else None
        self.dcount = [0] * len(self.factors)

    def update(self, raw: Ring, m_total: int) -> None:
        """Average the blocks completed by ``m_total`` samples (held in ``raw``)."""
        for level, p in enumerate(self.factors):
            if self.count[level] == B1_LIMIT and (not self.hadamard or self.dcount[level] == B1_LIMIT):
                continue
            ka, kb = self.count[level], min(m_total // p, B1_LIMIT)
            if kb > ka:
                v = raw.read(ka * p, kb * p)
                self.means[:, level, ka:kb] = v.reshape(v.shape[0], kb - ka, p).mean(axis=2)
                self.count[level] = kb
            if self.hadamard and m_total >= 1:
                ka, kb = self.dcount[level], min((m_total - 1) // p, B1_LIMIT)
                if kb > ka:
                    v = np.diff(raw.read(ka * p, kb * p + 1), axis=1)
                    self.dmeans[:, level, ka:kb] = v.reshape(v.shape[0], kb - ka, p).mean(axis=2)
                    self.dcount[level] = kb

    def observed(self, channel: int, level: int, differenced: bool) -> tuple[float, int]:
        """:func:`sigmatau.noiseid.b1_observed` of the kept means (the batch's ratio and Nb)."""
        if differenced:
            return b1_observed(self.dmeans[channel, level, : self.dcount[level]].copy(), 1)
        return b1_observed(self.means[channel, level, : self.count[level]].copy(), 1)

    @property
    def nbytes(self) -> int:
        return int(self.means.nbytes + (0 if self.dmeans is None else self.dmeans.nbytes))


def _b1(blocks: B1Blocks, channel: int, level: int, m: int, hadamard: bool,
        n_expected: int) -> tuple[int, float, bool]:
    """:func:`sigmatau.noiseid.b1_noise_id`: (α, α̂, ambiguous); DataError when B1 cannot decide."""
    ratio, nb = blocks.observed(channel, level, False)
    if nb < 3:
        raise InsufficientDataError(f"B1 noise identification needs at least 3 averages at m={m}, got {nb}")
    mu, mu_hat = b1_classify(ratio, nb, n_expected)
    if hadamard and mu >= 1:
        # second pass on the differenced frequency: FWFM and RRFM seen as FFM and RWFM
        try:
            ratio2, nb2 = blocks.observed(channel, level, True)
        except DataError:
            nb2 = 0
        if nb2 >= 3:
            mu2, mu2_hat = b1_classify(ratio2, nb2, n_expected)
            mu, mu_hat = min(max(mu2 + 2, 1), 3), min(max(mu2_hat + 2.0, 1.0), 3.0)
    return (1 if mu == -2 else -mu - 1), -mu_hat - 1.0, mu == -2


def _rn_split(rn: Callable[[int], float], m: int) -> Optional[tuple[int, float]]:
    """WPM or FPM from R(n), as :func:`sigmatau.uncertainty.noiseid.identify` splits them."""
    try:
        value = rn(m)
    except DataError:
        return None
    return rn_alpha(value, m)


def _carried_from(done: list[int], ms: Sequence[int], i: int) -> int:
    """The row whose α row ``i`` takes: the largest identified factor below it, else the nearest."""
    below = [j for j in done if ms[j] < ms[i]]
    if below:
        return max(below, key=lambda j: ms[j])
    return min(done, key=lambda j: (abs(math.log(ms[j] / ms[i])), -ms[j]))


def identify_rows(statistic: str, ms: Sequence[int], n_terms: Sequence[int], *, data_type: str, size: int,
                  n_freq: int, lag1: Callable[[int], Lag1Moments], blocks: B1Blocks, level_of: Callable[[int], int],
                  channel: int, rn: Callable[[int], float]) -> tuple[np.ndarray, np.ndarray]:
    """``(alpha, alpha_estimate)`` at each factor of ``ms`` by the rules of :func:`sigmatau.noiseid.identify`.

    ``size`` is the number of samples as given (phase or frequency), ``n_freq`` that
    of frequency samples, ``lag1(level)`` the moments of a factor, ``rn(m)`` R(n) at m
    (DataError when undefined). Raises DataError where ``identify`` does: a constant
    series, an exactly alternating one, no row identified.
    """
    dmax, lo, hi = FAMILY_RULES[FAMILY_ALIASES[statistic]]
    hadamard = FAMILY_ALIASES[statistic] == "hadamard"
    min_averages = b1_min_averages(statistic)
    alpha = np.zeros(len(ms), dtype=np.int64)
    est = np.full(len(ms), np.nan)
    done: list[int] = []
    for i, m in enumerate(ms):
        level = level_of(m)
        if size // m >= LAG1_MIN_POINTS:
            moments = lag1(level)
            d, delta, _ = difference_until_white(lambda k: moments.r1(channel, k), m, 0, dmax)
            alpha[i], est[i] = lag1_alpha(d, delta, data_type)
        elif n_freq // m >= min_averages:
            try:
                a, e, ambiguous = _b1(blocks, channel, level, m, hadamard, int(n_terms[i]))
            except DataError:
                continue
            split = _rn_split(rn, m) if ambiguous else None
            alpha[i], est[i] = split if split is not None else (a, e)
        else:
            continue
        done.append(i)
    for i in range(len(ms)):
        if i not in done:
            if not done:
                raise InsufficientDataError(
                    f"no averaging factor in ms leaves enough data ({size} points) for any method")
            alpha[i] = alpha[_carried_from(done, ms, i)]
    return np.clip(alpha, lo, hi).astype(float), est
