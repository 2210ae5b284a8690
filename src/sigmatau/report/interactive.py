"""Interactive σ–τ charts of ``report.html``: Vega-Lite specs drawn by vega-embed, all inlined.

Each σ–τ figure of the report gets, under its static PNG, a chart of the same
channels and statistics: log–log axes that pan (drag) and zoom (wheel; a
double-click resets), a tooltip on every point (τ, deviation, the interval
[min, max], the noise type α and its name, the EDF), legends whose entries hide
and show a statistic, the fitted model or a channel, and the model curve.
Time-error statistics (TDEV …; unit·s) are on a right-hand axis, as in the
static figure.

Why Vega-Lite: measured on the report of a simulated 30-minute 6-axis log (see
``docs/report.md``), its inlined library (vega, vega-lite and vega-embed, one
script of 0.9 MB) makes the smallest page and draws fastest in headless
Chromium, ahead of bokeh (1.3 MB for its core script alone, 3.9 MB for every
``bokeh.resources.INLINE`` bundle) and plotly (4.8 MB). The script comes from
the ``vl-convert-python`` package (the optional ``interactive`` extra), which
bundles those libraries for offline use (what altair's ``save(inline=True)``
calls); nothing is fetched by the page, and no charting package is needed to
*build* the specs: they are plain JSON. Without the extra the report has the
static figures only and one line saying so (:data:`MISSING_NOTE`).

Every name from the user's files (channel names, units, group names) reaches
the page only inside the specs, which are embedded as JSON in
``<script type="application/json">`` elements with ``<``, ``>`` and ``&``
written as ``\\u003c`` … (so ``</script>`` in a channel name cannot end the
element), and are drawn by Vega as SVG text or shown by its tooltip, which
escapes HTML.

This module imports nothing from :mod:`sigmatau.report.html` (which it feeds
through :func:`~sigmatau.report.outputs.write_outputs`); ``vl_convert`` is
imported only when the page is assembled.
"""

from __future__ import annotations

import functools
import json
import math
import re
from dataclasses import dataclass, field
from typing import Any, Mapping, Optional, Sequence

import numpy as np

from ..core.present import noise_name
from .figbase import _DISPLAY, _FALLBACK_COLORS, _PROMINENT, _TIME_STATS, STATISTIC_COLORS, _log_limits, _pretty
from .figmodel import _unit_factor
from .spectrum import _names

__all__ = ["InteractiveCharts", "MISSING_NOTE", "USAGE_NOTE", "MODEL_LABEL", "chart_spec", "chart_html",
           "chart_channels", "library_script", "report_charts", "statistic_label"]

#: The report's one line when the charting library (the ``interactive`` extra) is not installed.
MISSING_NOTE = ('Interactive σ–τ charts need the optional extra: pip install "sigmatau[interactive]" '
                "(static figures only).")
#: The report's one line on how to use the charts.
USAGE_NOTE = ("Under each σ–τ figure, an interactive chart of the same data: drag to pan, scroll to zoom,"
              " double-click to reset; hover a point for τ, σ, its interval, noise type and EDF; click a"
              " legend entry to hide or show a statistic, the model or a channel.")

#: Label of the model curve in the statistic legend.
MODEL_LABEL = "model fit"
#: Points of the model curve (a smooth line on a log axis; the data stay small).
_MODEL_POINTS = 80
#: Point shapes and line dashes that tell the channels of one chart apart (colour is the statistic).
_SHAPES = ("circle", "square", "triangle-up", "diamond", "triangle-down", "cross", "triangle-right",
           "triangle-left")
