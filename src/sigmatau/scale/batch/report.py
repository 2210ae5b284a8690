"""The fleet's figures and ``fleet.html``, and the writing of every fleet file."""

from __future__ import annotations

import base64
import html
import json
import math
from dataclasses import replace
from pathlib import Path
from typing import Any, Mapping, Optional, Sequence

from ..._version import __version__
from ...errors import SigmaTauError
from ...pipeline.analysis import IMU_GROUPS
from .common import LOGS_DIR, _write_text
from .summary import (_LIMIT_RULE, _LOG_COLUMNS, _OUTLIER_RULE, _ROW_COLUMNS, FleetSummary, _annotate, _csv_text,
                      _log_rows, _outliers_and_distribution, _rows)

_HIST_TERMS = ("N", "B", "K")


def _fleet_figures(rows: Sequence[dict], limits: Mapping[str, Any]) -> dict[str, bytes]:
    """Histograms and a strip plot with intervals of N, B, K per group (PNG bytes).

    Parameters
    ----------
    rows : sequence of dict
        The rows of ``fleet.csv`` (:func:`_rows`), outliers marked.
    limits : mapping
        The limits (:func:`load_limits`), drawn as dashed lines.

    Returns
    -------
    dict
        ``{"fleet_hist": png, "fleet_strip": png}``; empty when no row is of a gyro or accel group.

    Raises
    ------
    MissingDependencyError
        matplotlib is not installed (the message names the extra).
    """
    from ...report import plots

    plots.matplotlib_modules()  # MissingDependencyError naming the extra when matplotlib is missing
    groups = [g for g in IMU_GROUPS if any(r["group"] == g for r in rows)]
    if not groups:
        return {}
    out = {}
    logs = sorted({r["path"] for r in rows})
    for kind in ("hist", "strip"):
        fig = plots.new_figure((4.0 * len(_HIST_TERMS), 3.0 * len(groups) + 0.4))
        axes = fig.subplots(len(groups), len(_HIST_TERMS), squeeze=False)
        for i, g in enumerate(groups):
            for j, t in enumerate(_HIST_TERMS):
                _fleet_panel(axes[i][j], kind, g, t, rows, limits, logs)
        fig.suptitle("Fleet distribution of the noise terms" if kind == "hist" else
                     "Noise terms per log with intervals (colour: x, y, z axis)", fontsize=10)
        _thin_log_ticks(fig)
        out[f"fleet_{kind}"] = plots.figure_to_bytes(fig, "png")
    return out


def _fleet_panel(ax: Any, kind: str, g: str, t: str, rows: Sequence[dict], limits: Mapping[str, Any],
                 logs: Sequence[str]) -> None:
    """One panel of a fleet figure: term ``t`` of group ``g``, a histogram or a strip plot (``kind``).

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The panel.
    kind : {"hist", "strip"}
        Histogram of the resolved values, or every log's value with its interval.
    g, t : str
        Group (gyro, accel) and term (N, B, K).
    rows : sequence of dict
        The rows of ``fleet.csv``.
    limits : mapping
        The limits; the one of ``g``, ``t`` is drawn dashed.
    logs : sequence of str
        The paths of the logs, sorted: the x positions of the strip plot.
    """
    from ...imu.units import pretty

    sel = [r for r in rows if r["group"] == g and r["term"] == t]
    res = [r for r in sel if r["resolved"] and r["value"]]
    lim = limits.get(g, {}).get(t)
    unit = pretty(sel[0]["unit"]) if sel else ""
    ax.set_title(f"{g} {t} [{unit}]", fontsize=9)
    ax.tick_params(labelsize=8)
    ax.grid(True, color="0.88", linewidth=0.5)
    if kind == "hist":
        if not _hist_panel(ax, res, lim):
            lim = None  # an empty panel gets no limit line either
        ax.set_xlabel(f"{t} [{unit}]", fontsize=8)
        ax.set_ylabel("channels", fontsize=8)
    else:
        _strip_panel(ax, sel, logs)
    if lim:
        (ax.axvline if kind == "hist" else ax.axhline)(lim["max"], color="#D55E00", linestyle="--",
                                                       linewidth=1.0, label="limit")
    if kind == "hist" and ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=7, frameon=False)


