"""The σ–τ figure: one log–log panel per channel with intervals, model and datasheet terms.

Public through :mod:`sigmatau.report.plots` (:func:`sigma_tau_figure`).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, Mapping, Optional, Sequence, Union

import numpy as np

from ..errors import ParameterError
from .figbase import (_DISPLAY, _FALLBACK_COLORS, _FS, _FS_LABEL, _FS_TITLE, _MARKERS, _PROMINENT, _SLOPE_TEXT,
                      _TIME_STATS, STATISTIC_COLORS, _BELOW_AXES_PT, ChannelCurves, _below_axes, _freeze_layout,
                      _log_axis, _log_limits, _Panel, _positive, _pretty, _set_title, _spines_out_of_layout,
                      _style_log_axes, new_figure)
from .figmodel import _datasheet_terms, _draw_datasheet, _draw_model

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure

    from ..imu.model import Preset

def _as_channel(obj: object, i: int) -> ChannelCurves:
    """Channel ``i`` of :func:`sigma_tau_figure` as a checked ChannelCurves."""
    if isinstance(obj, ChannelCurves):
        ch = obj
    elif isinstance(obj, (tuple, list)) and len(obj) in (3, 4):
        ch = ChannelCurves(*obj)
    elif all(hasattr(obj, a) for a in ("name", "unit", "results")):
        ch = ChannelCurves(obj.name, obj.unit, obj.results, getattr(obj, "model", None))  # type: ignore[attr-defined]
    else:
        raise ParameterError(
            f"channels[{i}]={obj!r:.80} must be a ChannelCurves or a (name, unit, results[, model]) tuple"
        )
    if not isinstance(ch.name, str) or not isinstance(ch.unit, str):
        raise ParameterError(f"channels[{i}]: name={ch.name!r} and unit={ch.unit!r} must be strings")
    if not isinstance(ch.results, Mapping):
        raise ParameterError(f"channels[{i}] ({ch.name}): results must be a mapping statistic → StabilityResult,"
                             f" got {type(ch.results).__name__}")
    for key, res in ch.results.items():
        if not (hasattr(res, "taus") and hasattr(res, "dev")):
            raise ParameterError(f"channels[{i}] ({ch.name}): results[{key!r}] must be a StabilityResult,"
                                 f" got {type(res).__name__}")
    if ch.model is not None and not hasattr(ch.model, "term_deviation"):
        raise ParameterError(f"channels[{i}] ({ch.name}): model must be a sigmatau.imu.NoiseModel,"
                             f" got {type(ch.model).__name__}")
    return ch


def _stat_color(stat: str, order: list[str]) -> str:
    """The statistic's colour; unknown statistics take the fallback palette in order of appearance."""
    if stat in STATISTIC_COLORS:
        return STATISTIC_COLORS[stat]
    if stat not in order:
        order.append(stat)
    return _FALLBACK_COLORS[order.index(stat) % len(_FALLBACK_COLORS)]


def _draw_statistics(p: _Panel, ch: ChannelCurves, stats: list[str], legend: dict, order: list[str],
                     notes: list[str]) -> None:
    """Each statistic's curve and interval band (time-error ones on a right axis created on demand).

    Adds one legend entry per statistic label, the fallback colours in use to
    ``order`` and a note for zero values that a log axis cannot show.
    """
    prominent = next((s for s in ("oadev", "adev") if s in stats), None)
    zeros: list[str] = []
    for stat in stats:
        res = ch.results[stat]
        taus = np.asarray(res.taus, dtype=float)
        n = taus.size
        if n == 0:
            continue
        raw = np.asarray(res.dev, dtype=float)
        dev = _positive(raw, n)
        dropped = int(np.sum(np.isfinite(raw) & (raw <= 0))) if raw.shape == (n,) else 0
        if dropped:
            zeros.append(f"{dropped} {_DISPLAY.get(stat, stat)}")
        lo, hi = _positive(getattr(res, "ci_low", None), n), _positive(getattr(res, "ci_high", None), n)
        ok = np.isfinite(taus) & (taus > 0) & np.isfinite(dev)
        if not ok.any():
            continue
        time_stat = stat in _TIME_STATS
        if time_stat and p.twin is None:
            p.twin = p.ax.twinx()
            p.twin.set_yscale("log")
            _log_axis(p.twin.yaxis)
            p.twin.tick_params(labelsize=_FS, which="both", direction="in")
            _spines_out_of_layout(p.twin)
        ax = p.twin if time_stat else p.ax
        color = _stat_color(stat, order)
        strong = stat == prominent
        label = _DISPLAY.get(stat, stat.upper()) + (" (right axis)" if time_stat else "")
        band = None
        both = ok & np.isfinite(lo) & np.isfinite(hi)
        if both.any():
            band = ax.fill_between(taus[ok], np.where(both, lo, np.nan)[ok], np.where(both, hi, np.nan)[ok],
                                   color=color, alpha=0.22 if strong else 0.12, linewidth=0,
                                   zorder=2 if strong else 1.5)
            band.set_gid(f"band-{stat}-{ch.name}")
            p.take_y(lo[both], twin=time_stat)
            p.take_y(hi[both], twin=time_stat)
        (line,) = ax.plot(taus[ok], dev[ok], color=color, marker=_MARKERS.get(stat, "o"),
                          markersize=4.2 if strong else 3.0, linewidth=1.5 if strong else 0.9,
                          alpha=1.0 if strong else 0.8, markeredgewidth=0.6,
                          markerfacecolor=color if strong else "white", zorder=6 if strong else 4)
        line.set_gid(f"curve-{stat}-{ch.name}")
        p.take_y(dev[ok], twin=time_stat)
        p.take_x(taus[ok])
        p.empty = False
        if label not in legend:
            legend[label] = (line, band)
    if zeros:
        notes.append(f"{ch.name}: zero values not shown on the log axis ({', '.join(zeros)})")