_DASHES = ([1, 0], [6, 3], [2, 2], [8, 3, 2, 3], [4, 2, 1, 2], [12, 4])
#: Fields of a point record that are per-τ arrays (Vega-Lite's flatten transform makes rows of them).
_ARRAYS = ("tau", "dev", "low", "high", "alpha", "noise", "edf")
#: Vega-Lite expressions of the tooltip texts (a missing value shows as a dash, not "NaN").
_TEXTS = {
    "tau_text": "format(datum.tau, '.4g') + ' s'",
    "dev_text": "format(datum.dev, '.4e') + ' ' + datum.unit",
    "interval_text": ("isValid(datum.low) && isValid(datum.high) ? '[' + format(datum.low, '.4e') + ', '"
                      " + format(datum.high, '.4e') + ']' : '–'"),
    "edf_text": "isValid(datum.edf) ? format(datum.edf, '.4g') : '–'",
}
_TOOLTIP = [("channel", "channel"), ("statistic", "statistic"), ("tau_text", "τ"), ("dev_text", "σ"),
            ("interval_text", "interval [min, max]"), ("noise", "noise type"), ("edf_text", "EDF")]


@dataclass(frozen=True)
class InteractiveCharts:
    """What :func:`~sigmatau.report.html.render` places for the interactive charts.

    Attributes
    ----------
    fragments : mapping of str to str
        Figure stem → the chart's HTML (a target ``<div>`` and its spec as JSON),
        shown under that static figure.
    script : str
        The library and the code that draws every chart, once at the end of the
        page (empty without charts).
    note : str
        One line for the figures section: how to use the charts, or why there are none.
    """

    fragments: Mapping[str, str] = field(default_factory=dict)
    script: str = ""
    note: str = ""


# ----------------------------------------------------------------------- data


def _values(a: Any, n: int) -> list[Optional[float]]:
    """``a`` as a list of n floats, None where missing, not finite or not positive (a log axis drops them)."""
    if a is None:
        return [None] * n
    arr = np.asarray(a, dtype=float)
    if arr.shape != (n,):
        return [None] * n
    return [float(v) if math.isfinite(v) and v > 0 else None for v in arr.tolist()]


def _noise_texts(alpha: Any, n: int, unit: str) -> tuple[list[Optional[int]], list[str]]:
    """α at each τ (None when unknown) and its name: ``"WFM, α = 0 — white noise (ARW/VRW)"``.

    The short name is the one of the notebook tables (:func:`~sigmatau.core.present.noise_name`),
    the long one the name ``sigmatau psd`` gives the type on this kind of data.
    """
    if alpha is None or np.shape(alpha) != (n,):
        return [None] * n, ["–"] * n
    long_names = _names(unit)
    alphas: list[Optional[int]] = []
    texts: list[str] = []
    for a in np.asarray(alpha, dtype=float).tolist():
        if not math.isfinite(a):
            alphas.append(None)
            texts.append("–")
            continue
        k = int(a)
        label = long_names.get(k, "")
        alphas.append(k)
        texts.append(f"{noise_name(k) or 'α'}, α = {k}" + (f" — {label}" if label else ""))
    return alphas, texts


def statistic_label(stat: str) -> str:
    """The statistic's name in the legend (as in the static figure), time-error ones marked."""
    return _DISPLAY.get(stat, stat.upper()) + (" (right axis)" if stat in _TIME_STATS else "")


def _point_record(channel: Any, stat: str, res: Any) -> dict[str, Any]:
    """One channel's statistic as a record of per-τ arrays (flattened into rows by the chart)."""
    n = int(np.asarray(res.taus).size)
    unit = channel.unit
    alphas, noise = _noise_texts(getattr(res, "alpha", None), n, unit)
    shown_unit = _pretty(f"{unit}·s" if unit else "s") if stat in _TIME_STATS else _pretty(unit)
    return {"channel": channel.name, "statistic": statistic_label(stat), "unit": shown_unit,
            "tau": _values(res.taus, n), "dev": _values(res.dev, n),
            "low": _values(getattr(res, "ci_low", None), n), "high": _values(getattr(res, "ci_high", None), n),
            "alpha": alphas, "noise": noise, "edf": _values(getattr(res, "edf", None), n)}


