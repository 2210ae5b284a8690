"""Outputs of a cornered hat (``sigmatau compare``): table, CSV, JSON, figure and report page.

The result is a :class:`sigmatau.compare.HatResult`. Everything written goes
through :func:`~sigmatau.report.directory.write_directory` (atomic, manifest,
only sigmatau's own files replaced). Device names come from the user (file and
column names) and are escaped wherever they are written: CSV cells that would
start a formula, HTML, the terminal.
"""

from __future__ import annotations

import datetime as _dt
import io
import json
import math
import os
from pathlib import Path
from typing import Any, Mapping, Optional, Sequence, Union

import numpy as np

from .directory import write_directory, write_text
from .figbase import _DISPLAY, _FALLBACK_COLORS, _log_limits, _pretty, _style_log_axes, new_figure, save_figure
from .formats import csv_cell, printable
from .html import _e

__all__ = ["hat_table", "hat_csv", "hat_dict", "hat_figure", "write_comparison"]


def _num(v: float, fmt: str = ".4e") -> str:
    return format(float(v), fmt) if math.isfinite(float(v)) else "-"


def hat_table(result: Any, unit: str = "") -> str:
    """Each device's rows as a Stable32-like text table (one block per device).

    Columns: AF, Tau, # (terms), Alpha, EDF, Min Sigma, Sigma, Max Sigma (the non-negative
    estimate and its interval) and Classical (the signed estimate, negative when the
    pair variances say the device is quieter than their scatter can resolve).
    """
    stat = _DISPLAY.get(result.statistic, result.statistic.upper())
    lines = []
    for j, name in enumerate(result.names):
        lines.append(f"{printable(name)} {stat}{' [' + printable(unit) + ']' if unit else ''}")
        lines.append(f"{'AF':>7} {'Tau':>11} {'#':>7} {'Alpha':>5} {'EDF':>8} {'Min Sigma':>11} {'Sigma':>11}"
                     f" {'Max Sigma':>11} {'Classical':>11}")
        for i in range(result.tau.size):
            lines.append(f"{int(result.m[i]):>7} {result.tau[i]:>11.4e} {int(result.n[i]):>7}"
                         f" {int(result.alpha[i]):>5} {_num(result.edf[i], '.1f'):>8}"
                         f" {_num(result.low[i, j]):>11} {_num(result.dev[i, j]):>11} {_num(result.high[i, j]):>11}"
                         f" {_num(result.classical_dev[i, j]):>11}")
        lines.append("")
    return "\n".join(lines)


_CSV_HEADER = ["device", "statistic", "tau_s", "m", "n", "alpha", "edf", "dev_low", "dev", "dev_high",
               "classical_var", "classical_dev", "confidence", "unit"]


def hat_csv(result: Any, unit: str = "") -> str:
    """One row per device and τ (columns :data:`_CSV_HEADER`), device names escaped for spreadsheets."""
    buf = io.StringIO()
    buf.write(",".join(_CSV_HEADER) + "\n")
    for row in result.to_rows():
        cells = [row["device"], result.statistic, row["tau"], row["m"], row["n"], row["alpha"], row["edf"],
                 row["low"], row["dev"], row["high"], row["classical_var"], row["classical_dev"],
                 float(result.confidence), unit]
        buf.write(",".join(csv_cell(c) for c in cells) + "\n")
    return buf.getvalue()


def _finite(v: float) -> Optional[float]:
    return float(v) if math.isfinite(float(v)) else None


def hat_dict(result: Any, *, unit: str = "", inputs: Sequence[Mapping[str, Any]] = (),
             settings: Optional[Mapping[str, Any]] = None, version: str = "") -> dict[str, Any]:
    """The result as JSON-ready data (NaN as null): inputs, settings and every device's rows."""
    devices = {}
    for j, name in enumerate(result.names):
        devices[name] = [{"tau": float(result.tau[i]), "m": int(result.m[i]), "n": int(result.n[i]),
                          "alpha": int(result.alpha[i]), "edf": _finite(result.edf[i]),
                          "dev_low": _finite(result.low[i, j]), "dev": _finite(result.dev[i, j]),
                          "dev_high": _finite(result.high[i, j]),
                          "classical_var": _finite(result.classical_var[i, j]),
                          "classical_dev": _finite(result.classical_dev[i, j])}
                         for i in range(result.tau.size)]
    return {"tool": f"sigmatau {version}".strip(), "statistic": result.statistic, "unit": unit,
            "confidence": result.confidence, "inputs": list(inputs), "settings": dict(settings or {}),
            "devices": devices}


