"""Cornered hats: each device's own stability from the comparisons between N ≥ 3 devices.

At each τ the data are reduced to one small matrix: the K × K (K = N − 1) matrix
``S`` of statistic (co)variances of the differences ``d_p = x_p − x_0`` against
the first device, computed from sums of products of filtered series
(:func:`sigmatau.compare.covariance.covariance_matrices`, O(N_samples·K²) per τ).
For independent devices its expectation is

.. math:: Σ_{pq} = σ_0^2 + δ_{pq}\\,σ_p^2 ,

and every pairwise variance is a linear function of it,
``σ²_{pq} = Σ_pp + Σ_qq − 2Σ_pq`` (with ``Σ_0· = 0``).

*Classical estimate* (signed): the least-squares solution of
``σ²_{pq} = σ_p² + σ_q²`` over all pairs. For three devices it is the textbook
three-cornered hat ``σ_A² = ½(σ_AB² + σ_CA² − σ_BC²)``, identical to the
Groslambert covariance ``−GCov(x_A − x_B, x_C − x_A)``; it is negative whenever
sampling noise exceeds a device's share.

*Positive estimate and interval* (frequentist, Feldman–Cousins). ``ν·S`` is
taken as Wishart with ν degrees of freedom, ν the EDF of the statistic for the
noise type (:func:`sigmatau.uncertainty.confidence.edf`). Each classical
estimate is linear in S, ``θ̂_p = tr(A_p S)``, so for given true variances it is
distributed exactly as a weighted sum of independent χ² variables,

.. math:: θ̂_p \\sim \\sum_i λ_i\\,χ^2_{ν,i}/ν ,\\qquad λ = \\operatorname{eig}(Σ^{1/2} A_p Σ^{1/2}),

with mean ``θ_p`` (the Karhunen–Loève decomposition of Lantz et al.). Its
density is obtained by inverting the characteristic function
``Π_i (1 − 2iλ_i s/ν)^(−ν/2)`` with an FFT, on a grid of ``θ_p ≥ 0`` (the other
devices held at their classical estimates clipped at 0). The interval is the
Feldman–Cousins confidence belt for a parameter bounded below by zero
(likelihood-ratio ordering against the best ``θ ≥ 0``): it never leaves
``θ ≥ 0``, is never empty, turns by itself from a two-sided interval into an
upper limit (low = 0) when the data cannot tell the device from zero, and keeps
the nominal coverage right down to the boundary. The point estimate is the
maximum of the same likelihood over ``θ_p ≥ 0`` (≥ 0; exactly 0 when the
classical estimate lies far below zero). Deviations are the square roots.

This follows the KLTS approach of F.-X. Lantz et al. (IEEE TUFFC 66(12), 2019):
the exact law of the estimate as a combination of χ² variables from the
Karhunen–Loève decomposition of the covariance; the ordering rule that keeps the
interval inside ``θ ≥ 0`` is that of G. J. Feldman and R. D. Cousins, Phys. Rev.
D 57, 3873 (1998). The code is our own.

Assumptions and how it degrades:

* the devices are independent; a correlated pair (a common environment not
  shared by all) biases the estimates as it does the classical hat;
* the Wishart law with one ν is exact for independent samples and a very good
  approximation when all devices have the same noise type; when their noise
  types differ, ν (identified on the difference between the second and first
  device, unless ``alpha`` is given) is only approximately right, and at long τ
  the noise identification of a short record may misname the noise (pass
  ``alpha`` when it is known);
* the other devices' variances enter the law as plug-in estimates; their
  sampling noise widens the law slightly, so coverage errs on the high side
  (measured in tests/test_compare.py);
* for N ≥ 4 the classical estimate is the least-squares one, not the
  maximum-likelihood one: still exact in law, but not the narrowest possible;
* ν comes from sigmatau's EDF; where that EDF departs from the exact EDF of the
  sampled noise (Greenhall's model for the unmodified statistics at m < 16,
  docs/compare.md) the intervals are off by the same factor.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Optional, Sequence

import numpy as np

from ..core.validate import as_series
from ..errors import DataError, ParameterError, RangeWarning, caller_stacklevel
from ..uncertainty.confidence import ONE_SIGMA, edf
from .covariance import CovStatistic, check_statistic, checked_records, covariance_matrices, factors

__all__ = ["HatResult", "DeviceHat", "cornered_hat", "three_cornered_hat", "classical_hat"]

# α range of the Greenhall EDF for each statistic family.
_ALPHA_RANGE = {"adev": (-2, 2), "oadev": (-2, 2), "mdev": (-2, 2), "hdev": (-4, 2), "ohdev": (-4, 2)}


@dataclass(frozen=True, eq=False)
class DeviceHat:
    """One device's row of a :class:`HatResult` (arrays over τ)."""

    name: str
    tau: np.ndarray
    classical_var: np.ndarray
    classical_dev: np.ndarray
    dev: np.ndarray
    low: np.ndarray
    high: np.ndarray

    def __repr__(self) -> str:
        return f"DeviceHat({self.name!r}, {self.tau.size} τ)"


