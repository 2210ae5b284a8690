"""``plot()`` of the result types, for notebooks and scripts: σ–τ on given or new matplotlib axes.

The result classes (:class:`~sigmatau.StabilityResult`, :class:`~sigmatau.imu.NoiseModel`,
``ChannelAnalysis``, ``LogAnalysis``) sit below this layer; their ``plot`` methods
reach these functions through :func:`sigmatau.core.present.plot`, registered by the
package. With ``ax=None`` a new figure is made with pyplot, as pandas and xarray do,
so that a notebook shows it; given axes are drawn on and returned.
"""

from __future__ import annotations

from typing import Any, Optional, Sequence

import numpy as np

from ..core.present import noise_name
from ..errors import ParameterError
from .figbase import _pretty

__all__ = ["plot_result", "plot_model", "plot_channel", "plot_log"]


def _axes(ax: Any) -> Any:
    """``ax``, or the axes of a new pyplot figure (log–log)."""
    if ax is None:
        try:
            import matplotlib.pyplot as plt
        except ImportError:
            from ..errors import MissingDependencyError

            raise MissingDependencyError('plot() needs matplotlib: pip install "sigmatau[plot]"') from None
        _, ax = plt.subplots(figsize=(7.0, 4.5), layout="constrained")
    ax.set_xscale("log")
    ax.set_yscale("log")
    return ax


def _label_axes(ax: Any, ylabel: str) -> None:
    ax.set_xlabel("τ [s]")
    ax.set_ylabel(ylabel)
    ax.grid(True, which="both", alpha=0.3)


def plot_result(result: Any, ax: Any = None, *, label: Optional[str] = None, unit: str = "", band: bool = True,
                **kw: Any) -> Any:
    """σ(τ) of a :class:`~sigmatau.StabilityResult` with its interval band.

    Points with a non-positive or missing deviation are not drawn (log axes). The
    noise type of each point is in the line's ``gid`` list for tools that read it.
    """
    ax = _axes(ax)
    ok = np.isfinite(result.dev) & (result.dev > 0)
    line, = ax.plot(result.taus[ok], result.dev[ok], marker="o", markersize=3,
                    label=result.statistic if label is None else label, **kw)
    line.set_gid(",".join(noise_name(a) for a in (result.alpha[ok] if result.alpha is not None else [])))
    if band and result.ci_low is not None and result.ci_high is not None:
        lo = np.where(np.isfinite(result.ci_low) & (result.ci_low > 0), result.ci_low, np.nan)[ok]
        hi = np.where(np.isfinite(result.ci_high), result.ci_high, np.nan)[ok]
        ax.fill_between(result.taus[ok], np.where(np.isnan(lo), result.dev[ok], lo),
                        np.where(np.isnan(hi), result.dev[ok], hi), color=line.get_color(), alpha=0.2, linewidth=0)
    _label_axes(ax, f"deviation [{_pretty(unit)}]" if unit else "deviation")
    ax.legend(loc="best", fontsize="small")
    return ax


def plot_model(model: Any, ax: Any = None, *, label: Optional[str] = None, terms: bool = True,
               **kw: Any) -> Any:
    """The OADEV curve of an IMU :class:`~sigmatau.imu.NoiseModel` with the fitted model and its terms."""
    ax = plot_result(model.result, ax, label=label or f"{model.kind} OADEV", unit=model.unit, **kw)
    taus = np.geomspace(model.result.taus[0], model.result.taus[-1], 200)
    color = ax.get_lines()[-1].get_color()
    ax.plot(taus, model.deviation(taus), color="black", linewidth=1.2, linestyle="--", alpha=0.8, label="model")
    if terms:
        for t in model.fit_terms:
            dev = model.term_deviation(t, taus)
            if np.any(np.isfinite(dev) & (dev > 0)):
                ax.plot(taus, dev, linestyle=":", linewidth=1.0, color=color, alpha=0.7, label=f"{t} term")
    ax.legend(loc="best", fontsize="small")
    return ax


def plot_channel(channel: Any, ax: Any = None, *, statistics: Optional[Sequence[str]] = None, **kw: Any) -> Any:
    """Every statistic of a ``ChannelAnalysis`` (or those named) and its fitted model on one axes."""
    names = list(channel.results) if statistics is None else list(statistics)
    unknown = [s for s in names if s not in channel.results]
    if unknown:
        raise ParameterError(f"statistics {unknown} were not computed for {channel.name!r};"
                             f" computed: {', '.join(channel.results) or 'none'}")
    ax = _axes(ax)
    for name in names:
        plot_result(channel.results[name], ax, label=f"{channel.name} {name}", unit=channel.unit, **kw)
    if channel.model is not None:
        taus = np.geomspace(channel.model.result.taus[0], channel.model.result.taus[-1], 200)
        ax.plot(taus, channel.model.deviation(taus), color="black", linewidth=1.0, alpha=0.7,
                label=f"{channel.name} model")
        ax.legend(loc="best", fontsize="small")
    ax.set_title(channel.name)
    return ax


def plot_log(analysis: Any, ax: Any = None, *, group: Optional[str] = None, statistic: Optional[str] = None,
             model: bool = True, **kw: Any) -> Any:
    """One statistic of every channel of a group of a ``LogAnalysis``, with each channel's model."""
    groups = {g: [c for c in chans if c.results] for g, chans in analysis.groups().items()}
    groups = {g: cs for g, cs in groups.items() if cs}
    if not groups:
        raise ParameterError("the analysis has no statistics to draw")
    if group is None:
        group = next(iter(groups))
    if group not in groups:
        raise ParameterError(f"group={group!r} has no statistics; groups: {', '.join(groups)}")
    chans = groups[group]
    stat = statistic or ("oadev" if "oadev" in chans[0].results else next(iter(chans[0].results)))
    ax = _axes(ax)
    for c in chans:
        if stat not in c.results:
            continue
        plot_result(c.results[stat], ax, label=f"{c.name} {stat}", unit=c.unit, **kw)
        if model and c.model is not None:
            taus = np.geomspace(c.model.result.taus[0], c.model.result.taus[-1], 200)
            ax.plot(taus, c.model.deviation(taus), color=ax.get_lines()[-1].get_color(), linewidth=1.0,
                    alpha=0.6, linestyle="--")
    ax.set_title(f"{group}: {stat}")
    ax.legend(loc="best", fontsize="small")
    return ax