def _model_record(channel: Any) -> Optional[dict[str, Any]]:
    """The fitted model's deviation over the τ span of its OADEV, in the channel's unit (None without one)."""
    model = channel.model
    if model is None:
        return None
    taus = np.asarray(model.result.taus, dtype=float)
    taus = taus[np.isfinite(taus) & (taus > 0)]
    if taus.size == 0:
        return None
    tt = np.geomspace(taus.min() / 1.5, taus.max() * 1.5, _MODEL_POINTS)
    with np.errstate(invalid="ignore"):
        dev = np.asarray(model.deviation(tt), dtype=float) * _unit_factor(model, channel.unit)
    return {"channel": channel.name, "statistic": MODEL_LABEL, "tau": tt.tolist(), "dev": _values(dev, tt.size)}


# ---------------------------------------------------------------------- spec


def _stat_colors(stats: Sequence[str]) -> list[str]:
    """Each statistic's colour as in the static figure (unknown ones take the fallback palette in order)."""
    out, extra = [], 0
    for s in stats:
        if s in STATISTIC_COLORS:
            out.append(STATISTIC_COLORS[s])
        else:
            out.append(_FALLBACK_COLORS[extra % len(_FALLBACK_COLORS)])
            extra += 1
    return out


def _log_scale(values: list[Optional[float]], pad: float) -> dict[str, Any]:
    """A log scale over the positive values, padded as the static figure pads its axes.

    The domain is fixed (not taken from the data shown), so hiding a curve does
    not move the axes; the zoom starts from it and a double-click returns to it.
    """
    scale: dict[str, Any] = {"type": "log", "nice": False}
    good = [v for v in values if v is not None]
    if good:
        scale["domain"] = list(_log_limits(min(good), max(good), pad, pad))
    return scale


def _rows(data: str, *valid: str) -> list[dict[str, Any]]:
    """Transforms that make rows of a dataset's per-τ arrays, keep those with ``valid`` fields, and
    drop what the legends hide (the hidden curves are gone, so they show no tooltip either)."""
    fields = ("tau", "dev") if data == "model" else _ARRAYS
    test = " && ".join(f"isValid(datum.{f})" for f in valid)
    return [{"flatten": list(fields)}, {"filter": test}, {"filter": _SHOWN}]


#: Shown: the statistic and the channel are both selected in their legends (all are at first).
_SHOWN = {"and": [{"param": "statistics", "empty": False}, {"param": "channels", "empty": False}]}


def _legend_params(labels: list[str], names: list[str]) -> list[dict[str, Any]]:
    """The two legend selections: every click toggles an entry, all are selected at first, and a
    double-click (the zoom's reset) leaves them as they are.

    Each listens to clicks on its own legend only (Vega-Lite names the legend's
    marks ``<field>_legend_…``): by default a legend-bound selection re-applies
    its last value on a click on any item, which with ``toggle`` would flip
    that entry back on a click on the other legend or on a point.
    """
    def param(name: str, fld: str, values: list[str]) -> dict[str, Any]:
        own = f"click[event.item && event.item.mark && indexof(event.item.mark.name, '{fld}_legend_') === 0]"
        return {"name": name, "value": [{fld: v} for v in values], "bind": {"legend": own},
                "select": {"type": "point", "fields": [fld], "toggle": "true", "clear": False}}

    return [param("statistics", "statistic", labels), param("channels", "channel", names)]


def _zoom_param(name: str, encodings: list[str]) -> dict[str, Any]:
    """Pan (drag) and zoom (wheel) bound to the scales of ``encodings``; a double-click resets them."""
    return {"name": name, "select": {"type": "interval", "encodings": encodings}, "bind": "scales"}