@dataclass(frozen=True, eq=False)
class HatResult:
    """Cornered-hat estimates of each device's deviation.

    Attributes
    ----------
    names : tuple of str
        Device names, in the order of the columns below.
    statistic : str
        The variance used (``"oadev"`` by default).
    tau, m, n : numpy.ndarray
        Averaging times (s), factors, number of filtered terms.
    classical_var : numpy.ndarray, shape (n_tau, n_devices)
        Classical (least-squares) variance estimate, signed: negative values are kept.
    classical_dev : numpy.ndarray
        ``sign·sqrt(|classical_var|)``.
    dev : numpy.ndarray
        Non-negative estimate: maximum likelihood over σ² ≥ 0 (NaN where ν is undefined).
    low, high : numpy.ndarray
        Feldman–Cousins interval on each deviation at ``confidence`` (``low = 0``: an upper limit).
    edf : numpy.ndarray
        Degrees of freedom ν used at each τ.
    alpha : numpy.ndarray
        Noise type (α) behind ν at each τ.
    confidence : float
        Probability content of the intervals.
    """

    names: tuple
    statistic: str
    tau: np.ndarray
    m: np.ndarray
    n: np.ndarray
    classical_var: np.ndarray
    classical_dev: np.ndarray
    dev: np.ndarray
    low: np.ndarray
    high: np.ndarray
    edf: np.ndarray
    alpha: np.ndarray
    confidence: float

    def __repr__(self) -> str:
        return (f"HatResult({self.statistic}, devices={list(self.names)}, {self.tau.size} τ,"
                f" confidence={self.confidence:.3f})")

    def device(self, name: str) -> DeviceHat:
        """The estimates of one device."""
        if name not in self.names:
            raise ParameterError(f"name={name!r} is not one of the devices {list(self.names)}")
        j = self.names.index(name)
        return DeviceHat(name, self.tau, self.classical_var[:, j], self.classical_dev[:, j],
                         self.dev[:, j], self.low[:, j], self.high[:, j])

    def to_rows(self) -> list[dict]:
        """One dict per (τ, device): tau, m, n, edf, alpha, device, classical_var, classical_dev, dev, low, high."""
        rows = []
        for i in range(self.tau.size):
            for j, name in enumerate(self.names):
                rows.append({
                    "tau": float(self.tau[i]), "m": int(self.m[i]), "n": int(self.n[i]),
                    "edf": float(self.edf[i]), "alpha": int(self.alpha[i]), "device": name,
                    "classical_var": float(self.classical_var[i, j]),
                    "classical_dev": float(self.classical_dev[i, j]),
                    "dev": float(self.dev[i, j]), "low": float(self.low[i, j]), "high": float(self.high[i, j]),
                })
        return rows


# ---------------------------------------------------------------- classical hat

def _pair_design(n_dev: int) -> tuple[list[tuple[int, int]], np.ndarray]:
    """All pairs p < q and the matrix P with ``σ²_pq = (P θ)_pq = θ_p + θ_q``."""
    pairs = [(p, q) for p in range(n_dev) for q in range(p + 1, n_dev)]
    design = np.zeros((len(pairs), n_dev))
    for r, (p, q) in enumerate(pairs):
        design[r, p] = design[r, q] = 1.0
    return pairs, design