def _draw_slope_fan(p: _Panel, xlim: tuple[float, float], ylim: tuple[float, float]) -> None:
    """Slopes −1 … +1 in the emptiest corner, for panels without a model."""
    ax = p.ax
    lx0, lx1 = math.log10(xlim[0]), math.log10(xlim[1])
    ly0, ly1 = math.log10(ylim[0]), math.log10(ylim[1])
    dx, dy = lx1 - lx0, ly1 - ly0
    length = min(0.14 * dx, 0.17 * dy)
    w, h = length / dx, length / dy  # fan size in axes fractions: width w, ±h about its axis
    pts = []
    for a, lim in ((ax, ylim), (p.twin, p.twin.get_ylim() if p.twin is not None else None)):
        if a is None:
            continue
        for line in a.get_lines():
            xd, yd = (np.asarray(v, dtype=float) for v in line.get_data())
            ok = (xd > 0) & (yd > 0)
            if ok.any():
                pts.append(np.column_stack([(np.log10(xd[ok]) - lx0) / dx,
                                            (np.log10(yd[ok]) - math.log10(lim[0])) / math.log10(lim[1] / lim[0])]))
    xy = np.concatenate(pts) if pts else np.empty((0, 2))
    best = None
    for fx, fy in ((0.05, 0.28), (0.05, 0.72), (0.72, 0.72), (0.72, 0.28)):
        inside = (xy[:, 0] > fx - 0.03) & (xy[:, 0] < fx + w + 0.1) & (np.abs(xy[:, 1] - fy) < h + 0.06)
        if best is None or int(inside.sum()) < best[0]:
            best = (int(inside.sum()), fx, fy)
    assert best is not None
    x0, y0 = lx0 + best[1] * dx, ly0 + best[2] * dy
    for sl in (-1.0, -0.5, 0.0, 0.5, 1.0):
        xs = np.array([x0, x0 + length])
        ys = np.array([y0, y0 + sl * length])
        ax.plot(10 ** xs, 10 ** ys, color="0.55", linewidth=0.8, zorder=1.1, gid=f"slope-guide-{sl:+g}")
        ax.text(10 ** (xs[1] + 0.012 * dx), 10 ** ys[1], _SLOPE_TEXT[sl], fontsize=_FS - 1.5, color="0.4",
                va="center", ha="left")
    ax.text(10 ** x0, 10 ** (y0 + length + 0.03 * dy), "slope", fontsize=_FS - 1.5, color="0.4", va="bottom")


