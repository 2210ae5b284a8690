"""The dynamic-stability figure: a (time × τ) heat map of the deviation over sliding windows.

Draws a :class:`sigmatau.stats.dynamic.DynamicResult` (from :func:`sigmatau.stats.dynamic.dynamic`);
computes nothing. Matplotlib is imported only when drawing (:func:`.figbase.new_figure`).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, Optional

import numpy as np

from ..errors import ParameterError
from .figbase import (_DISPLAY, _FS, _FS_LABEL, _FS_TITLE, _TIME_STATS, _freeze_layout, _log_axis, _pretty,
                      _set_title, new_figure)
from .signalfig import _time_scale

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from ..stats.dynamic import DynamicResult

__all__ = ["dynamic_figure"]


def _edges(centres: np.ndarray, log: bool) -> np.ndarray:
    """Cell edges around ``centres`` (midpoints; geometric ones on a log axis)."""
    c = np.log10(centres) if log else np.asarray(centres, dtype=float)
    if c.size == 1:
        half = 0.15 if log else 0.5
        e = np.array([c[0] - half, c[0] + half])
    else:
        mid = 0.5 * (c[1:] + c[:-1])
        e = np.concatenate(([c[0] - (mid[0] - c[0])], mid, [c[-1] + (c[-1] - mid[-1])]))
    return 10.0**e if log else e


def _check(result: Any, ax: Any, unit: Any, title: Any, cmap: Any) -> None:
    needed = ("dev", "taus", "centre", "start", "window", "rate", "stationarity", "statistic")
    if not all(hasattr(result, a) for a in needed):
        raise ParameterError(f"result must be a DynamicResult (sigmatau.stats.dynamic.dynamic), got {type(result).__name__}")
    if ax is not None and not hasattr(ax, "pcolormesh"):
        raise ParameterError(f"ax must be a matplotlib Axes, got {type(ax).__name__}")
    for name, value in (("unit", unit), ("title", title), ("cmap", cmap)):
        if value is not None and not isinstance(value, str):
            raise ParameterError(f"{name}={value!r} must be a string")


def dynamic_figure(
    result: "DynamicResult",
    ax: Optional["Axes"] = None,
    *,
    unit: str = "",
    title: Optional[str] = None,
    cmap: str = "viridis",
    mark: bool = True,
) -> "Figure":
    """Heat map of a dynamic stability result: window time across, τ up, the deviation in colour.

    Parameters
    ----------
    result : DynamicResult
        From :func:`sigmatau.stats.dynamic.dynamic`.
    ax : matplotlib.axes.Axes, optional
        Draw into these axes (a colour bar is added beside them); by default a new figure
        on an Agg canvas.
    unit : str
        Unit of the frequency-type samples, for the colour-bar label (``""``: fractional
        frequency; time-error statistics such as TDEV are labelled in ``unit·s``).
    title : str, optional
        Panel title (default: the statistic, window and step).
    cmap : str
        Matplotlib colour map.
    mark : bool
        Mark the cells whose window disagrees with the others
        (``result.stationarity.disagree``) and the located change of level.

    Returns
    -------
    matplotlib.figure.Figure
        The figure drawn on (the heat map is its first axes, or ``ax``).

    Notes
    -----
    Each column is one window, centred on its centre time and as wide as the step;
    overlapping windows therefore share samples with their neighbours. The colour scale is
    logarithmic; cells without an estimate stay blank. Cells that disagree are crossed
    (×) and a dashed line marks the single change of level the stationarity test located.
    """
    _check(result, ax, unit, title, cmap)
    from matplotlib.colors import LogNorm

    dev = np.asarray(result.dev, dtype=float)
    taus = np.asarray(result.taus, dtype=float)
    centre = np.asarray(result.centre, dtype=float)
    own = ax is None
    if own:
        fig = new_figure((7.6, 4.4))
        ax = fig.subplots()
    else:
        fig = ax.get_figure()
    span = float(result.window) / float(result.rate)
    scale, tunit = _time_scale(max(float(centre[-1]) + span / 2, span) if centre.size else span)
    shown = np.where(np.isfinite(dev) & (dev > 0), dev, np.nan)
    positive = shown[np.isfinite(shown)]
    if positive.size and taus.size:
        lo, hi = float(positive.min()), float(positive.max())
        if hi <= lo:
            lo, hi = lo / 1.5, hi * 1.5
        mesh = ax.pcolormesh(_edges(centre / scale, False), _edges(taus, True), np.ma.masked_invalid(shown.T),
                             cmap=cmap, norm=LogNorm(vmin=lo, vmax=hi), shading="flat")
        mesh.set_gid("dynamic-heatmap")
        bar = fig.colorbar(mesh, ax=ax, pad=0.02)
        bar.set_label(_bar_label(result.statistic, unit), fontsize=_FS_LABEL)
        bar.ax.tick_params(labelsize=_FS)
        if mark:
            _mark(ax, result, centre / scale, taus, scale)
    else:
        ax.text(0.5, 0.5, "no positive deviation to plot", transform=ax.transAxes, ha="center", va="center",
                fontsize=_FS, color="0.3")
    ax.set_yscale("log")
    _log_axis(ax.yaxis)
    ax.tick_params(labelsize=_FS, which="both", direction="out")
    ax.set_xlabel(f"window centre [{tunit}]", fontsize=_FS_LABEL)
    ax.set_ylabel("averaging time τ [s]", fontsize=_FS_LABEL)
    name = _DISPLAY.get(result.statistic, result.statistic)
    head = title if title is not None else (f"Dynamic {name}: windows of {_duration(span)}"
                                            f" every {_duration(result.step / result.rate)}")
    _set_title(ax, head, _FS_TITLE)
    if own:
        _freeze_layout(fig)
    return fig


def _mark(ax: Any, result: Any, x: np.ndarray, taus: np.ndarray, scale: float) -> None:
    """Crosses on the disagreeing cells, a dashed line at the located change, the finding's legend."""
    st = result.stationarity
    cells = np.argwhere(np.asarray(st.disagree, dtype=bool))
    handles = []
    if cells.size:
        from matplotlib import patheffects

        h = ax.scatter(x[cells[:, 0]], taus[cells[:, 1]], marker="x", s=16, linewidths=0.9, color="white",
                       zorder=3, label=f"window disagrees (level {st.significance:g})")
        h.set_path_effects([patheffects.withStroke(linewidth=2.0, foreground="black")])
        h.set_gid("dynamic-disagree")
        handles.append(h)
    if st.change_time is not None and math.isfinite(st.change_time):
        line = ax.axvline(st.change_time / scale, color="#D55E00", linestyle="--", linewidth=1.2, zorder=4,
                          label="change of level")
        line.set_gid("dynamic-change")
        handles.append(line)
    if handles:
        ax.legend(handles=handles, loc="upper left", fontsize=_FS - 0.5, framealpha=0.85)


def _bar_label(statistic: str, unit: str) -> str:
    """The colour-bar label: the statistic and its unit (time-error statistics in unit·s)."""
    name = _DISPLAY.get(statistic, statistic)
    if statistic in _TIME_STATS:
        return f"{name} [{_pretty(unit + '·s') if unit else 's'}]"
    return f"{name} [{_pretty(unit)}]" if unit else f"{name} (fractional frequency)"


def _duration(seconds: float) -> str:
    """``seconds`` in the unit a reader expects (s, min, h)."""
    div, unit = _time_scale(seconds)
    return f"{seconds / div:.3g} {unit}"
