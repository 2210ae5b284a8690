"""Figures: σ–τ plots with intervals and the fitted IMU model; series, PSD and lag plot.

Nothing in the core imports this module and ``import sigmatau`` does not load
matplotlib: the figures are built with the object-oriented API only
(:class:`matplotlib.figure.Figure` on an Agg canvas, no pyplot and no change
to the global ``rcParams`` while drawing), so they work headless, in threads
and in Dask workers. Matplotlib is the optional extra ``plot``
(``pip install "sigmatau[plot]"``).

Plotting never computes a statistic: :func:`sigma_tau_figure` takes
:class:`~sigmatau.core.result.StabilityResult` curves and the
:class:`~sigmatau.imu.NoiseModel` fitted on them. :func:`signal_figure`
draws the design tip's Figure 2 panels (time series, Welch PSD, lag plot)
for one channel, from the passes over the record that :func:`prepare_signal`
makes (separately, so that they can run in other threads). :func:`save_figure` and :func:`figure_to_data_uri` write
PNG/SVG/PDF with reproducible bytes (no dates, fixed SVG ids).

Colours are the Okabe–Ito palette for the statistics (each statistic keeps
its colour in every panel and figure) and Paul Tol's muted palette for the
model terms, both readable with the common colour-vision deficiencies.

The figures are built in sibling modules — :mod:`.figbase` (style, log axes,
saving), :mod:`.sigmafig` (σ–τ), :mod:`.figmodel` (its model and datasheet
overlays) and :mod:`.signalfig` (series, PSD, lag plot). This module is their
public face and every name below stays importable from it: the report and
batch writers call ``plots.save_figure`` and friends through this module, so
tests may replace them here.

Examples
--------
>>> import numpy as np, sigmatau
>>> from sigmatau import plots                                    # doctest: +SKIP
>>> y = np.random.default_rng(1).normal(size=4096)
>>> ch = plots.ChannelCurves("x", "rad/s", {"oadev": sigmatau.oadev(y, rate=100.0)})  # doctest: +SKIP
>>> fig = plots.sigma_tau_figure([ch], title="white noise")       # doctest: +SKIP
>>> paths = plots.save_figure(fig, "out/sigma_tau")               # doctest: +SKIP
"""

from __future__ import annotations

from .figbase import (STATISTIC_COLORS, TERM_COLORS, ChannelCurves, figure_to_bytes, figure_to_data_uri,
                      save_figure)
# Outside __all__ but used through this module by the batch fleet figures (scale.batch).
from .figbase import matplotlib_modules, new_figure  # noqa: F401
from .dynamicfig import dynamic_figure
from .sigmafig import sigma_tau_figure
from .signalfig import SignalData, prepare_signal, signal_figure

__all__ = [
    "ChannelCurves",
    "dynamic_figure",
    "STATISTIC_COLORS",
    "TERM_COLORS",
    "sigma_tau_figure",
    "signal_figure",
    "prepare_signal",
    "SignalData",
    "save_figure",
    "figure_to_bytes",
    "figure_to_data_uri",
]