def _axis_layers(data: str, y: dict[str, Any], params: list[dict[str, Any]], enc: dict[str, Any],
                 with_model: bool) -> list[dict[str, Any]]:
    """The layers on one σ axis: the carrier of ``params``, the bands, the lines, the model, the points.

    ``enc`` holds the shared encodings ``color`` (statistic), ``shape`` and
    ``dash`` (channel).
    """
    source = {"data": {"name": data}}
    layers = [
        # Invisible points that hold the selections and give the legends their entries; never
        # filtered, so that a curve hidden from the legend can be shown again.
        {**source, "transform": [{"flatten": list(_ARRAYS)}, {"filter": "isValid(datum.tau) && isValid(datum.dev)"}],
         "params": params, "mark": {"type": "point", "opacity": 0},
         "encoding": {"y": y, "color": enc["color"], "shape": enc["shape"]}},
        {**source, "transform": _rows(data, "tau", "low", "high"), "mark": {"type": "area", "opacity": 0.15},
         "encoding": {"y": {**y, "field": "low"}, "y2": {"field": "high"}, "color": enc["color"],
                      "detail": {"field": "channel"}}},
        {**source, "transform": _rows(data, "tau", "dev"), "mark": {"type": "line", "strokeWidth": 1.3},
         "encoding": {"y": y, "color": enc["color"], "strokeDash": enc["dash"]}},
    ]
    if with_model:  # under the points, so that their tooltips stay reachable
        layers.append({"data": {"name": "model"}, "transform": _rows("model", "tau", "dev"),
                       "mark": {"type": "line", "color": "black", "strokeDash": [6, 2], "strokeWidth": 1.2},
                       "encoding": {"y": y, "detail": {"field": "channel"}}})
    texts = [{"calculate": expr, "as": name} for name, expr in _TEXTS.items()]
    layers.append({**source, "transform": [*_rows(data, "tau", "dev"), *texts],
                   "mark": {"type": "point", "filled": True, "size": 36, "opacity": 0.95},
                   "encoding": {"y": y, "color": enc["color"], "shape": enc["shape"],
                                "tooltip": [{"field": f, "type": "nominal", "title": t} for f, t in _TOOLTIP]}})
    return layers


def _encodings(stats: list[str], names: list[str], with_model: bool) -> dict[str, Any]:
    """Colour by statistic (the static figure's colours; the model black), shape and dash by channel."""
    labels = [statistic_label(s) for s in stats] + ([MODEL_LABEL] if with_model else [])
    colors = _stat_colors(stats) + (["#000000"] if with_model else [])
    # One channel legend: Vega-Lite merges the shape and dash legends of the same field.
    legend = {"title": "channel (click to hide)"}
    return {
        "labels": labels,
        "color": {"field": "statistic", "type": "nominal", "scale": {"domain": labels, "range": colors},
                  "legend": {"title": "statistic (click to hide)", "symbolType": "stroke", "symbolStrokeWidth": 3}},
        "shape": {"field": "channel", "type": "nominal", "legend": legend,
                  "scale": {"domain": names, "range": [_SHAPES[i % len(_SHAPES)] for i in range(len(names))]}},
        "dash": {"field": "channel", "type": "nominal", "legend": legend,
                 "scale": {"domain": names, "range": [_DASHES[i % len(_DASHES)] for i in range(len(names))]}},
    }


def _y(records: list[dict[str, Any]], extra: list[Optional[float]], name: str, right: bool) -> dict[str, Any]:
    """The y encoding of one axis: log scale over every value drawn on it, titled with the unit when
    the channels share one."""
    units = {r["unit"] for r in records}
    unit = units.pop() if len(units) == 1 else ""
    values = [v for r in records for k in ("dev", "low", "high") for v in r[k]] + extra
    axis = {"format": ".0e", "grid": not right, **({"orient": "right"} if right else {})}
    return {"field": "dev", "type": "quantitative", "title": f"{name}(τ) [{unit}]" if unit else f"{name}(τ)",
            "scale": _log_scale(values, 0.06), "axis": axis}


