"""Outputs of ``sigmatau psd``: the fit summary, the bin table as CSV, the figure and the folder.

Each channel's spectrum is a :class:`sigmatau.spectral.PsdResult`. Channel and file
names come from the user and are escaped wherever they are written (CSV formula
prefixes, HTML, the terminal); the folder is written by
:func:`~sigmatau.report.directory.write_directory` (atomic, manifest).
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
from .figbase import _FALLBACK_COLORS, _kind_of, _log_limits, _pretty, _style_log_axes, new_figure, save_figure
from .formats import csv_cell, printable
from .html import _e

__all__ = ["NOISE_NAMES", "IMU_NOISE_NAMES", "psd_summary", "psd_csv", "psd_figure", "spectra_dict", "write_spectra"]

#: Power-law noise names by α of S_y ∝ f^α (SP1065 Table 9; the design tip's slopes).
NOISE_NAMES = {2: "white PM", 1: "flicker PM", 0: "white FM", -1: "flicker FM", -2: "random-walk FM"}
#: The same types as IMU users name them on rate (gyro) and specific-force (accel) data (IEEE Std 952).
IMU_NOISE_NAMES = {2: "quantization", 1: "flicker of the angle", 0: "white noise (ARW/VRW)",
                   -1: "flicker (bias instability)", -2: "random walk (RRW)"}


def _names(unit: str) -> Mapping[int, str]:
    return IMU_NOISE_NAMES if _kind_of(unit) else NOISE_NAMES


def _unit2(unit: str) -> str:
    return f"({unit})²/Hz" if unit else "1/Hz"


def psd_summary(name: str, r: Any, unit: str = "") -> str:
    """The fitted ``h_α`` with intervals and the dominant noise type per decade, as text lines."""
    names = _names(unit)
    lines = [f"{printable(name)}: S_y from {r.f[0]:.4g} to {r.f[-1]:.4g} Hz, {r.f.size} log bins,"
             f" {r.confidence:.2%} intervals [{printable(_unit2(unit))}]"]
    for a in sorted(r.h, reverse=True):
        h, lo, hi = r.h[a], r.h_lo.get(a, math.nan), r.h_hi.get(a, math.nan)
        if h > 0:
            lines.append(f"  h{a:+d} = {h:.4e}  [{lo:.4e}, {hi:.4e}]  {names.get(a, '')}")
    for f_lo, f_hi, a in r.dominant:
        lines.append(f"  {f_lo:10.4g} … {f_hi:<10.4g} Hz: {names.get(int(a), f'f^{a}')} dominates")
    return "\n".join(lines)


_CSV_HEADER = ["channel", "f_hz", "s_y", "s_y_low", "s_y_high", "edf", "estimates_averaged", "model", "unit",
               "l_dbc_hz"]


def psd_csv(spectra: Mapping[str, Any], units: Mapping[str, str]) -> str:
    """One row per channel and log bin: the bin's mean S_y, its interval, EDF, the fitted model and,
    with a carrier, the phase noise L(f) in dBc/Hz (empty without one)."""
    buf = io.StringIO()
    buf.write(",".join(_CSV_HEADER) + "\n")
    for name, r in spectra.items():
        model = r.model(r.f)
        l_dbc = r.l_dbc if r.carrier is not None else np.full(r.f.size, np.nan)
        for i in range(r.f.size):
            cells = [name, float(r.f[i]), float(r.s_y[i]), float(r.lo[i]), float(r.hi[i]), float(r.edf[i]),
                     int(r.n_avg[i]), float(model[i]), _unit2(units.get(name, "")), float(l_dbc[i])]
            buf.write(",".join(csv_cell(c) for c in cells) + "\n")
    return buf.getvalue()


def psd_figure(spectra: Mapping[str, Any], units: Mapping[str, str], *, title: Optional[str] = None) -> Any:
    """Each channel's log-binned S_y with interval bars, the Welch estimate faint and the fitted power laws."""
    fig = new_figure((7.2, 4.6))
    ax = fig.add_subplot(1, 1, 1)
    lo, hi = math.inf, -math.inf
    for j, (name, r) in enumerate(spectra.items()):
        color = _FALLBACK_COLORS[j % len(_FALLBACK_COLORS)]
        if r.raw_f.size:
            # log-spaced subset: the raw estimate has N/2/segments points, which a figure cannot show anyway
            keep = np.unique(np.geomspace(1, r.raw_f.size, min(r.raw_f.size, 2000)).astype(np.int64) - 1)
            ax.loglog(r.raw_f[keep], r.raw_s_y[keep], color=color, lw=0.5, alpha=0.2)
        err = np.vstack([r.s_y - r.lo, r.hi - r.s_y])
        ax.errorbar(r.f, r.s_y, yerr=err, fmt="o", ms=3, color=color, lw=0.8, label=printable(name))
        model = r.model(r.f)
        ax.loglog(r.f, model, color=color, lw=1.2)
        for a, h in r.h.items():
            if h > 0:
                ax.loglog(r.f, h * r.f**a, color=color, lw=0.7, ls=":")
        v = np.concatenate([r.lo, r.hi, model])
        v = v[np.isfinite(v) & (v > 0)]
        if v.size:
            lo, hi = min(lo, float(v.min())), max(hi, float(v.max()))
    if math.isfinite(lo):
        ax.set_ylim(*_log_limits(lo, hi, 0.2, 0.2))
    unit = next(iter(units.values()), "") if len(set(units.values())) == 1 else ""
    ax.set_xlabel("f [Hz]")
    ax.set_ylabel(f"S_y [{'(' + _pretty(unit) + ')²/Hz' if unit else '1/Hz'}]")
    _style_log_axes(ax)
    ax.legend(fontsize=7.5, frameon=False, loc="best")
    ax.set_title(printable(title) if title else "Power spectral density: log bins with intervals, power-law fit"
                 " (dotted: each term)", fontsize=10)
    return fig


