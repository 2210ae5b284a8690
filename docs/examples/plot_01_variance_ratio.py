"""
The design tip's Figure 1: why the Allan variance
==================================================

ST's design tip DT0064 opens with two pictures. On the left, the ratio of the plain (standard)
variance to the Allan variance: for white noise the two agree, whatever the length of the
record; for flicker and random-walk noise the standard variance keeps growing with the record and
says nothing stable about the sensor. On the right, the chain of digital filters that computes the Allan family:
``M(m)`` (moving average of m samples) → ``D1(m)`` (difference of samples m apart) → ``m:1``
(keep one sample in m) → half the mean square.

This example draws both, with the design tip's own noise generators (``cumsum`` for random walk,
the octave bank for flicker noise), and checks that :mod:`sigmatau.filterchain` (the filters
written plainly) and the fast statistics (:func:`sigmatau.oadev`, :func:`sigmatau.stdev`) agree.
"""

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.patches import FancyArrowPatch, FancyBboxPatch

import sigmatau
from sigmatau import filterchain, generate

rng = np.random.default_rng(2016)
n = 2**15
rate = 1.0  # one sample per second: τ = m seconds

# %%
# The noise types, generated the way the design tip does
# --------------------------------------------------------
# White noise is ``randn``; integrating it gives a random walk; flicker (1/f) noise comes from
# the tip's bank of octave generators (:func:`sigmatau.generate.octave_flicker`); differencing
# white noise gives white phase noise.
white = rng.standard_normal(n)
series = {
    "white PM (diff of white)": np.diff(rng.standard_normal(n + 1)),
    "white FM (randn)": white,
    "flicker FM (octave bank)": generate.octave_flicker(n, rng=rng),
    "random walk FM (cumsum)": np.cumsum(rng.standard_normal(n)) / 30,
}

# %%
# Left: the standard variance over the Allan variance, as the record grows
# ------------------------------------------------------------------------
# For each record length N (the first N samples), the ratio of the standard variance of the
# samples (:func:`sigmatau.stdev` at m = 1) to their Allan variance (:func:`sigmatau.adev` at
# m = 1). ``ci=None`` asks for the bare estimators (no noise identification, no interval).
lengths = 2 ** np.arange(6, 16)
ratios = {}
for name, y in series.items():
    ratios[name] = [sigmatau.stdev(y[:k], rate=rate, m=[1], ci=None).var[0]
                    / sigmatau.adev(y[:k], rate=rate, m=[1], ci=None).var[0] for k in lengths]
    print(f"{name:28s} N = {lengths[0]}: {ratios[name][0]:8.2f}   N = {lengths[-1]}: {ratios[name][-1]:8.2f}")

# %%
# Right: the filter chain
# ------------------------
# Each box is one of the tip's filters; a transient must never reach the output, so every
# filter drops its first outputs. The Allan variance is half the mean square of what comes
# out; without the ``m:1`` decimation it is the overlapped Allan variance (OAVAR), with a
# second ``M(m)`` after ``D1(m)`` the modified Allan variance (MVAR).
fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.2), gridspec_kw={"width_ratios": [1.1, 1]})
for name, r in ratios.items():
    left.loglog(lengths, r, "o-", ms=3, label=name)
left.axhline(1.0, color="0.5", lw=0.8, ls=":")
left.set_xlabel("record length N [samples]")
left.set_ylabel("var / AVAR")
left.set_title("the standard variance does not settle")
left.legend(fontsize=8)

right.set_axis_off()
right.set_xlim(0, 10)
right.set_ylim(0, 4)
boxes = [("x[n]", 0.2, 1.3), ("M(m)", 1.9, 1.3), ("D1(m)", 3.6, 1.3), ("m:1", 5.3, 1.3),
         ("½·mean(·²)", 7.0, 2.2)]
for label, x, width in boxes:
    right.add_patch(FancyBboxPatch((x, 1.6), width, 0.8, boxstyle="round,pad=0.1",
                                   fc="white" if label == "x[n]" else "#e8f0fa", ec="#1f4e79"))
    right.text(x + width / 2, 2.0, label, ha="center", va="center")
for (_, x0, w0), (_, x1, _) in zip(boxes, boxes[1:]):
    right.add_patch(FancyArrowPatch((x0 + w0 + 0.05, 2.0), (x1 - 0.05, 2.0), arrowstyle="-|>",
                                    mutation_scale=12, color="#1f4e79"))
right.text(5.0, 3.3, "AVAR: M(m) → D1(m) → m:1 → ½·mean square", ha="center", fontsize=9)
right.text(5.0, 0.9, "OAVAR: no m:1      MVAR: M(m) → D1(m) → M(m)", ha="center", fontsize=9)
right.text(5.0, 0.4, "STDVAR: M(m) → m:1 → variance", ha="center", fontsize=9)
right.set_title("the chain of digital filters")
fig.tight_layout()

# %%
# For white FM the two variances agree whatever the length (the ratio stays at 1; for white PM
# it stays at 2/3); for flicker FM the standard variance creeps up with the record and for
# random-walk FM it grows in proportion to it, so it says more about how long one recorded than
# about the sensor. The Allan variance settles: that is why the Allan family exists.
#
# The filter chain and the fast statistics give the same numbers
# ----------------------------------------------------------------
# :mod:`sigmatau.filterchain` is the tip's chain written plainly; the statistics use running
# sums (the tip's second formulation). The test suite holds them to 1e-10 on all seven noise
# types; here on the random walk:
y = series["random walk FM (cumsum)"]
print(f"{'m':>5} {'filter chain OAVAR':>20} {'sigmatau.oadev':>20} {'relative difference':>20}")
for mm in (1, 4, 16, 64, 256):
    chain = filterchain.oavar(y, mm, rate=rate)
    fast = sigmatau.oadev(y, rate=rate, m=[mm], ci=None).var[0]
    print(f"{mm:5d} {chain:20.12e} {fast:20.12e} {abs(chain - fast) / fast:20.1e}")