def _hist_panel(ax: Any, res: Sequence[dict], lim: Optional[Mapping[str, Any]]) -> bool:
    """Histogram of the resolved values ``res`` on log bins, their median and outliers (▼).

    The bins also cover the limit ``lim``, so that its line is inside the panel.
    Without a resolved value the panel says so instead.

    Returns
    -------
    bool
        Whether anything was drawn (False: the panel is empty).
    """
    import numpy as np

    if not res:
        ax.text(0.5, 0.5, "not resolved in any log", ha="center", va="center",
                transform=ax.transAxes, fontsize=8, color="0.4")
        ax.set_xticks([])
        ax.set_yticks([])
        return False
    ax.set_xscale("log")
    v = np.array([r["value"] for r in res])
    lo, hi = v.min(), v.max()
    if lim:
        lo, hi = min(lo, lim["max"]), max(hi, lim["max"])
    bins = np.logspace(np.log10(lo) - 0.05, np.log10(hi) + 0.05, 25)
    ax.hist(v, bins=bins, color="#56B4E9", edgecolor="#0072B2", linewidth=0.6)
    ax.axvline(float(np.median(v)), color="black", linewidth=1.0, label="median")
    bad = [r["value"] for r in res if r["outlier"]]
    if bad:
        ax.plot(bad, [0] * len(bad), "v", color="#D55E00", markersize=7, clip_on=False,
                label="outlier")
    return True


_AXIS_COLORS = {"x": "#0072B2", "y": "#E69F00", "z": "#009E73"}


def _strip_panel(ax: Any, sel: Sequence[dict], logs: Sequence[str]) -> None:
    """Every log's value with its interval, per axis in its colour; outliers circled, bounds as ▼.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The panel.
    sel : sequence of dict
        The rows of one group and term.
    logs : sequence of str
        The paths of the logs, sorted: log ``i`` is drawn at x = i (the axes shifted by ±0.2).
    """
    import numpy as np

    pos = {p: i for i, p in enumerate(logs)}
    ax.set_yscale("log")
    for letter, color in _AXIS_COLORS.items():  # one call per axis: thousands of logs stay fast
        mine = [r for r in sel if r["channel"].rsplit("_", 1)[-1] == letter or
                (letter == "x" and r["channel"].rsplit("_", 1)[-1] not in _AXIS_COLORS)]
        shift = {"x": -0.2, "y": 0.0, "z": 0.2}[letter]
        good = [r for r in mine if r["resolved"] and r["value"]]
        if good:
            x = np.array([pos[r["path"]] for r in good]) + shift
            v = np.array([r["value"] for r in good])
            lo = np.array([max(r["low"], r["value"] / 100) for r in good])
            hi = np.array([r["high"] if math.isfinite(r["high"]) else r["value"] for r in good])
            ax.errorbar(x, v, yerr=np.clip([v - lo, hi - v], 0, None), fmt="o", color=color, markersize=3,
                        elinewidth=0.8, linestyle="none")
            bad = [(xi, r["value"]) for xi, r in zip(x, good) if r["outlier"]]
            if bad:
                ax.plot(*zip(*bad), "o", mfc="none", mec="#D55E00", markersize=9, mew=1.2,
                        linestyle="none")
        bounds = [r for r in mine if not r["resolved"] and r["high"] and math.isfinite(r["high"])]
        if bounds:
            ax.plot(np.array([pos[r["path"]] for r in bounds]) + shift, [r["high"] for r in bounds],
                    "v", color=color, markersize=4, alpha=0.6, linestyle="none")
    ax.set_xlabel("log (sorted by path); ▼ upper bound, not resolved", fontsize=8)
    ax.set_xlim(-0.8, len(logs) - 0.2)


def _thin_log_ticks(fig: Any) -> None:
    """At most ~6 major and no minor ticks on log axes: minor log ticks over many decades make the layout slow."""
    from matplotlib.ticker import LogLocator, NullLocator

    for ax in fig.axes:
        for axis in (ax.xaxis, ax.yaxis):
            if axis.get_scale() == "log":
                axis.set_major_locator(LogLocator(numticks=6))
                axis.set_minor_locator(NullLocator())


_CSS = """
body{font-family:system-ui,-apple-system,"Segoe UI",Roboto,Helvetica,Arial,sans-serif;margin:0 auto;
max-width:1200px;padding:0 1.5em 3em;color:#1d1d1f;line-height:1.45}
h1{font-size:1.6em;margin:1.2em 0 .2em}h2{font-size:1.25em;margin-top:2em;border-bottom:1px solid #ccc}
table{border-collapse:collapse;margin:.5em 0;font-size:.86em}
th,td{border:1px solid #d0d0d0;padding:.2em .5em;text-align:right;vertical-align:top}
th{background:#f2f2f2}td.l,th.l{text-align:left}
figure{margin:1em 0}figure img{max-width:100%;height:auto;border:1px solid #eee}
.fail{color:#a00;font-weight:600}.pass{color:#185c18}.muted{color:#666}.flag{color:#8a4b00}
"""


def _h(text: Any) -> str:
    """``text`` escaped for HTML (quotes included)."""
    return html.escape(str(text), quote=True)