def _projector(n_dev: int) -> np.ndarray:
    """Linear map from the flattened K×K matrix S to the least-squares device variances θ.

    ``σ²_pq = S̃_pp + S̃_qq − 2S̃_pq`` with S̃ the N×N matrix bordered by a zero row
    and column for the first device; θ = P⁺ σ² (P⁺ the pseudo-inverse).
    """
    k = n_dev - 1
    pairs, design = _pair_design(n_dev)
    to_pairs = np.zeros((len(pairs), k * k))
    for r, (p, q) in enumerate(pairs):
        for a, b, w in ((p, p, 1.0), (q, q, 1.0), (p, q, -1.0), (q, p, -1.0)):
            if a > 0 and b > 0:
                to_pairs[r, (a - 1) * k + (b - 1)] += w
    return np.linalg.pinv(design) @ to_pairs


def classical_hat(pair_variances: Mapping) -> dict:
    r"""Classical N-cornered hat from pairwise variances (signed, least squares).

    Parameters
    ----------
    pair_variances : mapping
        ``{(p, q): σ²_pq}`` with ``σ²_pq`` a float or an array over τ: the variance
        of the difference between devices p and q. Every pair of the N devices
        named must be given once (in either order).

    Returns
    -------
    dict
        Device name → signed variance estimate (same shape as the inputs).

    Notes
    -----
    Solves ``σ²_pq = σ_p² + σ_q²`` in the least-squares sense. For three devices
    this is exact: ``σ_A² = ½(σ_AB² + σ_CA² − σ_BC²)`` and cyclically
    (J. E. Gray and D. W. Allan, Proc. 28th Frequency Control Symposium, 1974;
    NIST SP 1065 §4.4).

    Examples
    --------
    >>> v = classical_hat({("A", "B"): 1.00e-22, ("B", "C"): 1.64e-22, ("C", "A"): 1.36e-22})
    >>> {k: round(float(s) ** 0.5, 14) for k, s in v.items()}
    {'A': 6e-12, 'B': 8e-12, 'C': 1e-11}
    """
    if not isinstance(pair_variances, Mapping):
        raise ParameterError("pair_variances must be a mapping {(p, q): variance}")
    names = _names_of_pairs(list(pair_variances))
    index = {nm: i for i, nm in enumerate(names)}
    pairs, design = _pair_design(len(names))
    given: dict[tuple[int, int], np.ndarray] = {}
    for (p, q), v in pair_variances.items():
        key = tuple(sorted((index[p], index[q])))
        given[key] = np.asarray(v, dtype=float)  # type: ignore[index]
    missing = [(names[p], names[q]) for p, q in pairs if (p, q) not in given]
    if missing:
        raise DataError(f"classical_hat needs every pair; missing {missing}")
    values = np.stack([given[pq] for pq in pairs])
    theta = np.tensordot(np.linalg.pinv(design), values, axes=1)
    return {nm: theta[i] for i, nm in enumerate(names)}


def _names_of_pairs(keys: list) -> list:
    names: list = []
    for key in keys:
        if not (isinstance(key, tuple) and len(key) == 2):
            raise ParameterError(f"pair key {key!r} must be a tuple (p, q) of two device names")
        if key[0] == key[1]:
            raise ParameterError(f"pair key {key!r} compares a device with itself")
        for nm in key:
            if nm not in names:
                names.append(nm)
    if len(names) < 3:
        raise DataError(f"a cornered hat needs at least 3 devices, got {len(names)}: {names}")
    seen = set()
    for key in keys:
        fs = frozenset(key)
        if fs in seen:
            raise ParameterError(f"pair {key!r} is given twice")
        seen.add(fs)
    return names


# ---------------------------------------------------------------- input forms