def hat_figure(result: Any, *, unit: str = "", title: Optional[str] = None,
               pairs: Optional[Mapping[str, tuple[np.ndarray, np.ndarray]]] = None) -> Any:
    """Each device's deviation against τ with its interval band; the classical estimate as crosses.

    ``pairs`` maps a pair's label (``"A−B"``) to ``(tau, dev)`` of the difference series,
    drawn thin and grey: the device curves lie below them. Negative classical estimates
    cannot be drawn on a log axis and are counted in the legend instead.
    """
    fig = new_figure((7.2, 4.6))
    ax = fig.add_subplot(1, 1, 1)
    lo, hi = math.inf, -math.inf

    def take(values: np.ndarray) -> None:
        nonlocal lo, hi
        v = np.asarray(values, dtype=float)
        v = v[np.isfinite(v) & (v > 0)]
        if v.size:
            lo, hi = min(lo, float(v.min())), max(hi, float(v.max()))

    for k, (label, (t, d)) in enumerate((pairs or {}).items()):
        ax.loglog(t, d, color="#9a9a9a", lw=0.9, ls="--", label="pair differences" if k == 0 else None)
        take(d)
    for j, name in enumerate(result.names):
        color = _FALLBACK_COLORS[j % len(_FALLBACK_COLORS)]
        dev, low, high = result.dev[:, j], result.low[:, j], result.high[:, j]
        ok = np.isfinite(low) & np.isfinite(high) & (high > 0)
        ax.fill_between(result.tau[ok], np.maximum(low[ok], np.nextafter(0, 1)), high[ok], color=color, alpha=0.18,
                        lw=0)
        ax.loglog(result.tau, dev, color=color, marker="o", ms=3.5, lw=1.4, label=printable(name))
        classical = result.classical_dev[:, j]
        neg = int(np.sum(np.isfinite(classical) & (classical < 0)))
        pos = np.isfinite(classical) & (classical > 0)
        ax.loglog(result.tau[pos], classical[pos], ls="none", marker="x", ms=4, color=color,
                  label=f"{printable(name)} classical" + (f" ({neg} negative, not drawn)" if neg else ""))
        take(dev), take(low), take(high), take(classical)
    if math.isfinite(lo):
        ax.set_ylim(*_log_limits(lo, hi, 0.15, 0.15))
    stat = _DISPLAY.get(result.statistic, result.statistic.upper())
    ax.set_xlabel("τ [s]")
    ax.set_ylabel(f"{stat}{' [' + _pretty(unit) + ']' if unit else ''}")
    _style_log_axes(ax)
    ax.legend(fontsize=7.5, frameon=False, loc="best")
    ax.set_title(printable(title) if title else f"Cornered hat: {stat} of each device,"
                 f" {result.confidence:.1%} intervals", fontsize=10)
    return fig


_CSS = """body{font-family:system-ui,sans-serif;margin:0 auto;max-width:1100px;padding:0 1.5em 3em;color:#1d1d1f}
table{border-collapse:collapse;font-size:.85em;margin:.5em 0}th,td{border:1px solid #d0d0d0;padding:.2em .5em;
text-align:right}th{background:#f2f2f2}td.l{text-align:left}figure img{max-width:100%}.muted{color:#666}
pre{background:#f6f6f6;border:1px solid #ddd;padding:.7em;overflow-x:auto;font-size:.85em}"""