def _page(source: Mapping[str, Any], spectra: Mapping[str, Any], units: Mapping[str, str], png: Optional[bytes],
          version: str) -> str:
    import base64

    stamp = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    parts = ["<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
             f"<title>sigmatau psd — {_e(source.get('name', ''))}</title>",
             "<style>body{font-family:system-ui,sans-serif;margin:0 auto;max-width:1100px;padding:0 1.5em 3em}"
             "pre{background:#f6f6f6;border:1px solid #ddd;padding:.7em;overflow-x:auto}"
             "figure img{max-width:100%}.muted{color:#666}</style></head><body>",
             f"<h1>Power spectral density — {_e(source.get('name', ''))}</h1>",
             f'<p class="muted">sigmatau {_e(version)}, {stamp}; input SHA-256 {_e(source.get("sha256", ""))}</p>']
    if png is not None:
        uri = "data:image/png;base64," + base64.b64encode(png).decode("ascii")
        parts.append(f'<figure><img alt="power spectral density" src="{uri}"></figure>')
    for name, r in spectra.items():
        parts.append(f"<h2>{_e(name)}</h2><pre>{_e(psd_summary(name, r, units.get(name, '')))}</pre>")
    parts.append("</body></html>")
    return "\n".join(parts) + "\n"


def _finite_list(a: np.ndarray) -> list[Optional[float]]:
    return [float(v) if math.isfinite(float(v)) else None for v in np.asarray(a, dtype=float)]


def spectra_dict(spectra: Mapping[str, Any], units: Mapping[str, str], *, source: Mapping[str, Any],
                 settings: Mapping[str, Any], version: str) -> dict[str, Any]:
    """JSON-ready data: the input, the settings and each channel's bins and fit (NaN as null)."""
    out: dict[str, Any] = {"tool": f"sigmatau {version}", "input": dict(source), "settings": dict(settings),
                           "channels": {}}
    for name, r in spectra.items():
        out["channels"][name] = {
            "unit": _unit2(units.get(name, "")), "confidence": r.confidence,
            "f": _finite_list(r.f), "s_y": _finite_list(r.s_y), "s_y_low": _finite_list(r.lo),
            "s_y_high": _finite_list(r.hi), "edf": _finite_list(r.edf), "estimates_averaged": [int(v) for v in r.n_avg],
            "h": {str(a): float(v) for a, v in r.h.items()}, "h_low": {str(a): float(v) for a, v in r.h_lo.items()},
            "h_high": {str(a): float(v) for a, v in r.h_hi.items()},
            "dominant": [{"f_low": float(a), "f_high": float(b), "alpha": int(c)} for a, b, c in r.dominant],
            "l_dbc_hz": _finite_list(r.l_dbc) if r.carrier is not None else None}
    return out


def write_spectra(spectra: Mapping[str, Any], out_dir: Union[str, os.PathLike], *, units: Mapping[str, str],
                  source: Mapping[str, Any], settings: Mapping[str, Any], version: str,
                  figures: Sequence[str] = ("png", "svg"), report: bool = True, force: bool = False,
                  protect: Sequence[Union[str, os.PathLike]] = ()) -> list[Path]:
    """Write ``psd.csv``, ``psd.json``, ``psd.<fmt>`` and ``report.html`` into ``out_dir``, atomically."""
    data = spectra_dict(spectra, units, source=source, settings=settings, version=version)
    fmts = list(dict.fromkeys(str(f).lower() for f in figures))
    if report and fmts and "png" not in fmts:
        fmts.insert(0, "png")

    def fill(folder: Path) -> None:
        png = None
        if fmts:
            save_figure(psd_figure(spectra, units), folder / "psd", fmts)
            png = (folder / "psd.png").read_bytes() if "png" in fmts else None
        write_text(folder / "psd.csv", psd_csv(spectra, units))
        write_text(folder / "psd.json", json.dumps(data, indent=1, allow_nan=False, ensure_ascii=False) + "\n")
        if report:
            write_text(folder / "report.html", _page(source, spectra, units, png, version))

    return write_directory(out_dir, fill, version, force=force, protect=protect)