def _differences_from_pairs(data: Mapping, names: list) -> list[np.ndarray]:
    """Series ``x_p − x_0`` (p ≥ 1) reconciled from pair series by least squares at each sample.

    With pairs ``e = (p, q)`` holding ``x_p − x_q`` and the incidence matrix B
    (``B[e,p] = 1``, ``B[e,q] = −1``), the device series relative to device 0
    solve ``B[:, 1:]·u = d`` in the least-squares sense; for exactly consistent
    pairs (``x_AB + x_BC + x_CA = 0``) this is exact, otherwise the loop closure
    error is shared out.
    """
    index = {nm: i for i, nm in enumerate(names)}
    keys = list(data)
    series = [as_series(data[key], f"pair {key!r}") for key in keys]
    sizes = {s.size for s in series}
    if len(sizes) > 1:
        raise DataError("the pair series must have the same length, got "
                        + ", ".join(f"{k!r}: {s.size}" for k, s in zip(keys, series)))
    inc = np.zeros((len(keys), len(names)))
    for r, (p, q) in enumerate(keys):
        inc[r, index[p]] = 1.0
        inc[r, index[q]] = -1.0
    reduced = inc[:, 1:]
    if np.linalg.matrix_rank(reduced) < len(names) - 1:
        raise DataError(f"the pairs {keys} do not connect every device {names}")
    u = np.linalg.pinv(reduced) @ np.stack(series)
    return [u[i] for i in range(len(names) - 1)]


def _differences(data: object) -> tuple[list, list[np.ndarray]]:
    """``(names, [x_p − x_0 for p ≥ 1])`` from records or pair series."""
    if not isinstance(data, Mapping):
        raise ParameterError("data must be a mapping {name: record} or {(p, q): difference series}")
    keys = list(data)
    if keys and all(isinstance(k, tuple) for k in keys):
        names = _names_of_pairs(keys)
        return names, _differences_from_pairs(data, names)
    if any(isinstance(k, tuple) for k in keys):
        raise ParameterError("data mixes device names and (p, q) pairs; give one form only")
    if len(keys) < 3:
        raise DataError(f"a cornered hat needs at least 3 devices, got {len(keys)}: {keys}")
    recs = [as_series(data[k], f"record {k!r}") for k in keys]
    sizes = {r.size for r in recs}
    if len(sizes) > 1:
        raise DataError("the records must have the same length, got "
                        + ", ".join(f"{k!r}: {r.size}" for k, r in zip(keys, recs)))
    _refuse_same(keys, recs)
    return keys, [r - recs[0] for r in recs[1:]]


def _refuse_same(keys: list, recs: list[np.ndarray]) -> None:
    """Two records that differ by a constant (the same file given twice, a copied column) leave
    their pair nothing to compare: say so, instead of failing later on a constant series."""
    for i in range(len(recs)):
        for j in range(i + 1, len(recs)):
            d = recs[j] - recs[i]
            # equal up to the round-off of adding a constant to either record
            scale = max(float(np.max(np.abs(recs[i]))), float(np.max(np.abs(recs[j])))) if d.size else 0.0
            if d.size and float(np.max(d)) - float(np.min(d)) <= 8.0 * np.finfo(float).eps * scale:
                raise DataError(f"records {keys[i]!r} and {keys[j]!r} are the same (they differ by a constant);"
                                " a cornered hat needs independent devices")


# ---------------------------------------------------------------- intervals

#: θ grid points and t grid points (FFT length) of the confidence-belt construction.
_THETA_POINTS = 121
_T_POINTS = 1024
#: Tail probability left outside the t grid by each χ² term.
_TAIL = 1e-10


def _sym_sqrt(cov: np.ndarray) -> np.ndarray:
    """Symmetric square roots of a stack of positive semi-definite matrices."""
    w, v = np.linalg.eigh(cov)
    return (v * np.sqrt(np.clip(w, 0.0, None))[..., None, :]) @ np.swapaxes(v, -1, -2)


def _weights(theta_grid: np.ndarray, k: int, others: np.ndarray, a_sym: np.ndarray) -> np.ndarray:
    """Eigenvalues λ(θ) of Σ^½ A Σ^½ for device k's variance on ``theta_grid`` (others fixed).

    ``θ̂_k = tr(A S)`` with ``ν S ~ W(Σ, ν)`` is distributed as ``Σ_i λ_i χ²_ν,i / ν``.
    """
    theta = np.repeat(others[None, :], theta_grid.size, axis=0)
    theta[:, k] = theta_grid
    kk = others.size - 1
    cov = theta[:, :1, None] * np.ones((1, kk, kk))
    cov[:, np.arange(kk), np.arange(kk)] += theta[:, 1:]
    root = _sym_sqrt(cov)
    return np.linalg.eigvalsh(root @ a_sym @ root)


