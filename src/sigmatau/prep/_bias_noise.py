"""A power-law noise model of block means (white + flicker + random walk) and its REML posterior.

The steps that fit a slow model to block means of a rate record (the temperature fit) need the
covariance of the block means' noise: independent only when the noise is white at the block
length. A MEMS bias also has flicker ("bias instability", ``S_y = h₋₁/f``) and random-walk
(``S_y = h₋₂/f²``) components, whose block means are strongly correlated. This module builds
that covariance exactly for block averages of continuous power-law noise, weighs a grid of
levels of the three components by their restricted likelihood (REML), and averages the
generalised least-squares (GLS) fit of every order over that posterior (Bayesian model
averaging: a short record determines the flicker and random-walk levels poorly, and the
variance of a slope depends strongly on them).

**Covariances.** Neither flicker nor random-walk noise has a finite variance; both have a
*generalised* covariance (Matheron's intrinsic random functions), defined up to a constant:
``k₋₁(τ) = −h₋₁ ln|τ|`` (the 1/f spectrum's cosine transform less its divergent constant;
Keshner 1982) and ``k₋₂(τ) = −π² h₋₂ |τ|`` (a random walk: ``Var(y(t) − y(s)) = 2π² h₋₂ |t − s|``).
The constant is fixed by a cut-off at the record's span S, which makes both kernels positive
definite functions (``ln(S/|τ|)`` and ``S − |τ|`` on ``|τ| ≤ S``: their Fourier transforms,
``2 Si(ωS)/ω`` and ``2(1 − cos ωS)/ω²``, are positive). The covariance of the means over
blocks ``[a₁, b₁]`` and ``[a₂, b₂]`` is ``∬k(t − s) dt ds / (L₁L₂)``, in closed form with a
second antiderivative ``Φ`` of ``k``: ``Φ(b₁−a₂) − Φ(a₁−a₂) − Φ(b₁−b₂) + Φ(a₁−b₂)``, where
``Φ(u) = u² ln|u|/2 − 3u²/4`` (flicker) and ``|u|³/6`` (random walk). The constant only adds
``c·11ᵀ``: for a regression with an intercept this changes neither the GLS estimates nor the
covariance of the other coefficients (Rao 1967), so S affects the intercept's error alone.
Checked against the Allan variance: adjacent blocks give ``2 ln 2·h₋₁`` and
``(2π²/3)·h₋₂·τ`` (:func:`sigmatau.core.powerlaw.response`).

**Posterior.** ``Σ = s²·V``, ``V = D + ρ_f·F̃ + ρ_w·W̃`` (see :class:`NoisePosterior`). The REML
likelihood of ``(ρ_f, ρ_w)`` with ``s²`` concentrated out is their marginal posterior under flat
priors on the coefficients and on ``ln s²`` (Harville 1974). The prior of each ratio is a
spike at 0 (the component absent) with probability ½ — even prior odds for its presence, as
Jeffreys proposed for a test — and a slab uniform in ``ln ρ`` (scale-free) over ``e^−10 … e^8``,
on a grid of steps 1/4 (flicker) and 1 (random walk). Per order, the coefficients and their
covariance are averaged over the posterior by the law of total variance (Hoeting et al.
1999): ``β̄ = Σ w_g β_g``, ``Cov = Σ w_g s²_g (X̃ᵀX̃)⁻¹_g + Σ w_g (β_g − β̄)(β_g − β̄)ᵀ``.

References
----------
G. Matheron, "The intrinsic random functions and their applications", Adv. Appl. Probab. 5
(1973) 439–468. M. S. Keshner, "1/f noise", Proc. IEEE 70 (1982) 212–218. C. R. Rao, "Least
squares theory using an estimated dispersion matrix and its application to measurement of
signals", Proc. Fifth Berkeley Symp. Math. Statist. Probab. 1 (1967) 355–372.
S. D. P. Williams, "The effect of coloured noise on the uncertainties of rates estimated from
geodetic time series", J. Geodesy 76 (2003) 483–494 (white + flicker + random-walk covariance,
amplitudes by maximum likelihood, rate errors). H. D. Patterson and R. Thompson, "Recovery of
inter-block information when block sizes are unequal", Biometrika 58 (1971) 545–554;
D. A. Harville, "Maximum likelihood approaches to variance component estimation and to
related problems", J. Amer. Statist. Assoc. 72 (1977) 320–338 (REML); D. A. Harville, "Bayesian
inference for variance components using only error contrasts", Biometrika 61 (1974) 383–385.
H. Jeffreys, *Theory of Probability*, 3rd ed., OUP (1961), ch. V (even prior odds for a
test). J. A. Hoeting, D. Madigan, A. E. Raftery and C. T. Volinsky, "Bayesian model
averaging: a tutorial", Statist. Sci. 14 (1999) 382–417.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..core.powerlaw import response

__all__ = ["BlockLayout", "NoisePosterior", "noise_posterior", "allan_levels", "flicker_covariance",
           "random_walk_covariance", "MIN_DOF_COLOURED"]

#: The slab of each coloured component's prior: ln ρ from −10 to 8 (ρ = e^−10 is negligible at any
#: length of record; ρ = e^8 is a component 3000 times the white one at the block length), in steps
#: of 1/4 for flicker, which a record often determines to a few tenths of ln ρ (each extra flicker
#: level costs O(K), see _grams), and of 1 for the random walk, whose posterior is broad.
_SLAB_FLICKER = np.arange(-10.0, 8.001, 0.25)
_SLAB_WALK = np.arange(-10.0, 8.001, 1.0)
#: Prior probability that a coloured component is absent (the spike at ρ = 0): even odds.
_P_ABSENT = 0.5
#: Fewest residual degrees of freedom for which the two coloured levels are fitted at all.
MIN_DOF_COLOURED = 20


@dataclass(frozen=True)
class BlockLayout:
    """Where the block means sit, in units of the nominal block length ``m`` samples.

    Attributes
    ----------
    start, stop : numpy.ndarray
        The interval each block mean averages over (a block with gaps: an interval as long as its
        valid samples, centred on their mean time).
    counts : numpy.ndarray
        Valid samples per block.
    m : int
        Nominal block length (samples).
    span : float
        The record's span (blocks): the cut-off of the generalised covariances.
    """

    start: np.ndarray
    stop: np.ndarray
    counts: np.ndarray
    m: int
    span: float


def _pair_integral(phi, lay: BlockLayout) -> np.ndarray:
    """``∬ k(t − s) dt ds / (L_a L_b)`` over every pair of blocks, from ``phi`` = Φ (Φ'' = k)."""
    a1, b1 = lay.start[:, None], lay.stop[:, None]
    a2, b2 = lay.start[None, :], lay.stop[None, :]
    total = phi(b1 - a2) - phi(a1 - a2) - phi(b1 - b2) + phi(a1 - b2)
    length = lay.stop - lay.start
    return total / np.outer(length, length)


def _phi_log(u: np.ndarray) -> np.ndarray:
    """Second antiderivative of ``ln|u|`` vanishing at 0: ``u² ln|u|/2 − 3u²/4``."""
    au = np.abs(u)
    with np.errstate(divide="ignore", invalid="ignore"):
        out = 0.5 * u * u * np.log(au) - 0.75 * u * u
    return np.where(au > 0, out, 0.0)


def _phi_abs(u: np.ndarray) -> np.ndarray:
    """Second antiderivative of ``|u|`` vanishing at 0: ``|u|³/6``."""
    return np.abs(u) ** 3 / 6.0


def flicker_covariance(lay: BlockLayout) -> np.ndarray:
    """Covariance of the block means of flicker FM with ``h₋₁ = 1``: kernel ``ln(S/|τ|)``."""
    return math.log(lay.span) - _pair_integral(_phi_log, lay)


def random_walk_covariance(lay: BlockLayout) -> np.ndarray:
    """Covariance of the block means of random-walk FM with ``π² h₋₂ = 1``, time in blocks:
    kernel ``S − |τ|``, i.e. ``Var(y(t) − y(s)) = 2|t − s|``."""
    return lay.span - _pair_integral(_phi_abs, lay)


class _Components:
    """The three unit covariances of a layout, each scaled to an Allan variance of 1 between full blocks."""

    def __init__(self, lay: BlockLayout):
        self.white = lay.m / lay.counts.astype(np.float64)
        # a two-block probe with full blocks: the Allan variance each kernel gives at the block length
        probe = BlockLayout(np.array([0.0, 1.0]), np.array([1.0, 2.0]), np.array([lay.m, lay.m]), lay.m, 2.0)
        self.flicker = flicker_covariance(lay) / _adjacent_avar(flicker_covariance(probe))
        self.walk = random_walk_covariance(lay) / _adjacent_avar(random_walk_covariance(probe))

    def matrix(self, rf: float, rw: float) -> np.ndarray:
        """``V = D + ρ_f·F̃ + ρ_w·W̃``."""
        v = np.diag(self.white)
        if rf > 0:
            v = v + rf * self.flicker
        if rw > 0:
            v = v + rw * self.walk
        return v


def _adjacent_avar(c: np.ndarray) -> float:
    """½E[(ȳ₂ − ȳ₁)²] from a 2 × 2 covariance."""
    return 0.5 * float(c[0, 0] + c[1, 1] - 2.0 * c[0, 1])


def allan_levels(white: float, flicker: float, walk: float, rate: float, m: int) -> dict[str, float]:
    """The Allan-terms levels ``N`` (unit/√Hz), ``B`` (unit) and ``K`` (unit/√s) from the three Allan
    variances at the block length ``τ = m/rate``.

    ``N² = σ²_white·τ``; ``B² = π h₋₁`` with ``2 ln 2·h₋₁ = σ²_flicker``; ``K² = 2π² h₋₂`` with
    ``(2π²/3)h₋₂τ = σ²_walk`` (IEEE Std 952-1997 Annex C; the simulator's conventions, the Allan
    variances of :func:`sigmatau.core.powerlaw.response`).
    """
    tau = m / rate
    flicker_avar = float(response("avar", -1, np.array([tau]), rate)[0])
    walk_avar = float(response("avar", -2, np.array([tau]), rate)[0])
    return {"N": math.sqrt(max(white, 0.0) * tau),
            "B": math.sqrt(math.pi * max(flicker, 0.0) / flicker_avar),
            "K": math.sqrt(2.0 * math.pi ** 2 * max(walk, 0.0) / walk_avar)}


@dataclass(frozen=True)
class NoisePosterior:
    """GLS fits of every order over a grid of noise models, and the REML posterior over that grid.

    The grid holds the white + flicker + random-walk covariances ``Σ = s²·V(ρ_f, ρ_w)``,
    ``V = D + ρ_f·F̃ + ρ_w·W̃``: ``D = diag(m/counts)`` (white), ``F̃`` and ``W̃`` the flicker and
    random-walk covariances scaled to an Allan variance of 1 between adjacent full blocks, as D
    gives, so that ``ρ_f`` and ``ρ_w`` are the components' Allan variances at the block length
    relative to the white one, and ``s²`` is the white Allan variance there. Per grid point g
    and order p (design columns ``0 … p``): the REML cost ``cost[p, g]`` (−2 log-likelihood of
    the error contrasts, ``s²`` profiled out), the coefficients ``beta[p, g]``, their unscaled
    covariance ``cov[p, g] = (X̃ᵀX̃)⁻¹`` and the whitened residual sum of squares ``rss[p, g]``.
    """

    rho_f: np.ndarray
    rho_w: np.ndarray
    log_prior: np.ndarray
    cost: np.ndarray
    rss: np.ndarray
    beta: np.ndarray
    cov: np.ndarray
    layout: BlockLayout

    @property
    def coloured(self) -> bool:
        """Whether the coloured levels were fitted (False: too few blocks, white only)."""
        return self.rho_f.size > 1

    def weights(self, p: int) -> np.ndarray:
        """Posterior probability of each grid point under the order-p design (prior × REML likelihood)."""
        log_w = self.log_prior - 0.5 * self.cost[p]
        w = np.exp(log_w - np.max(log_w))
        return w / np.sum(w)

    def scale(self, p: int) -> np.ndarray:
        """``s²`` per grid point under the order-p design: ``RSS̃/(K − p − 1)`` (REML's)."""
        return self.rss[p] / max(self.layout.counts.size - p - 1, 1)

    def mean_levels(self, p: int) -> tuple[float, float, float]:
        """Posterior means of the white, flicker and random-walk Allan variances at the block length."""
        w, s2 = self.weights(p), self.scale(p)
        return float(w @ s2), float(w @ (s2 * self.rho_f)), float(w @ (s2 * self.rho_w))

    def present(self, p: int) -> tuple[float, float]:
        """Posterior probabilities that flicker and random walk are present (ρ > 0)."""
        w = self.weights(p)
        return float(np.sum(w[self.rho_f > 0])), float(np.sum(w[self.rho_w > 0]))

    def average(self, p: int) -> tuple[np.ndarray, np.ndarray]:
        """The order-p coefficients and their covariance averaged over the posterior.

        ``β̄ = Σ_g w_g β_g`` and ``Cov = Σ_g w_g s²_g (X̃ᵀX̃)⁻¹_g + Σ_g w_g (β_g − β̄)(β_g − β̄)ᵀ``
        (the law of total variance: the spread within each noise model plus that between them).
        """
        w, s2 = self.weights(p), self.scale(p)
        b = self.beta[p, :, : p + 1]
        mean = w @ b
        dev = b - mean
        cov = np.einsum("g,gij->ij", w * s2, self.cov[p, :, : p + 1, : p + 1]) + np.einsum("g,gi,gj->ij", w, dev, dev)
        return mean, cov

    def mean_model(self, p: int) -> np.ndarray:
        """Cholesky factor of ``V`` at the posterior-mean levels (the covariance of the noise averaged over
        the posterior, up to the scale): the one whitening the order criterion uses."""
        white, flicker, walk = self.mean_levels(p)
        if not white > 0:  # a noiseless record: any model whitens it alike
            white, flicker, walk = 1.0, 0.0, 0.0
        return np.linalg.cholesky(_Components(self.layout).matrix(flicker / white, walk / white))


def _levels(slab: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The levels tried for one ratio (0: absent, then the slab) and their log prior."""
    levels = np.concatenate(([0.0], np.exp(slab)))
    log_p = np.concatenate(([math.log(_P_ABSENT)], np.full(slab.size, math.log((1.0 - _P_ABSENT) / slab.size))))
    return levels, log_p


def _grams(comp: _Components, data: np.ndarray, rw: np.ndarray, rf: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Whitened Gram matrices ``[X y]ᵀV⁻¹[X y]`` and ``ln det V`` for every pair ``(ρ_w, ρ_f)``.

    For each ``ρ_w``, ``A = D + ρ_w·W̃ = LLᵀ`` and the eigenvectors of ``L⁻¹F̃L⁻ᵀ = UΛUᵀ`` turn every
    ``V = A + ρ_f·F̃`` into ``LU(I + ρ_fΛ)UᵀLᵀ``: one factorisation and one eigendecomposition per
    ρ_w serve all ρ_f, so the grid needs 2 × 20 decompositions of K × K matrices, not one per
    point (a threaded BLAS makes each slow on a busy machine).
    """
    from scipy.linalg import solve_triangular  # on first use: import sigmatau stays light

    k, cols = data.shape
    grams = np.empty((rw.size, rf.size, cols, cols))
    log_det = np.empty((rw.size, rf.size))
    for i, level in enumerate(rw):
        chol = np.linalg.cholesky(comp.matrix(0.0, float(level)))
        z = solve_triangular(chol, data, lower=True, check_finite=False)
        lam = np.zeros(k)
        if np.any(rf > 0):
            half = solve_triangular(chol, comp.flicker, lower=True, check_finite=False)
            lam, u = np.linalg.eigh(solve_triangular(chol, half.T, lower=True, check_finite=False))
            lam = np.maximum(lam, 0.0)  # F̃ is positive definite: a negative eigenvalue is rounding
            z = u.T @ z
        c = 1.0 / (1.0 + rf[:, None] * lam[None, :])
        grams[i] = np.einsum("fk,ka,kb->fab", c, z, z)
        log_det[i] = 2.0 * float(np.sum(np.log(np.diag(chol)))) - np.sum(np.log(c), axis=1)
    return grams, log_det


def noise_posterior(x: np.ndarray, y: np.ndarray, lay: BlockLayout) -> NoisePosterior:
    """Fit every order ``p = 0 … P`` (columns ``0 … p`` of ``x``; column 0 the constant) to the block
    means ``y`` under each noise model of the grid, with the REML cost of each (see
    :class:`NoisePosterior`).

    With fewer than :data:`MIN_DOF_COLOURED` residual degrees of freedom at the largest order the grid
    is the white model alone.
    """
    k, top = x.shape
    if k - top >= MIN_DOF_COLOURED:
        (walk, p_walk), (flicker, p_flicker) = _levels(_SLAB_WALK), _levels(_SLAB_FLICKER)
    else:
        walk, p_walk, flicker, p_flicker = np.zeros(1), np.zeros(1), np.zeros(1), np.zeros(1)
    comp = _Components(lay)
    # the Gram products lose digits to a large offset: fit y less its mean (the constant is in every design)
    offset = float(np.average(y, weights=lay.counts))
    grams, log_det = _grams(comp, np.column_stack([x, y - offset]), walk, flicker)
    grams, log_det = grams.reshape(-1, top + 1, top + 1), log_det.ravel()
    size = log_det.size
    cost, rss = np.empty((top, size)), np.empty((top, size))
    beta, cov = np.zeros((top, size, top)), np.zeros((top, size, top, top))
    for p in range(top):
        n = p + 1
        gxx, gxy = grams[:, :n, :n], grams[:, :n, top]
        inv = np.linalg.inv(gxx)
        b = np.einsum("gij,gj->gi", inv, gxy)
        rss[p] = np.maximum(grams[:, top, top] - np.einsum("gi,gi->g", gxy, b), 1e-300)
        b[:, 0] += offset
        beta[p, :, :n], cov[p, :, :n, :n] = b, inv
        # Harville (1977): (K − p − 1)·ln RSS̃ + ln det V + ln det X̃ᵀX̃, the scale concentrated out
        cost[p] = (k - n) * np.log(rss[p]) + log_det + np.linalg.slogdet(gxx)[1]
    rw, rf = (a.ravel() for a in np.meshgrid(walk, flicker, indexing="ij"))
    lp = (p_walk[:, None] + p_flicker[None, :]).ravel()
    return NoisePosterior(rf, rw, lp, cost, rss, beta, cov, lay)