def _records(channels: Sequence[Any]) -> tuple[list[dict[str, Any]], list[dict[str, Any]], list[str]]:
    """The point records of the left (σ) and right (time error) axes, and the statistics in legend order.

    OADEV/ADEV come last in the data, so that they are drawn on top (as the
    static figure draws them strongest); the legend lists them first.
    """
    left: list[dict[str, Any]] = []
    right: list[dict[str, Any]] = []
    stats: list[str] = []
    for ch in channels:
        for stat, res in ch.results.items():
            (right if stat in _TIME_STATS else left).append(_point_record(ch, stat, res))
            if stat not in stats:
                stats.append(stat)
    stats.sort(key=lambda s: (s not in _PROMINENT, s in _TIME_STATS))
    prominent = {statistic_label(s) for s in _PROMINENT}
    left.sort(key=lambda r: r["statistic"] in prominent)
    return left, right, stats


def chart_spec(channels: Sequence[Any], *, title: str = "") -> dict[str, Any]:
    """The Vega-Lite spec of one interactive σ–τ chart.

    Parameters
    ----------
    channels : sequence of ChannelAnalysis
        The channels of the chart (name, unit, results, model), as the static
        σ–τ figure of their group shows them.
    title : str
        Chart title.

    Returns
    -------
    dict
        A JSON-ready Vega-Lite spec. Its ``datasets`` hold the data:
        ``left`` and ``right`` (time-error statistics, on a right-hand axis) one
        record per channel and statistic with the per-τ arrays ``tau``, ``dev``,
        ``low``, ``high`` (the StabilityResult's ``taus``, ``dev``, ``ci_low``,
        ``ci_high``; None where not positive), ``alpha``, ``noise`` (its name)
        and ``edf``; ``model`` one record per channel with the fitted model's
        curve (``tau``, ``dev``).
    """
    left, right, stats = _records(channels)
    models = [m for m in (_model_record(ch) for ch in channels) if m is not None]
    enc = _encodings(stats, [ch.name for ch in channels], bool(models))
    legends = _legend_params(enc["labels"], [ch.name for ch in channels])
    layers: list[dict[str, Any]] = []
    if left or not right:
        y = _y(left, [v for m in models for v in m["dev"]], "σ", right=False)
        layers.append({"layer": _axis_layers("left", y, [*legends, _zoom_param("zoom", ["x", "y"])], enc,
                                             bool(models))})
    if right:
        # Its own scale binding on y, so that the right axis pans and zooms with the left one (x is shared).
        params = [_zoom_param("zoom_right", ["y"])] if layers else [*legends, _zoom_param("zoom", ["x", "y"])]
        layers.append({"layer": _axis_layers("right", _y(right, [], "x", right=True), params, enc, False)})
    spec: dict[str, Any] = {
        "title": {"text": title, "anchor": "start", "fontSize": 13},
        "width": "container", "height": 440,
        "autosize": {"type": "fit-x", "contains": "padding"},
        "datasets": {"left": left, "right": right, "model": models},
        "encoding": {"x": {"field": "tau", "type": "quantitative", "title": "averaging time τ [s]",
                           "scale": _log_scale([v for r in left + right for v in r["tau"]], 0.04),
                           "axis": {"format": "~g", "grid": True}}},
        "layer": layers,
        # The legends take their symbols from the invisible carrier: opacity 1 there.
        "config": {"legend": {"labelLimit": 260, "orient": "right", "symbolOpacity": 1},
                   "axis": {"labelFontSize": 11, "gridOpacity": 0.5}},
    }
    if len(layers) == 2:
        spec["resolve"] = {"scale": {"y": "independent"}}
    return spec


# ---------------------------------------------------------------------- page


def _script_json(obj: Any) -> str:
    """JSON for a ``<script type="application/json">`` element: nothing in it can end the element.

    ``<``, ``>`` and ``&`` become ``\\u003c`` … (JSON.parse reads them back), so a
    channel named ``</script><script>alert(1)</script>`` stays data; U+2028/2029
    are escaped too, so the text is also valid JavaScript.
    """
    text = json.dumps(obj, ensure_ascii=False, allow_nan=False, separators=(",", ":"))
    for ch, esc in (("<", "\\u003c"), (">", "\\u003e"), ("&", "\\u0026"), ("\u2028", "\\u2028"),
                    ("\u2029", "\\u2029")):
        text = text.replace(ch, esc)
    return text