def _densities(lam: np.ndarray, nu: float) -> tuple[np.ndarray, np.ndarray]:
    """``(t, f)``: density of ``Σ_i λ_i χ²_ν,i/ν`` on a common t grid, one row per row of ``lam``.

    Inverts the characteristic function ``Π_i (1 − 2iλ_i s/ν)^(−ν/2)`` by FFT on a grid wide
    enough that every χ² term leaves less than ``_TAIL`` outside.
    """
    from scipy.stats import chi2
    q_lo, q_hi = chi2.ppf(_TAIL, nu) / nu, chi2.isf(_TAIL, nu) / nu
    pos, neg = np.clip(lam, 0.0, None), np.clip(lam, None, 0.0)
    t_min = float(np.min(pos.sum(1) * q_lo + neg.sum(1) * q_hi))
    t_max = float(np.max(pos.sum(1) * q_hi + neg.sum(1) * q_lo))
    dt = (t_max - t_min) / (_T_POINTS - 1)
    t = t_min + dt * np.arange(_T_POINTS)
    s = 2.0 * np.pi * np.fft.fftfreq(_T_POINTS, dt)
    # log(1 − i·a) = ½·log(1 + a²) − i·atan(a), in real arithmetic (much faster than complex log1p).
    a = (2.0 / nu) * lam[:, :, None] * s[None, None, :]
    modulus = np.exp(-0.25 * nu * np.log1p(a * a).sum(axis=1))
    phase = 0.5 * nu * np.arctan(a).sum(axis=1) - s[None, :] * t_min
    f = np.fft.fft(modulus * np.exp(1j * phase), axis=1).real / (_T_POINTS * dt)
    return t, np.clip(f, 0.0, None)


def _belt(theta_grid: np.ndarray, t: np.ndarray, f: np.ndarray, t_obs: float,
          confidence: float) -> tuple[float, float, float]:
    """Feldman–Cousins interval of θ ≥ 0 and the constrained ML estimate, from densities ``f[θ, t]``."""
    dt = t[1] - t[0]
    best = f.max(axis=0)
    ratio = np.where(best > 0.0, f / np.where(best > 0.0, best, 1.0), 0.0)
    order = np.argsort(-ratio, axis=1)
    mass = np.take_along_axis(f, order, axis=1).cumsum(axis=1) * dt
    cut = np.minimum((mass < confidence).sum(axis=1), t.size - 1)
    threshold = np.take_along_axis(ratio, order, axis=1)[np.arange(theta_grid.size), cut]
    f_obs = np.array([np.interp(t_obs, t, row, left=0.0, right=0.0) for row in f])
    if f_obs.max() <= 0.0:
        return math.nan, math.nan, math.nan
    margin = f_obs / f_obs.max() - threshold
    accepted = np.flatnonzero(margin >= 0.0)
    if accepted.size == 0:
        return math.nan, math.nan, math.nan
    return (_peak(theta_grid, f_obs), _crossing(theta_grid, margin, accepted[0], -1),
            _crossing(theta_grid, margin, accepted[-1], 1))


def _peak(grid: np.ndarray, values: np.ndarray) -> float:
    """Location of the maximum of ``values`` on ``grid``, refined by a parabola through three points."""
    i = int(np.argmax(values))
    if i == 0 or i == grid.size - 1:
        return float(grid[i])
    y0, y1, y2 = values[i - 1], values[i], values[i + 1]
    curvature = y0 - 2.0 * y1 + y2
    shift = 0.5 * (y0 - y2) / curvature if curvature < 0.0 else 0.0
    return float(grid[i] + shift * (grid[1] - grid[0]))


