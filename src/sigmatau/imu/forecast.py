"""What the fit of an IMU noise model would give on a longer (or shorter) record.

The engine behind :func:`~sigmatau.imu.recording_advice` (see its Notes for the equations):
``_Plan`` holds the model's curve and evaluates, for a record of ``n`` samples, the
covariance of the unconstrained fit behind the model's intervals (``rel_sd``) and the
expected significance of a term not yet resolved (``detection``), on the τ grid and with
the Greenhall EDF that record would have; ``_prediction_curve`` takes the curve from the
model; ``_Anchor`` ties one term's prediction to its interval now; ``_first_time`` finds
the record length at which a prediction reaches a goal; ``_h`` is the relative half-width
of a coefficient from that of its square, ``_h_printed`` that of the interval ``analyze``
prints (conditional on the term selection).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Mapping, Optional

import numpy as np

from ..core.taus import STOP_RATIOS
from ..uncertainty.confidence import edf_array
from .extraction import _usable_points
from .fitting import (_columns, _fit_free, _fit_once, _free_fit_of_every_term, _truncated_below_limits,
                      _truncated_solve)
from .noisemodel import NoiseModel
from .units import TERMS

__all__: list[str] = []

#: Most τ per octave of the predicted curves: a denser grid (``taus="all"``) adds points
#: that the τ correlation of the fit makes nearly redundant, at a cost in time only.
_MAX_PER_OCTAVE = 8

#: Expected significance ``c/σ_c`` (fit of the kept terms and this one, on the expected curve)
#: at which about half of the records resolve a term with ``analyze``'s defaults. Measured
#: (30 records per length, 100 Hz): Q over N 3.1 (50 % at 10 min); B over N 2.3 (20 %, 60 %
#: and 90 % at z = 1.7, 2.3, 3.0); K over B 1.7 and K over N 1.7 (30 %/70 % at z = 1.6/1.8;
#: 48 %/60 % at 1.7/2.0). Below 3 where the selection's second rule (a term the curve needs:
#: its removal sends χ² beyond its 10⁻⁴ tail) keeps a term at the end of the record before
#: its significance reaches 3. R is given K's value unmeasured: K and R trade places at the
#: end of the record, and R's resolution did not rise steadily with length.
_Z50 = {"Q": 3.0, "N": 3.0, "B": 2.3, "K": 1.7, "R": 1.7}


class _Plan:
    """The fitted curve of a model and the covariance its fit would have on a record of any length.

    ``rel_sd(n)`` is ``σ_c/c`` of every column for the unconstrained fit of every term (the
    intervals) on a record of ``n`` samples, ``detection(n, j, c)`` the expected significance
    of column ``j`` at the values ``c`` over its 50 % point. Both are cached by their arguments.
    """

    def __init__(self, coef: np.ndarray, s_data: np.ndarray, free: list[int], rate: float, gm_tau: float,
                 eps: float, statistic: str, m0: int, per_octave: float, n_now: int) -> None:
        self.coef, self.s_data, self.free = coef, s_data, free
        self.rate, self.gm_tau, self.eps = rate, gm_tau, eps
        self.statistic, self.stop = statistic, STOP_RATIOS[statistic]
        self.m0, self.per_octave, self.n_now = m0, per_octave, n_now
        self._cache: dict[tuple, np.ndarray] = {}

    @classmethod
    def of(cls, model: NoiseModel, duration: float, assumed: Mapping[str, float]) -> "_Plan":
        """The plan of ``model``'s curve (see :func:`_prediction_curve`), the ``assumed`` terms set."""
        names = TERMS + ("GM",)
        free = [TERMS.index(t) for t in TERMS if getattr(model, t).method != "excluded"]
        gm_tau = math.nan
        if model._gm is not None:
            gm_tau = model._gm[1]
            free.append(5)
        coef, s_data = _prediction_curve(model, [names[j] for j in free], gm_tau)
        for t, v in assumed.items():
            coef[TERMS.index(t)] = v**2
        m = np.asarray(model.result.m, float)
        per_octave = (m.size - 1) / math.log2(m[-1] / m[0]) if m.size > 1 and m[-1] > m[0] else 1.0
        return cls(coef, s_data, free, model.rate, gm_tau, model.discrepancy, model.result.statistic, int(m[0]),
                   min(max(per_octave, 1.0), _MAX_PER_OCTAVE), int(round(duration * model.rate)))

    def samples(self, duration: float) -> int:
        """Samples of a record of ``duration`` seconds."""
        return max(int(round(duration * self.rate)), 1)

    def _curve(self, n: int, coef: np.ndarray) -> Optional[tuple]:
        """Columns, expected AVAR and EDF on the τ grid of a record of ``n`` samples (None: too short)."""
        k_max = math.floor(self.per_octave * math.log2(max(n / self.stop, 1.0) / self.m0) + 1e-9)
        if k_max < 2:
            return None
        ms = np.unique(np.round(self.m0 * 2.0 ** (np.arange(k_max + 1) / self.per_octave)).astype(np.int64))
        taus = ms / self.rate
        design = _columns(taus, self.rate, self.gm_tau)
        width = design.mat.shape[1]
        var = design.mat @ coef[:width]
        # The EDF of each point is that of the term holding most of its variance.
        share = design.mat * np.abs(coef[:width])
        alpha = np.clip(design.alpha[np.arange(taus.size), np.argmax(share, axis=1)], -2, 2)
        key = ("edf", n, alpha.tobytes())
        if key not in self._cache:
            self._cache[key] = np.asarray(edf_array(self.statistic, alpha, ms, n + 1, unsupported="nan"), float)
        nu = self._cache[key]
        ok = np.isfinite(nu) & (nu > 0) & (var > 0)
        if ok.sum() < 3:
            return None
        if not ok.all():  # a negative 1/τ² (filter) term can take the shortest τ below 0
            design = _columns(taus[ok], self.rate, self.gm_tau)
        return design, var[ok], nu[ok], taus[ok]

    def rel_sd(self, n: int, coef: Optional[np.ndarray] = None) -> np.ndarray:
        """σ_c/c of every column (NaN where c = 0 or the record is too short) in the free fit."""
        c = self.coef if coef is None else coef
        key = ("free", n, c.tobytes())
        if key not in self._cache:
            out = np.full(6, math.nan)
            curve = self._curve(n, c)
            if curve is not None:
                design, var, nu, taus = curve
                # The free fit of every term is what the model's intervals come from.
                _, cov, _, _ = _fit_free(design, var, nu, taus, self.free, self.eps)
                sd = np.sqrt(np.clip(np.diag(cov), 0.0, None))
                with np.errstate(divide="ignore", invalid="ignore"):
                    out[self.free] = np.where(c[self.free] > 0, sd / np.abs(c[self.free]), math.nan)
            self._cache[key] = out
        return self._cache[key]

    def detection(self, n: int, j: int, coef: np.ndarray) -> float:
        """Expected significance of column ``j`` (at value ``coef[j]``) over its 50 % point
        :data:`_Z50`: ≥ 1 when about half the records of ``n`` samples would resolve it."""
        key = ("sel", n, j, coef.tobytes())
        if key not in self._cache:
            curve = self._curve(n, coef)
            score = math.nan
            if curve is not None:
                design, var, nu, taus = curve
                # The terms of the curve (kept, assumed, a filter's negative 1/τ²) and this one.
                width = design.mat.shape[1]
                cols = sorted({i for i in range(width) if coef[i] != 0} | {j})
                h, cov, *_ = _fit_once(design, var, nu, taus, cols, self.eps)
                k = cols.index(j)
                sd = math.sqrt(max(float(cov[k, k]), 0.0))
                score = (float(h[k]) / sd if sd > 0 else math.inf) / _Z50[TERMS[j]]
            self._cache[key] = np.array([score])
        return float(self._cache[key][0])


