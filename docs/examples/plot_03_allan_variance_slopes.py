"""
The design tip's Figure 3: the slopes of the Allan variance
============================================================

Each power-law noise has its own slope on a log–log plot of the Allan variance σ²(τ) against τ
(Figure 3 of DT0064): τ^−2 for white and flicker PM, τ^−1 for white FM, τ^0 for flicker FM, τ^+1
for random-walk FM, τ^+2 for flicker walk, τ^+3 for random run. The two phase noises share a
slope in AVAR; the modified Allan variance (MVAR) tells them apart.

This example draws the overlapped Allan variance (:func:`sigmatau.oadev`) of each type from
:func:`sigmatau.power_law_noise`, with its interval and the expected curve of the continuous
model (:func:`sigmatau.generate.expected_avar`; for flicker walk and random run the Allan
variance of the continuous model diverges — a finite record still shows the slope — and the
Hadamard variances, :func:`sigmatau.ohdev`, are the ones that converge), then reads the slopes back with
:func:`sigmatau.local_slopes` and the noise type :func:`sigmatau.oadev` identified at each τ.
"""

import matplotlib.pyplot as plt
import numpy as np

import sigmatau
from sigmatau import generate

rng = np.random.default_rng(3)
n = 2**15
rate = 1.0
names = {2: "white PM", 1: "flicker PM", 0: "white FM", -1: "flicker FM",
         -2: "random walk FM", -3: "flicker walk FM", -4: "random run FM"}
slopes = {2: "τ^-2", 1: "τ^-2", 0: "τ^-1", -1: "τ^0", -2: "τ^+1", -3: "τ^+2", -4: "τ^+3"}

# %%
# Allan variance of each noise type
# ----------------------------------
# ``h`` scales each component so the curves do not sit on top of each other; the shaded band
# is the 68 % interval on each variance (χ², with the EDF of the identified noise type).
fig, ax = plt.subplots(figsize=(8, 6))
results = {}
for (alpha, name), color in zip(names.items(), plt.cm.viridis(np.linspace(0, 0.9, len(names)))):
    h = 10.0 ** (2 * alpha)
    y = sigmatau.power_law_noise(n, alpha, h=h, rate=rate, rng=rng)
    r = sigmatau.oadev(y, rate=rate, taus="octave")
    results[alpha] = r
    ax.loglog(r.taus, r.var, "o", ms=4, color=color, label=f"{name}  ({slopes[alpha]})")
    ax.fill_between(r.taus, r.ci_low**2, r.ci_high**2, color=color, alpha=0.2, lw=0)
    if alpha >= -2:  # the continuous model's AVAR diverges below α = −2 (Hadamard converges)
        ax.loglog(r.taus, generate.expected_avar(alpha, h, r.taus, rate=rate), "-", lw=0.8, color=color)
ax.set_xlabel("τ [s]")
ax.set_ylabel("σ²(τ)  (overlapped Allan variance)")
ax.set_title("Allan variance of the power-law noises (points) and their model (lines)")
ax.legend(fontsize=8, loc="upper left", ncol=2)
fig.tight_layout()

# %%
# The slopes read back
# ---------------------
# :func:`sigmatau.local_slopes` gives the slope of log σ between neighbouring τ (the deviation's:
# half the variance's slope) with its uncertainty. For flicker walk and random run the Allan
# variance of a finite record is flatter than the table says (its expectation diverges, so the
# estimate depends on the length of the record: random run stops at τ^+2, the slope of a linear
# frequency drift); the overlapped Hadamard variance (:func:`sigmatau.ohdev`), which removes a
# drift, converges for them and shows τ^+2 and τ^+3.
print(f"{'noise':16s} {'α':>3} {'table':>6} {'OAVAR':>7} {'OHVAR':>7}")
for alpha, r in results.items():
    y = sigmatau.power_law_noise(n, alpha, h=10.0 ** (2 * alpha), rate=rate, rng=rng)
    h = sigmatau.ohdev(y, rate=rate, ci=None)
    print(f"{names[alpha]:16s} {alpha:3d} {slopes[alpha]:>6} "
          f"{2 * np.nanmedian(sigmatau.local_slopes(r).slope):7.2f} "
          f"{2 * np.nanmedian(sigmatau.local_slopes(h).slope):7.2f}")

# %%
# Each row of a result also carries the noise type identified at that τ (``alpha``, from the
# lag-1 autocorrelation, or the B1 and R(n) ratios where few averages remain), which sets the
# EDF and so the width of the interval:
print(results[0].to_table())  # white FM

# %%
# White and flicker PM: MDEV tells them apart
# --------------------------------------------
# Both give τ^−2 in AVAR; in MVAR white PM falls as τ^−3 and flicker PM as τ^−2, as in the tip's
# table.
fig, ax = plt.subplots(figsize=(6, 4))
for alpha, color in ((2, "#1f4e79"), (1, "#c0504d")):
    y = sigmatau.power_law_noise(n, alpha, rate=rate, rng=rng)
    for stat, marker in ((sigmatau.oadev, "o"), (sigmatau.mdev, "s")):
        r = stat(y, rate=rate, ci=None)
        ax.loglog(r.taus, r.var, marker + "-", ms=3, color=color, lw=0.8,
                  label=f"{names[alpha]}, {stat.__name__.upper()}")
ax.set_xlabel("τ [s]")
ax.set_ylabel("variance")
ax.legend(fontsize=8)
fig.tight_layout()