def chart_html(spec: Mapping[str, Any], index: int) -> str:
    """The HTML of one chart: its target ``<div>`` and its spec (drawn by :func:`library_script`'s code)."""
    return (f'<div class="ichart" id="ichart-{index}" role="figure" aria-label="interactive σ–τ chart"></div>'
            f'<script type="application/json" class="ichart-spec" data-target="ichart-{index}">'
            f"{_script_json(spec)}</script>")


#: Draws every chart of the page; ``window.sigmatauCharts`` holds the Vega views (for tests and users'
#: consoles) and ``ready``, a promise settled when all are drawn. Errors go to the console and the chart's box.
_BOOT = """(function () {
  var specs = document.querySelectorAll("script.ichart-spec");
  var views = [];
  var jobs = Array.prototype.map.call(specs, function (el, i) {
    var target = document.getElementById(el.getAttribute("data-target"));
    return vegaEmbed(target, JSON.parse(el.textContent), {mode: "vega-lite", renderer: "svg", actions: false})
      .then(function (result) { views[i] = result.view; return result.view; })
      .catch(function (err) { target.textContent = "chart not drawn: " + err; console.error(err); });
  });
  window.sigmatauCharts = {views: views, ready: Promise.all(jobs)};
})();"""


@functools.lru_cache(maxsize=1)
def _bundle() -> Optional[str]:
    """vega, vega-lite and vega-embed as one script (vl-convert's bundle; ~1.4 s once per process), or None."""
    try:
        import vl_convert
    except ImportError:
        return None
    js = vl_convert.javascript_bundle()
    # Inlined, a "</script" would end the element (none is in the bundle today); "<\\/" means the
    # same to JavaScript in a string, a template or a regular expression.
    return re.sub(r"</(?=script)", r"<\\/", js, flags=re.IGNORECASE)


def library_script() -> Optional[str]:
    """The ``<script>`` elements that draw the page's charts (library inlined), or None without the extra."""
    js = _bundle()
    if js is None:
        return None
    return f"<script>{js}</script>\n<script>{_BOOT}</script>"


def chart_channels(analysis: Any, group: str, max_channels: int) -> list[Any]:
    """The channels of ``group`` that its static σ–τ figure shows: the first ``max_channels`` with results."""
    return [c for c in analysis.groups().get(group, []) if c.results][:max_channels]


def report_charts(analysis: Any, figures: Sequence[Mapping[str, Any]], *, max_channels: int) -> InteractiveCharts:
    """One interactive chart per σ–τ figure of the report, the library once, and the report's note.

    Parameters
    ----------
    analysis : LogAnalysis
    figures : sequence of dict
        The figures written (``kind``, ``group``, ``stem``): charts follow the
        ``"sigma-tau"`` ones, so the report's caps on figures hold for them too.
    max_channels : int
        Channels per chart (the cap of the static figure,
        :data:`~sigmatau.report.outputs.MAX_CURVES_PER_FIGURE`).

    Returns
    -------
    InteractiveCharts
        Empty with :data:`MISSING_NOTE` when the extra is not installed; empty
        without a note when there is no σ–τ figure.
    """
    sigma = [f for f in figures if f.get("kind") == "sigma-tau"]
    if not sigma:
        return InteractiveCharts()
    script = library_script()
    if script is None:
        return InteractiveCharts(note=MISSING_NOTE)
    fragments = {}
    for i, fig in enumerate(sigma):
        chans = chart_channels(analysis, fig["group"], max_channels)
        if chans:
            title = f"{fig['group']}: {', '.join(c.name for c in chans)}"
            fragments[fig["stem"]] = chart_html(chart_spec(chans, title=title), i)
    return InteractiveCharts(fragments=fragments, script=script if fragments else "", note=USAGE_NOTE)