def _n(v: Any, fmt: str = ".4g") -> str:
    """A number formatted by ``fmt``; ``–`` for None and non-finite values."""
    return "–" if v is None or (isinstance(v, float) and not math.isfinite(v)) else format(float(v), fmt)


def _fleet_html(fleet: FleetSummary, figs: Mapping[str, bytes], figure_note: str) -> str:
    """The self-contained ``fleet.html``: distribution, figures (embedded PNG), limits, outliers, errors and logs."""
    from ...imu.units import pretty

    recs, errs = fleet.records, fleet.errors
    n = len(recs) + len(errs)
    fails = [r for r in recs if r.get("verdict") == "fail"]
    parts = ["<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
             '<meta name="viewport" content="width=device-width, initial-scale=1">',
             f"<title>sigmatau fleet report — {n} logs</title><style>{_CSS}</style></head><body>",
             f"<h1>sigmatau fleet report — {n} logs</h1>",
             f'<p class="muted">sigmatau {_h(__version__)}; {len(recs)} analysed ({fleet.computed} in this run,'
             f" {fleet.reused} done before), {len(errs)} failed; {fleet.seconds:.1f} s."
             ' <a href="#dist">distribution</a> · <a href="#figures">figures</a> · <a href="#limits">limits</a> ·'
             ' <a href="#outliers">outliers</a> · <a href="#errors">errors</a> · <a href="#logs">logs</a></p>']
    parts.append('<h2 id="dist">Distribution across the fleet</h2>'
                 "<p>SI units; values of resolved terms only (bounds counted apart); spread ×/÷ is 10^(1.4826·MAD)"
                 " of log10 values.</p><table><tr><th class=l>group</th><th>term</th><th class=l>unit</th>"
                 "<th>logs</th><th>resolved</th><th>bounds</th><th>median</th><th>spread ×/÷</th><th>5 %</th>"
                 "<th>95 %</th><th>min</th><th>max</th><th>limit</th><th>fail</th><th>outliers</th></tr>")
    for d in fleet.distribution:
        parts.append(f"<tr><td class=l>{_h(d['group'])}</td><td>{_h(d['term'])}</td><td class=l>"
                     f"{_h(pretty(d['unit']))}</td><td>{d['logs']}</td><td>{d['resolved']}</td><td>{d['bounds']}</td>"
                     f"<td>{_n(d['median'])}</td><td>{_n(d['spread_factor'], '.3g')}</td><td>{_n(d['p05'])}</td>"
                     f"<td>{_n(d['p95'])}</td><td>{_n(d['min'])}</td><td>{_n(d['max'])}</td><td>{_n(d['limit'])}</td>"
                     f"<td{' class=fail' if d['fail'] else ''}>{d['fail']}</td><td>{d['outliers']}</td></tr>")
    parts.append("</table>")
    parts.append('<h2 id="figures">Figures</h2>')
    if figure_note:
        parts.append(f'<p class="flag">Figures not made: {_h(figure_note)}</p>')
    for stem, data in figs.items():
        cap = ("Histograms of the resolved N, B, K of every channel; median (black), limit (dashed), outliers (▼)"
               if stem.endswith("hist") else "N, B, K of every log with their intervals; outliers circled;"
               " ▼ marks the upper bound of a term the record does not resolve")
        parts.append(f'<figure><img src="data:image/png;base64,{base64.b64encode(data).decode("ascii")}"'
                     f' alt="{_h(cap)}"><figcaption>{_h(cap)}</figcaption></figure>')
    parts.append('<h2 id="limits">Limits</h2>')
    if fleet.limits:
        parts.append(f"<p>{_h(_LIMIT_RULE)}.</p><ul>" + "".join(
            f"<li>{_h(g)} {_h(t)} ≤ {_n(v['max'])} {_h(pretty(v['unit']))} ({_h(v['given'])}; {_h(v['source'])})</li>"
            for g, terms in fleet.limits.items() for t, v in terms.items()) + "</ul>")
        parts.append(f"<p><span class=pass>{sum(r.get('verdict') == 'pass' for r in recs)} pass</span>,"
                     f" <span class=fail>{len(fails)} fail</span>,"
                     f" {sum(r.get('verdict') == 'untested' for r in recs)} untested.</p>")
        if fails:
            parts.append("<table><tr><th class=l>log</th><th class=l>failures</th></tr>" + "".join(
                f"<tr><td class=l>{_link(r)}</td><td class=l>{_h('; '.join(r['limit_failures']))}</td></tr>"
                for r in fails) + "</table>")
    else:
        parts.append('<p class="muted">No limits given (--limits).</p>')
    parts.append(f'<h2 id="outliers">Outliers against the fleet</h2><p>{_h(_OUTLIER_RULE)}.</p>')
    outl = [r for r in recs if r.get("outliers")]
    parts.append("<table><tr><th class=l>log</th><th class=l>terms</th></tr>" + "".join(
        f"<tr><td class=l>{_link(r)}</td><td class=l>{_h(', '.join(r['outliers']))}</td></tr>" for r in outl)
        + "</table>" if outl else '<p class="muted">None.</p>')
    parts.append('<h2 id="errors">Logs that could not be analysed</h2>')
    parts.append("<table><tr><th class=l>path</th><th class=l>error</th><th class=l>kind</th><th class=l>reason</th>"
                 "</tr>" + "".join(f"<tr><td class=l>{_h(e['path'])}</td><td class=l>{_h(e['error']['type'])}</td>"
                                   f"<td class=l>{_h(e['error']['kind'])}</td><td class=l>{_h(e['error']['message'])}"
                                   "</td></tr>" for e in errs) + "</table>" if errs else '<p class="muted">None.</p>')
    parts.append('<h2 id="logs">Logs</h2><table><tr><th class=l>log</th><th>duration</th><th>rate [Hz]</th>'
                 "<th class=l>verdict</th><th>gyro N max</th><th>accel N max</th><th>outliers</th><th>warnings</th>"
                 "<th class=l>sha256</th></tr>")
    for r in recs:
        nmax = {}
        for g in IMU_GROUPS:
            vs = [c["terms"]["N"]["value"] for c in r["channels"] if c["group"] == g and c.get("terms")
                  and c["terms"]["N"]["resolved"]]
            nmax[g] = max(vs) if vs else None
        v = r.get("verdict", "")
        parts.append(f"<tr><td class=l>{_link(r)}</td><td>{_n(r['duration_s'] / 3600, '.3g')} h</td>"
                     f"<td>{_n(r['rate'], '.6g')}</td><td class='l {v}'>{_h(v or '–')}</td>"
                     f"<td>{_n(nmax['gyro'])}</td><td>{_n(nmax['accel'])}</td><td>{len(r.get('outliers', []))}</td>"
                     f"<td>{len(r.get('warnings', []))}</td><td class=l><code>{_h(r['sha256'][:12])}</code></td></tr>")
    parts.append("</table></body></html>")
    return "\n".join(parts) + "\n"