def _page(data: Mapping[str, Any], png: Optional[bytes], note: str) -> str:
    import base64

    stamp = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    stat = _DISPLAY.get(data["statistic"], str(data["statistic"]).upper())
    parts = ["<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
             f"<title>sigmatau compare — {_e(stat)}</title><style>{_CSS}</style></head><body>",
             f"<h1>Cornered hat — {_e(stat)}</h1>",
             f'<p class="muted">{_e(data["tool"])}, {stamp}. {_e(note)}</p>', "<h2>Inputs</h2><table>",
             "<tr><th>input</th><th>samples</th><th>rate [Hz]</th><th>data</th><th>SHA-256</th></tr>"]
    for src in data["inputs"]:
        parts.append(f'<tr><td class="l">{_e(src.get("name", ""))}</td><td>{_e(src.get("samples", ""))}</td>'
                     f'<td>{_e(src.get("rate", ""))}</td><td>{_e(src.get("data_type", ""))}</td>'
                     f'<td class="l">{_e(src.get("sha256", ""))}</td></tr>')
    parts.append("</table>")
    if png is not None:
        uri = "data:image/png;base64," + base64.b64encode(png).decode("ascii")
        parts.append(f'<h2>Figure</h2><figure><img alt="cornered hat" src="{uri}"></figure>')
    unit = f" [{_e(data['unit'])}]" if data["unit"] else ""
    for name, rows in data["devices"].items():
        parts.append(f"<h2>{_e(name)}</h2><table><tr><th>τ [s]</th><th>m</th><th>n</th><th>α</th><th>EDF</th>"
                     f"<th>min σ{unit}</th><th>σ{unit}</th><th>max σ{unit}</th><th>classical σ{unit}</th></tr>")
        for r in rows:
            cells = [_num(r["tau"]), r["m"], r["n"], r["alpha"], _num(r["edf"] if r["edf"] is not None else math.nan,
                                                                       ".1f")]
            cells += [_num(r[k] if r[k] is not None else math.nan) for k in ("dev_low", "dev", "dev_high",
                                                                            "classical_dev")]
            parts.append("<tr>" + "".join(f"<td>{_e(c)}</td>" for c in cells) + "</tr>")
        parts.append("</table>")
    parts.append(f"<h2>Settings</h2><pre>{_e(json.dumps(data['settings'], indent=1, ensure_ascii=False))}</pre>")
    parts.append("</body></html>")
    return "\n".join(parts) + "\n"


def write_comparison(result: Any, out_dir: Union[str, os.PathLike], *, unit: str = "",
                     inputs: Sequence[Mapping[str, Any]] = (), settings: Optional[Mapping[str, Any]] = None,
                     pairs: Optional[Mapping[str, tuple[np.ndarray, np.ndarray]]] = None, version: str = "",
                     figures: Sequence[str] = ("png", "svg"), report: bool = True, force: bool = False,
                     protect: Sequence[Union[str, os.PathLike]] = ()) -> list[Path]:
    """Write ``compare.csv``, ``compare.json``, ``compare.<fmt>`` and ``report.html`` into ``out_dir``.

    Atomic, with a manifest; an existing ``out_dir`` only with ``force`` and only if
    sigmatau wrote it (:func:`~sigmatau.report.directory.write_directory`).
    """
    data = hat_dict(result, unit=unit, inputs=inputs, settings=settings, version=version)
    fmts = list(dict.fromkeys(str(f).lower() for f in figures))
    if report and fmts and "png" not in fmts:
        fmts.insert(0, "png")

    def fill(folder: Path) -> None:
        png = None
        if fmts:
            save_figure(hat_figure(result, unit=unit, pairs=pairs), folder / "compare", fmts)
            png = (folder / "compare.png").read_bytes() if "png" in fmts else None
        write_text(folder / "compare.csv", hat_csv(result, unit))
        write_text(folder / "compare.json", json.dumps(data, indent=1, allow_nan=False, ensure_ascii=False) + "\n")
        if report:
            note = ("Estimates: maximum likelihood over non-negative variances; intervals: Feldman–Cousins belts"
                    " on the exact distribution of each classical estimate (a weighted sum of χ² variables, the"
                    " KLTS approach of Lantz et al. 2019), never below zero — an interval starting at 0 is an"
                    " upper limit. Classical: the signed least-squares cornered hat.")
            write_text(folder / "report.html", _page(data, png, note))

    return write_directory(out_dir, fill, version, force=force, protect=protect)