def sigma_tau_figure(
    channels: Sequence[Union[ChannelCurves, tuple]],
    *,
    title: Optional[str] = None,
    datasheet: Optional[Union[Mapping[str, Any], "Preset"]] = None,
    statistics: Optional[Sequence[str]] = None,
) -> "Figure":
    """σ–τ figure of one sensor group: one log–log panel per channel.

    Parameters
    ----------
    channels : sequence of ChannelCurves or (name, unit, results[, model]) tuples
        The channels (e.g. the three gyro axes). Panels share the σ axis when
        every channel has the same unit.
    title : str, optional
        Figure title.
    datasheet : mapping or sigmatau.imu.Preset, optional
        Datasheet terms drawn as grey dash-dot lines: ``{"N": 6.98e-5}`` in
        the term units of the panel's unit, ``{"N": (4.0, "mdps/sqrt(Hz)")}``
        in any unit, or a :data:`sigmatau.imu.PRESETS` entry (SI, converted).
    statistics : sequence of str, optional
        Statistics to draw and their order (default: every one given, OADEV first).

    Returns
    -------
    matplotlib.figure.Figure
        On an Agg canvas; save it with :func:`save_figure`.

    Notes
    -----
    Each statistic is a line with markers and its interval ``ci_low … ci_high``
    as a shaded band where finite; OADEV is drawn strongest. Time-error
    statistics (TDEV, TTOTDEV, MTIE, TIE rms; unit·s) go on a right-hand
    axis. With a :class:`~sigmatau.imu.NoiseModel`: the fitted total, each
    resolved term with its value in customary units, each unresolved term as
    a ▼ upper bound on the term's line where it comes closest to the curve,
    and each read-off as its fixed-slope line over the region it was fitted in
    (shaded), the point where the line is read (◇: N at 1 s, K at 3 s, B at the
    flat bottom …) and a faint guide of that slope across the panel. Panels
    without a model get slope guides (−1 … +1) in a corner.

    Raises
    ------
    ParameterError
        Malformed channels, statistics or datasheet.
    MissingDependencyError
        matplotlib is not installed.
    """
    chans, statistics = _check_figure_args(channels, title, statistics)
    ds_terms = [_datasheet_terms(datasheet, ch.unit) for ch in chans]

    n = len(chans)
    ncols = min(n, 3)
    nrows = math.ceil(n / ncols)
    shared = len({ch.unit for ch in chans}) == 1
    fig = new_figure((0.6 + 4.1 * ncols, 1.0 + 4.3 * nrows))
    axes = fig.subplots(nrows, ncols, sharey=shared, sharex=False, squeeze=False).ravel()
    for extra in axes[n:]:
        extra.set_visible(False)

    legend: dict[str, tuple] = {}
    order: list[str] = []
    notes: list[str] = []
    panels: list[_Panel] = []
    for ch, ax, ds in zip(chans, axes, ds_terms):
        _style_log_axes(ax)
        p = _Panel(ax=ax, term_handles=[])
        _draw_statistics(p, ch, _panel_statistics(ch, statistics), legend, order, notes)
        if ch.model is not None:
            _draw_model(p, ch, legend, notes)
        _draw_datasheet(p, ch, ds, legend)
        panels.append(p)

    ylims, tlim = _panel_limits(panels, shared)
    for i, (ch, p) in enumerate(zip(chans, panels)):
        _finish_panel(p, ch, ylims[i], tlim, label_y=not shared or i % ncols == 0,
                      last_in_row=i % ncols == ncols - 1 or i == n - 1, shared=shared)
    _figure_legend(fig, legend, ncols)
    _figure_title(fig, title, notes)
    _freeze_layout(fig)
    return fig


def _check_figure_args(channels: Any, title: Any, statistics: Any) -> tuple[list[ChannelCurves], Optional[list[str]]]:
    """The channels of :func:`sigma_tau_figure` as ChannelCurves and its statistics as a list (or None)."""
    if isinstance(channels, ChannelCurves):
        channels = [channels]
    if isinstance(channels, (str, bytes, Mapping)) or not hasattr(channels, "__iter__"):
        raise ParameterError(f"channels={channels!r:.80} must be a sequence of ChannelCurves")
    chans = [_as_channel(c, i) for i, c in enumerate(channels)]
    if not chans:
        raise ParameterError("channels is empty: give at least one channel to plot")
    if statistics is not None:
        if isinstance(statistics, str) or not all(isinstance(s, str) for s in statistics):
            raise ParameterError(f"statistics={statistics!r} must be a sequence of statistic names")
        statistics = list(statistics)
    if title is not None and not isinstance(title, str):
        raise ParameterError(f"title={title!r} must be a string")
    return chans, statistics