def _link(r: Mapping[str, Any]) -> str:
    """A log's path as HTML, linked to its ``report.html`` when it has one."""
    label = _h(r["path"])
    if r.get("name") and r.get("has_report", True):
        return f'<a href="{_h(LOGS_DIR)}/{_h(r["name"])}/report.html">{label}</a>'
    return label


def _build_fleet(out: Path, records: list[dict], errors: list[dict], *, limits: Mapping[str, Any],
                 outlier_z: float, computed: int, reused: int, seconds: float, figures: bool) -> FleetSummary:
    """Summarise the fleet and write its files; the FleetSummary.

    ``fleet.csv``, ``fleet_logs.csv``, ``fleet.json``, ``fleet.html`` and, with
    ``figures``, ``fleet_hist.png`` and ``fleet_strip.png``.
    """
    rows = _rows(records, limits)
    dist = _outliers_and_distribution(rows, limits, outlier_z)
    _annotate(records, rows, limits)
    for r in records:
        r["has_report"] = (out / LOGS_DIR / r["name"] / "report.html").is_file()
    figs: dict[str, bytes] = {}
    note = ""
    if figures:
        try:
            figs = _fleet_figures(rows, limits)
        except SigmaTauError as exc:  # matplotlib missing: the tables are still useful
            note = str(exc)
    files = []
    for stem, data in figs.items():
        _write_text(out / f"{stem}.png", data)
        files.append(out / f"{stem}.png")
    fleet = FleetSummary(out=out, records=tuple(records), errors=tuple(errors), rows=tuple(rows),
                         distribution=tuple(dist), limits=dict(limits), computed=computed, reused=reused,
                         seconds=seconds)
    _write_text(out / "fleet.csv", _csv_text(_ROW_COLUMNS, rows))
    _write_text(out / "fleet_logs.csv", _csv_text(_LOG_COLUMNS, _log_rows(records, errors)))
    _write_text(out / "fleet.json", json.dumps(fleet.to_dict(), indent=1, allow_nan=False, ensure_ascii=False) + "\n")
    _write_text(out / "fleet.html", _fleet_html(fleet, figs, note))
    files += [out / n for n in ("fleet.csv", "fleet_logs.csv", "fleet.json", "fleet.html")]
    return replace(fleet, files=tuple(files))