def _crossing(grid: np.ndarray, margin: np.ndarray, i: int, step: int) -> float:
    """Where ``margin`` crosses zero between accepted point i and its rejected neighbour (linear)."""
    j = i + step
    if j < 0 or j >= grid.size or margin[j] >= 0.0:
        return float(grid[i])
    w = margin[i] / (margin[i] - margin[j])
    return float(grid[i] + w * (grid[j] - grid[i]))


def _device_interval(s: np.ndarray, nu: float, proj: np.ndarray, k: int, confidence: float,
                     start: np.ndarray) -> tuple[float, float, float]:
    """``(estimate, low, high)`` on device k's variance (NaN where ν is unusable)."""
    kk = s.shape[0]
    a = proj[k].reshape(kk, kk)
    a_sym = 0.5 * (a + a.T)
    t_obs = float(proj[k] @ s.ravel())
    others = np.clip(start, 0.0, None)
    scale = float(np.max(others)) or 1.0
    # Upper end of the θ grid: well past what a χ²_ν lower quantile allows; doubled while reached.
    from scipy.stats import chi2
    top = max(t_obs, 0.0) * nu / chi2.ppf(min((1.0 - confidence) / 20.0, 0.01), nu) + 4.0 * scale * np.sqrt(2.0 / nu)
    for _ in range(6):
        grid = np.linspace(0.0, top, _THETA_POINTS)
        t, f = _densities(_weights(grid, k, others, a_sym), nu)
        est, low, high = _belt(grid, t, f, t_obs, confidence)
        if not (high >= grid[-2]):
            return est, low, high
        top *= 2.0
    return est, low, high