def _prediction_curve(model: NoiseModel, terms: list[str], gm_tau: float) -> tuple[np.ndarray, np.ndarray]:
    """The coefficients the predictions are made on, and σ̂_c/c measured by the record.

    Both come from the unconstrained fit of every term that :func:`~sigmatau.imu.analyze`
    builds its intervals from, redone on the model's curve (same points, EDF, columns and
    discrepancy floor), for the terms the model keeps: that ``ĉ`` is free of term
    selection, and its ``σ̂_c`` is the one behind the printed interval (which is conditional on
    the selection and cannot be read back when clipped at 0). A kept term whose
    ``ĉ`` is not positive keeps the selected value; so does a negative 1/τ² (filter)
    term. Terms not kept are 0: entering them at their ``ĉ`` (the noise level) gave
    predictions no closer to the widths achieved (B next to a K still unresolved: median
    0.83× instead of 0.79×; B alone: 1.17× instead of 1.06×). Returns ``(coef, s)``, six
    entries (Q, N, B, K, R, GM), ``s`` NaN where ``c ≤ 0``.
    """
    # analyze's default min_significance (3) settles the EDF of each point, as it did there.
    taus, dev, nu = _usable_points(model.result, model.rate, [t for t in terms if t != "GM"], 3.0)
    design = _columns(taus, model.rate, gm_tau)
    full, cov, _, _ = _free_fit_of_every_term(design, dev**2, nu, taus, terms, model.discrepancy)
    selected = np.zeros(6)
    selected[:5] = [model.coefficients[t] for t in TERMS]
    if model._gm is not None:
        selected[5] = model._gm[0]
    coef = np.zeros(6)
    coef[:full.size] = np.maximum(full, 0.0)
    kept = [(TERMS + ("GM",)).index(t) for t in model.fit_terms]
    # A term not kept enters at 0 (unless assumed): its ĉ is at the noise level, and a
    # positive draw of it (R at the end of the record) would hide the terms beside it.
    coef[[j for j in range(6) if j not in kept]] = 0.0
    fallback = [j for j in kept if not full[j] > 0] + ([0] if model.filter_time > 0 else [])
    coef[fallback] = selected[fallback]
    sd = np.zeros(6)
    sd[:full.size] = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    with np.errstate(divide="ignore", invalid="ignore"):
        s_data = np.where(coef > 0, sd / coef, math.nan)
    return coef, s_data