def _panel_statistics(ch: ChannelCurves, statistics: Optional[list[str]]) -> list[str]:
    """The statistics drawn on a panel, in drawing order.

    The caller's order when given; otherwise OADEV/ADEV first, the time-error
    statistics (right axis) last, the rest as given.
    """
    names = list(ch.results)
    if statistics is not None:
        return [s for s in statistics if s in ch.results]
    given = list(names)
    names.sort(key=lambda s: (s not in _PROMINENT, s in _TIME_STATS, given.index(s)))
    return names


def _panel_limits(panels: list[_Panel], shared: bool
                  ) -> tuple[list[tuple[float, float]], Optional[tuple[float, float]]]:
    """σ limits of each panel (one range for all when the axis is shared) and the right-axis limits."""
    ylims = [_log_limits(p.ylo, p.yhi, 0.06, 0.08) for p in panels]
    if shared:
        finite = [p for p in panels if p.ylo <= p.yhi]
        lim = (_log_limits(min(p.ylo for p in finite), max(p.yhi for p in finite), 0.06, 0.08)
               if finite else (0.1, 10.0))
        ylims = [lim] * len(panels)
    tl = [p for p in panels if p.twin is not None and p.tlo <= p.thi]
    tlim = _log_limits(min(p.tlo for p in tl), max(p.thi for p in tl), 0.06, 0.08) if tl else None
    return ylims, tlim


def _finish_panel(p: _Panel, ch: ChannelCurves, ylim: tuple[float, float], tlim: Optional[tuple[float, float]],
                  *, label_y: bool, last_in_row: bool, shared: bool) -> None:
    """Limits, labels and title of one panel, its empty-panel note or slope fan, and its term legend.

    ``label_y``: this panel carries the σ label (first of its row, or axes not
    shared); ``last_in_row``: it carries the right-axis label when that axis is shared.
    """
    ax = p.ax
    xlim = _log_limits(p.xlo, p.xhi, 0.04, 0.04, min_span=2.0) if p.xlo <= p.xhi else (0.1, 10.0)
    ax.set_xlim(*xlim)
    ax.set_ylim(*ylim)
    ax.set_xlabel("averaging time τ [s]", fontsize=_FS_LABEL)
    if label_y:
        ax.set_ylabel(f"σ(τ) [{_pretty(ch.unit)}]" if ch.unit else "σ_y(τ) (fractional frequency)",
                      fontsize=_FS_LABEL)
    _set_title(ax, ch.name, _FS_TITLE)
    if p.twin is not None:
        if tlim is not None:
            p.twin.set_ylim(*tlim)
        if shared and tlim is not None and not last_in_row:
            p.twin.tick_params(labelright=False)
        else:
            tunit = f"{ch.unit}·s" if ch.unit else "s"
            p.twin.set_ylabel(f"x(τ) [{_pretty(tunit)}]", fontsize=_FS_LABEL)
    if p.empty:
        ax.text(0.5, 0.5, "no positive deviation to plot\n(constant or empty data?)", transform=ax.transAxes,
                ha="center", va="center", fontsize=_FS, color="0.3")
    elif ch.model is None:
        _draw_slope_fan(p, xlim, ylim)
    if p.term_handles:
        # A fixed distance below the axes (not a fraction of their height): one layout pass suffices.
        ax.legend(handles=p.term_handles, loc="upper center", bbox_to_anchor=(0.5, 0.0),
                  bbox_transform=_below_axes(ax, _BELOW_AXES_PT), fontsize=_FS - 0.5, frameon=False,
                  handlelength=2.6, borderaxespad=0.0)


def _figure_legend(fig: "Figure", legend: dict, ncols: int) -> None:
    """The shared legend of the statistics (line and band together) below the panels."""
    handles, labels = [], []
    for label, (line, band) in legend.items():
        handles.append((band, line) if band is not None else line)
        labels.append(label)
    if handles:
        from matplotlib.legend_handler import HandlerTuple

        fig.legend(handles, labels, loc="outside lower center", ncols=min(len(handles), 4 if ncols > 1 else 2),
                   fontsize=_FS, frameon=False, handler_map={tuple: HandlerTuple(ndivide=1)}, handlelength=2.4)


def _figure_title(fig: "Figure", title: Optional[str], notes: list[str]) -> None:
    """The figure title, followed by the notes gathered while drawing (wrapped to the figure width)."""
    head = title or ""
    if notes:
        import textwrap

        wrapped = textwrap.fill("; ".join(notes), width=int(fig.get_figwidth() * 11))
        head = (head + "\n" if head else "") + wrapped
    if head:
        fig.suptitle(head, fontsize=_FS_TITLE + 1)