def _intervals(s: np.ndarray, nu: float, proj: np.ndarray, classical: np.ndarray,
               confidence: float) -> Optional[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Per device ``(estimate σ, low σ, high σ)``, or None where ν is not usable."""
    if not np.isfinite(nu) or nu <= 0.0:
        return None
    rows = np.array([_device_interval(s, nu, proj, k, confidence, classical) for k in range(classical.size)])
    return np.sqrt(rows[:, 0]), np.sqrt(rows[:, 1]), np.sqrt(rows[:, 2])


# ---------------------------------------------------------------- public API

def _alphas(alpha: object, diff: np.ndarray, ms: np.ndarray, data_type: str, statistic: str,
            counts: np.ndarray) -> np.ndarray:
    """Noise type at each factor: the given α, or identified on ``diff`` as the statistics do."""
    lo, hi = _ALPHA_RANGE[statistic]
    if alpha is None:
        from ..uncertainty.noiseid import identify
        ident = identify(diff, ms, data_type=data_type, family=statistic, n_terms=counts)
        return np.clip(np.asarray(ident.alpha, dtype=np.int64), lo, hi)
    if isinstance(alpha, bool) or not isinstance(alpha, (int, np.integer)) or not lo <= alpha <= hi:
        raise ParameterError(f"alpha={alpha!r} must be None or an integer in {lo}..{hi} for {statistic}")
    return np.full(ms.size, int(alpha), dtype=np.int64)


def cornered_hat(
    data: Mapping,
    *,
    rate: float = 1.0,
    data_type: str = "phase",
    statistic: CovStatistic = "oadev",
    taus: object = "octave",
    m: object = None,
    points_per_decade: int = 10,
    confidence: float = ONE_SIGMA,
    alpha: Optional[int] = None,
) -> HatResult:
    """N-cornered hat (N ≥ 3): each device's deviation, signed and positive, with intervals.

    Parameters
    ----------
    data : mapping
        Either simultaneous records ``{"A": a, "B": b, "C": c, ...}`` of every
        device against one common reference (the reference and anything common
        to all — a shared table motion, the room — cancels in the differences),
        or pairwise difference series ``{("A", "B"): x_A − x_B, ...}`` whose pairs
        connect every device (all pairs are reconciled by least squares).
    rate, data_type, taus, m, points_per_decade
        As for every statistic.
    statistic : {"oadev", "adev", "mdev", "hdev", "ohdev"}
        Variance used for every pair and covariance.
    confidence : float
        Probability content of the intervals (default 0.683, ±1σ).
    alpha : int, optional
        Noise type for the EDF at every τ; by default identified at each τ on the
        difference between the second and the first device.

    Returns
    -------
    HatResult

    Notes
    -----
    See the module docstring for the model, the classical estimate, the
    confidence belt and their assumptions. Cost per τ: O(N_samples·K²) for the
    covariances plus, per device, a few FFTs of 121 × 1024 points for the
    confidence belt (about 10 ms), independent of the record length.

    References
    ----------
    J. E. Gray, D. W. Allan, "A method for estimating the frequency stability of
    an individual oscillator", Proc. 28th Frequency Control Symp. (1974).
    F.-X. Lantz, C. E. Calosso, E. Rubiola, V. Giordano, F. Vernotte, IEEE
    TUFFC 66(12), 2019. G. J. Feldman, R. D. Cousins, "Unified approach to the
    classical statistical analysis of small signals", Phys. Rev. D 57, 3873
    (1998). NIST SP 1065 §4.4 (three-cornered hat).

    Examples
    --------
    >>> import numpy as np
    >>> g = np.random.default_rng(5)
    >>> x = {n: s * g.standard_normal(20000) for n, s in zip("ABC", (1.0, 2.0, 3.0))}
    >>> r = cornered_hat(x, m=[1], alpha=2)
    >>> [round(float(v), 1) for v in r.classical_dev[0] / np.sqrt(3.0)]
    [1.0, 2.0, 3.0]
    """
    stat = check_statistic(statistic)
    names, diffs = _differences(data)
    conf = _check_confidence(confidence)
    phases, ks, rate_f, dtype, n_points = checked_records(diffs, [f"x_{n} - x_{names[0]}" for n in names[1:]],
                                                          rate, data_type, stat)
    ms = factors(stat, n_points, rate_f, taus, m, points_per_decade)
    if ms.size == 0:
        raise DataError(f"{stat}: no averaging factor fits {n_points} phase points")
    scaled, counts = covariance_matrices(phases, ms, 1.0 / rate_f, stat)
    weights = np.ldexp(1.0, np.add.outer(ks, ks))
    mats = scaled * weights
    proj = _projector(len(names))
    k = len(names) - 1
    classical = mats.reshape(ms.size, k * k) @ proj.T
    alphas = _alphas(alpha, diffs[0], ms, dtype, stat, counts)
    nus = np.array([edf(stat, int(a), int(mm), n_points) for a, mm in zip(alphas, ms)])
    est = np.full(classical.shape, np.nan)
    low, high = est.copy(), est.copy()
    undefined = []
    for i in range(ms.size):
        post = _intervals(mats[i], nus[i], proj, classical[i], conf)
        if post is None:
            undefined.append(int(ms[i]))
            continue
        est[i], low[i], high[i] = post
    if undefined:
        warnings.warn(f"cornered_hat: no EDF, hence no interval, at m={undefined}",
                      RangeWarning, stacklevel=caller_stacklevel())
    return HatResult(tuple(names), stat, ms / rate_f, ms, counts, classical,
                     np.sign(classical) * np.sqrt(np.abs(classical)), est, low, high, nus, alphas, conf)


def three_cornered_hat(
    ab: object,
    bc: object,
    ca: object,
    *,
    names: Sequence[str] = ("A", "B", "C"),
    **options: object,
) -> HatResult:
    """Three-cornered hat of the pair series ``x_A − x_B``, ``x_B − x_C``, ``x_C − x_A``.

    ``names`` labels the three devices; every other option is that of
    :func:`cornered_hat`, which does the work.
    """
    if len(names) != 3 or len(set(names)) != 3:
        raise ParameterError(f"names={tuple(names)!r} must be three distinct device names")
    a, b, c = names
    return cornered_hat({(a, b): ab, (b, c): bc, (c, a): ca}, **options)  # type: ignore[arg-type]


def _check_confidence(confidence: object) -> float:
    try:
        value = float(confidence)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise ParameterError(f"confidence={confidence!r} must be a number in (0, 1)") from None
    if not 0.0 < value < 1.0:
        raise ParameterError(f"confidence={confidence!r} must be in (0, 1), e.g. 0.683 or 0.95")
    return value
