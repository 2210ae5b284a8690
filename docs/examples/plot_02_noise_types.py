"""
The design tip's Figure 2: seven noise types, three views
==========================================================

Figure 2 of DT0064 shows each noise type three ways: the time series, its power spectral density
and a lag plot (each sample against the next). The generators are the tip's: ``randn`` for white
FM, ``cumsum`` for the walks, ``diff`` for the phase noises and the bank of octave generators for
flicker noise (:func:`sigmatau.generate.octave_flicker`).

The spectrum is :func:`sigmatau.psd` (Welch, averaged in log-frequency bins, with a fitted
``h_α f^α``); the slope of each spectrum is the ``S(f)`` column of the tip's table.
"""

import matplotlib.pyplot as plt
import numpy as np

import sigmatau
from sigmatau import generate

rng = np.random.default_rng(64)
n = 2**14
rate = 1.0


def unit(x):
    """Zero mean, unit standard deviation: the panels share one scale."""
    x = np.asarray(x, dtype=float)
    return (x - x.mean()) / x.std()


flicker = generate.octave_flicker(n + 1, rng=rng)
noises = {
    # name: (series, the slope of S(f) in the tip's table)
    "white PM: diff(white FM)": (np.diff(rng.standard_normal(n + 1)), "f^+2"),
    "flicker PM: diff(flicker FM)": (np.diff(flicker), "f^+1"),
    "white FM: randn": (rng.standard_normal(n), "f^0"),
    "flicker FM: octave bank": (flicker[:n], "f^-1"),
    "random walk FM: cumsum(white FM)": (np.cumsum(rng.standard_normal(n)), "f^-2"),
    "flicker walk FM: cumsum(flicker FM)": (np.cumsum(generate.octave_flicker(n, rng=rng)), "f^-3"),
    "random run FM: cumsum(random walk)": (np.cumsum(np.cumsum(rng.standard_normal(n))), "f^-4"),
}

# %%
# One row per noise type
# -----------------------
fig, axes = plt.subplots(len(noises), 3, figsize=(10, 2.0 * len(noises)),
                         gridspec_kw={"width_ratios": [2.2, 1.4, 1]})
for row, (name, (x, slope)) in zip(axes, noises.items()):
    x = unit(x)
    series_ax, psd_ax, lag_ax = row
    series_ax.plot(np.arange(n) / rate, x, lw=0.4, color="#1f4e79")
    series_ax.set_ylabel(name.split(":")[0], fontsize=8)
    series_ax.tick_params(labelsize=7)
    spectrum = sigmatau.psd(x, rate=rate, segments=16)
    psd_ax.loglog(spectrum.raw_f, spectrum.raw_s_y, lw=0.3, color="0.75")
    psd_ax.loglog(spectrum.f, spectrum.s_y, ".-", ms=3, color="#c0504d")
    psd_ax.text(0.97, 0.9, f"S(f) ∝ {slope}", transform=psd_ax.transAxes, ha="right", va="top",
                fontsize=8)
    psd_ax.tick_params(labelsize=7)
    lag_ax.plot(x[:-1], x[1:], ",", color="#1f4e79", alpha=0.5)
    lag_ax.set_aspect("equal", adjustable="datalim")
    lag_ax.tick_params(labelsize=7)
axes[0, 0].set_title("time series", fontsize=9)
axes[0, 1].set_title("PSD (log bins over Welch)", fontsize=9)
axes[0, 2].set_title("lag plot: x[k+1] vs x[k]", fontsize=9)
axes[-1, 0].set_xlabel("t [s]", fontsize=8)
axes[-1, 1].set_xlabel("f [Hz]", fontsize=8)
fig.tight_layout()

# %%
# White noise fills the lag plot as a round cloud (no memory from one sample to the next);
# the walks draw a diagonal line (each sample is almost the one before); the phase noises,
# differences of white or flicker noise, lean the other way (negative lag-1 correlation). The
# lag-1 autocorrelation is what :func:`sigmatau.identify` uses to tell the noise type at each τ
# when enough averages remain.
for name, (x, _) in noises.items():
    x = unit(x)
    print(f"{name:38s} lag-1 autocorrelation {np.corrcoef(x[:-1], x[1:])[0, 1]:+.3f}")