@dataclass(frozen=True, eq=False)
class _Anchor:
    """One term's prediction: precision and significance as functions of the record length.

    ``s_now`` is σ_c/c now (measured for a resolved term, the model's for an assumed one),
    ``h_now`` the precision reported now, ``coef`` the curve the model ratio is taken on.
    """

    plan: _Plan
    j: int
    coef: np.ndarray
    z_p: float
    s_now: float
    h_now: float
    s_model_now: float
    resolved: bool

    def precision(self, duration: float) -> float:
        """Relative half-width after a record of ``duration`` seconds (NaN: too short for a curve)."""
        s_model = self.plan.rel_sd(self.plan.samples(duration), self.coef)[self.j]
        if not (math.isfinite(s_model) and self.s_model_now > 0):
            return math.nan
        r = s_model / self.s_model_now
        if not self.resolved:
            # No interval yet: the one analyze will print once the term is kept, conditional on that.
            return _h_printed(self.j, self.z_p, self.s_now * r)
        # A resolved term's interval now is measured, conditional inflation included; scaling it by
        # the plain ratio carries that inflation forward, which errs towards a longer record (the
        # typical inflation modelled by _h_printed did not match B's: predicted/achieved 0.62).
        base = _h(self.z_p * self.s_now)
        return self.h_now * _h(self.z_p * self.s_now * r) / base if base > 0 else math.nan

    def detection(self, duration: float) -> float:
        """≥ 1 when a term of this value would be kept by a record of ``duration`` seconds."""
        if self.resolved:
            return math.inf
        return self.plan.detection(self.plan.samples(duration), self.j, self.coef)


def _first_time(excess: Callable[[float], float], start: float, horizon: float) -> float:
    """The first record length in [start, horizon] where the decreasing ``excess`` reaches 0
    (``start`` when it already has, ``inf`` when it does not by ``horizon``): doubling to
    bracket it, then Brent's method on ln T to 2 %."""
    from scipy.optimize import brentq  # imported here: keeps `import sigmatau` light

    first = excess(start)
    if math.isfinite(first) and first <= 0:
        return start
    lo = start
    while True:
        hi = min(2.0 * lo, horizon)
        e = excess(hi)
        if math.isfinite(e) and e <= 0:
            break
        if hi >= horizon:
            return math.inf
        lo = hi

    def f(log_t: float) -> float:
        v = excess(math.exp(log_t))
        return v if math.isfinite(v) else 1.0

    if not f(math.log(lo)) > 0:
        return lo
    return float(math.exp(brentq(f, math.log(lo), math.log(hi), xtol=0.02)))


def _h(a: float) -> float:
    """Relative half-width of P = √c for the interval c·(1 ± a) (lower end clipped at 0)."""
    return 0.5 * (math.sqrt(1.0 + a) - math.sqrt(max(1.0 - a, 0.0)))


def _h_printed(j: int, z_p: float, s: float) -> float:
    """Relative half-width ``(high − low)/(2·value)`` of the interval :func:`~sigmatau.imu.analyze`
    prints for term ``j`` with ``σ_c/c = s``, in the median record that keeps the term.

    The interval of a kept term is conditional on the selection keeping it (a normal truncated
    below at the edge where the selection would drop it, ``fitting._selection_aware_intervals``),
    and its value the median given the selection. The edge is put at ``z₅₀·σ_c``
    (:data:`_Z50`: the selection keeps half of the records there) and the estimate at its median
    among the records that keep the term, ``ĉ₅₀ = c + σ_c·Φ⁻¹(Φ(a) + ½Φ(−a))``,
    ``a = (z₅₀σ_c − c)/σ_c`` (the width falls as ĉ rises, so this is the median width). Far above
    the edge this is ``h(z_p·s)``; near it, where a term is just resolved, the interval is wider
    (K at its 50 % point, ``s = 1/1.7``: 0.68 against 0.31 at 68.3 %). The spread is taken as
    constant (analyze takes it at the candidate value), and the Gauss–Markov term, which has no
    selection-aware interval, gets ``h(z_p·s)``.
    """
    from scipy.special import ndtr, ndtri

    if j >= len(TERMS) or not (math.isfinite(s) and s > 0):
        return _h(z_p * s)
    level = 1.0 - 2.0 * float(ndtr(-z_p))
    edge = _Z50[TERMS[j]] * s
    a = (edge - 1.0) / s
    c_hat = 1.0 + s * float(ndtri(float(ndtr(a)) + 0.5 * float(ndtr(-a))))
    lo, hi = _truncated_below_limits(c_hat, lambda c: s, edge, level)
    if not (hi > 0 and math.isfinite(hi)):
        return _h(z_p * s)  # analyze then prints the limits not conditioned on the selection
    mid = _truncated_solve(c_hat, lambda c: s, edge, 0.5)
    value = math.sqrt(mid) if mid > 0 else min(math.sqrt(c_hat), math.sqrt(hi))
    return (math.sqrt(hi) - math.sqrt(max(lo, 0.0))) / (2.0 * value)
