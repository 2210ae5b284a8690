"""Writing a :class:`~sigmatau.analysis.LogAnalysis` to a directory.

:func:`write_outputs` produces, in one directory:

- ``results.json`` — tool version, input file and SHA-256, every setting, the
  timing report, and per channel every statistic (τ, m, n, α, EDF, interval),
  the noise model with intervals in SI and customary units, flags and checks;
- ``statistics.csv`` (one row per channel, statistic and τ) and ``model.csv``
  (one row per channel and term, SI and customary units);
- ``imu.yaml`` — the Kalibr IMU file (:func:`kalibr_yaml`), when the log has
  gyroscope and accelerometer models, and the other estimators' parameter files
  asked for with ``exports`` (:mod:`sigmatau.report.estimators`: VINS, OpenVINS,
  MATLAB, GTSAM);
- figures (:mod:`sigmatau.plots`, needs the ``plot`` extra): ``sigma_tau_<group>``
  per sensor group and ``signal_<channel>`` (time series, Welch PSD, lag plot)
  per channel, as PNG and SVG (PDF on request);
- ``report.html`` — one self-contained page (:mod:`sigmatau.report.html`).

and ``sigmatau-manifest.json``, the list of those files with their sizes and
SHA-256.

Everything is written into a temporary sibling directory that is renamed into
place at the end, so an interrupted or failed run leaves nothing half-written.
An existing directory is used only with ``force=True`` and only if it is empty
or holds a sigmatau manifest; then only the unchanged files the manifest lists
are replaced (and put back if the replacement fails): a file the user added
there survives. A temporary directory left by a killed run is removed by a
later run once its process is gone.
"""

from __future__ import annotations

import json
import os
import re
import warnings
from collections import deque
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any, Optional, Sequence, Union

from ..errors import ParameterError, SigmaTauError, SigmaTauWarning, caller_stacklevel
from .estimators import EXPORT_FILES, EXPORTS, export_text, parse_exports
from .directory import (
    MANIFEST, OutputExistsError, PARTIAL_MARKER, _write_text, check_output_dir, read_manifest, remove_stale_partials,
    umask, write_directory,
)
from .formats import KALIBR_KEYS, csv_cell, kalibr_yaml, model_csv, printable, statistics_csv

__all__ = ["write_outputs", "check_output_dir", "read_manifest", "remove_stale_partials", "kalibr_yaml",
           "statistics_csv", "model_csv", "csv_cell", "printable", "OutputExistsError", "FIGURE_FORMATS",
           "KALIBR_KEYS", "MANIFEST", "PARTIAL_MARKER", "MAX_SIGNAL_FIGURES", "MAX_SIGMA_TAU_FIGURES",
           "MAX_CURVES_PER_FIGURE", "umask", "write_directory", "EXPORTS", "EXPORT_FILES", "export_text",
           "parse_exports"]

#: Figure formats :func:`write_outputs` can write.
FIGURE_FORMATS = ("png", "svg", "pdf")


def _export_text(analysis: Any, target: str) -> Optional[str]:
    """The text of one estimator file; None without an IMU model or, with one warning, without PyYAML."""
    from ..io import MissingDependencyError

    if analysis.kalibr is None:
        return None
    try:
        return export_text(analysis, target)
    except MissingDependencyError as exc:  # everything else is still useful
        warnings.warn(f"{EXPORT_FILES[target]} not written: {exc}", SigmaTauWarning, stacklevel=caller_stacklevel())
        return None


def _datasheet_for(analysis: Any, group: str, unit: str) -> Optional[dict[str, float]]:
    """Datasheet terms of ``group`` in the unit of the group's channels (for the figures)."""
    from ..imu.units import convert, term_unit

    ref = analysis.settings.get("datasheet", {}).get(group)
    if not ref or not unit:
        return None
    out = {}
    for term, (value, u) in ref.items():
        try:
            out[term] = float(convert(float(value), u, term_unit(unit, term)))
        except SigmaTauError:
            continue
    return out or None


def _safe_stem(text: str, taken: set[str]) -> str:
    """A file stem from a channel or group name: letters, digits, '-', '_' and '.' only, never
    starting with '.', unique in ``taken`` (names come from the user's file: 'a/../../x' must
    not write outside the output directory)."""
    stem = re.sub(r"[^A-Za-z0-9_.-]+", "_", text).lstrip(".") or "channel"
    out, k = stem, 2
    while out.lower() in taken:
        out, k = f"{stem}_{k}", k + 1
    taken.add(out.lower())
    return out


#: Figures are capped so that a log of thousands of columns finishes in seconds, not minutes: at
#: most this many signal figures (time series, PSD, lag plot; the first channels in log order) …
MAX_SIGNAL_FIGURES = 24
#: … at most this many σ–τ figures (one per sensor group, the first groups in log order) …
MAX_SIGMA_TAU_FIGURES = 24
#: … and at most this many channels drawn in one σ–τ figure (the first of the group). Every channel
#: is still in results.json, the CSV tables and the report's tables.
MAX_CURVES_PER_FIGURE = 12


def _figure_cap_note(analysis: Any) -> str:
    """One line saying which figures the caps leave out; empty when none."""
    groups = [[c for c in chans if c.results] for chans in analysis.groups().values()]
    groups = [g for g in groups if g]
    parts = []
    if len(analysis.channels) > MAX_SIGNAL_FIGURES:
        parts.append(f"signal figures of the first {MAX_SIGNAL_FIGURES} of {len(analysis.channels):,} channels")
    if len(groups) > MAX_SIGMA_TAU_FIGURES:
        parts.append(f"σ–τ figures of the first {MAX_SIGMA_TAU_FIGURES} of {len(groups):,} groups")
    crowded = max((len(g) for g in groups[:MAX_SIGMA_TAU_FIGURES]), default=0)
    if crowded > MAX_CURVES_PER_FIGURE:
        parts.append(f"at most {MAX_CURVES_PER_FIGURE} channels per σ–τ figure (largest group {crowded:,})")
    if not parts:
        return ""
    return "figures limited to " + "; ".join(parts) + "; every channel is in results.json and the CSV tables"


#: What a log analysed out of core has no figures of, and why.
_OUT_OF_CORE_NOTE = ("signal figures (time series, spectrum, lag plot) not drawn: the log was analysed out of"
                     " core and its samples were never held in memory; the σ–τ figures are complete")


def _out_of_core(analysis: Any) -> bool:
    """Whether the analysis read its log in chunks (a :class:`sigmatau.io.DiskLog`)."""
    from ..io import DiskLog

    return isinstance(analysis.log, DiskLog)


def _figures(analysis: Any, folder: Path, formats: Sequence[str]) -> list[dict[str, Any]]:
    """Write the figures (within the caps above); return their descriptions (file stem, caption, kind)."""
    from . import plots

    made: list[dict[str, Any]] = []
    taken: set[str] = set()
    groups = [(g, [c for c in chans if c.results]) for g, chans in analysis.groups().items()]
    for group, with_results in [(g, cs) for g, cs in groups if cs][:MAX_SIGMA_TAU_FIGURES]:
        shown = with_results[:MAX_CURVES_PER_FIGURE]
        curves = [plots.ChannelCurves(c.name, c.unit, c.results, c.model) for c in shown]
        unit = shown[0].unit
        more = f" (first {len(shown)} of {len(with_results):,})" if len(shown) < len(with_results) else ""
        title = f"{group}: {', '.join(c.name for c in shown)}{more}"
        fig = plots.sigma_tau_figure(curves, title=title, datasheet=_datasheet_for(analysis, group, unit))
        stem = _safe_stem(f"sigma_tau_{group}", taken)
        plots.save_figure(fig, folder / stem, formats=formats)
        made.append({"stem": stem, "kind": "sigma-tau", "group": group,
                     "caption": f"σ–τ of the {group} channels{more} with {analysis.settings['confidence']:.1%}"
                                " intervals (bands), the fitted noise model and its terms, read-off points and"
                                " slope guides"})
    log = analysis.log
    # A log read in chunks holds no samples: its signal figures would need them (_OUT_OF_CORE_NOTE).
    chans = () if _out_of_core(analysis) else analysis.channels[:MAX_SIGNAL_FIGURES]
    # The passes over each record (envelope, PSD, lag-1 correlation) run in two threads, up to two
    # channels ahead, while this thread draws: matplotlib draws one figure at a time, numpy does not
    # need the GIL (a 24 h channel: 1.3 s of such passes against 0.9 s of drawing and saving).
    with ThreadPoolExecutor(max_workers=2, thread_name_prefix="sigmatau-figure") as pool:
        def prepare(c: Any) -> Any:
            return pool.submit(plots.prepare_signal, log[c.name], rate=log.rate, name=c.name)

        ahead = deque(prepare(c) for c in chans[:2])
        for i, c in enumerate(chans):
            prepared = ahead.popleft().result()
            if i + 2 < len(chans):
                ahead.append(prepare(chans[i + 2]))
            fig = plots.signal_figure(log[c.name], rate=log.rate, name=c.name, unit=c.unit, model=c.model,
                                      prepared=prepared)
            stem = _safe_stem(f"signal_{c.name}", taken)
            plots.save_figure(fig, folder / stem, formats=formats)
            made.append({"stem": stem, "kind": "signal", "group": c.group,
                         "caption": f"{c.name}: time series, power spectral density (Welch) and lag plot"})
    for c in [c for c in analysis.channels if getattr(c, "dynamic", None) is not None][:MAX_SIGNAL_FIGURES]:
        fig = plots.dynamic_figure(c.dynamic, unit=c.unit, title=f"{c.name}: dynamic {c.dynamic.statistic}")
        stem = _safe_stem(f"dynamic_{c.name}", taken)
        plots.save_figure(fig, folder / stem, formats=formats)
        made.append({"stem": stem, "kind": "dynamic", "group": c.group,
                     "caption": f"{c.name}: {c.dynamic.statistic} over sliding windows of {c.dynamic.window:,} samples"
                                f" every {c.dynamic.step:,}; {c.dynamic.stationarity.finding}"})
    return made


# ------------------------------------------------------------- our own files only


def write_outputs(
    analysis: Any,
    out_dir: Union[str, os.PathLike],
    *,
    force: bool = False,
    figures: Optional[Sequence[str]] = ("png", "svg"),
    report: bool = True,
    protect: Sequence[Union[str, os.PathLike]] = (),
    exports: Union[str, Sequence[str]] = ("kalibr",),
) -> list[Path]:
    """Write every output of an analysis into ``out_dir``, atomically.

    Everything is written into a temporary sibling directory first (marked
    with this process's PID; :func:`remove_stale_partials`, called here, removes
    those of killed runs). A new ``out_dir`` is that directory renamed into
    place. An existing one is accepted only with ``force`` and only if it is
    empty or sigmatau wrote it (:data:`MANIFEST`): then the files sigmatau
    wrote there before are replaced (put back if anything fails) and every
    other file is left as it is. ``sigmatau-manifest.json`` lists the files
    written, with their sizes and SHA-256.

    Parameters
    ----------
    analysis : LogAnalysis
    out_dir : path
        Directory to create, or with ``force`` an empty or sigmatau output directory.
    force : bool
        Replace the previous sigmatau outputs in an existing ``out_dir``
        (see :func:`check_output_dir`). The current directory, its parents and
        the home directory are always refused.
    figures : sequence of {"png", "svg", "pdf"} or None
        Figure formats; None or empty: no figures. The report embeds PNG, so
        PNG is added when the report is made with figures.
    report : bool
        Write ``report.html``.
    protect : sequence of path
        Paths that must not lie inside ``out_dir`` (the input): refused with a
        ParameterError, so ``force`` can never delete the user's data.
    exports : sequence of str or str
        Estimator parameter files to write when the analysis has gyro and accel
        models (:data:`EXPORTS`: ``kalibr`` → ``imu.yaml``, ``vins`` →
        ``vins_imu.yaml``, ``openvins`` → ``kalibr_imu_chain.yaml``, ``matlab`` →
        ``imu_params.m``, ``gtsam`` → ``gtsam_imu_params.py``); a comma-separated
        string is accepted. Default: Kalibr's only.

    Returns
    -------
    list of Path
        The files written, in ``out_dir`` (the manifest included).
    """
    fmts = [str(f).lower() for f in (figures or ())]
    for f in fmts:
        if f not in FIGURE_FORMATS:
            raise ParameterError(f"figure format {f!r} must be one of {', '.join(FIGURE_FORMATS)}")
    if report and fmts and "png" not in fmts:  # the report embeds the PNG files
        fmts.insert(0, "png")
    targets = parse_exports(exports)
    return write_directory(out_dir, lambda folder: _write_all(analysis, folder, fmts, report, targets),
                           analysis.version, force=force, protect=protect)


def _write_all(analysis: Any, folder: Path, fmts: Sequence[str], report: bool, exports: Sequence[str]) -> None:
    """Every output file of ``analysis`` into the (new, empty) ``folder``."""
    figs: list[dict[str, Any]] = []
    figure_note = ""
    if fmts:
        try:
            figs = _figures(analysis, folder, fmts)
        except SigmaTauError as exc:  # matplotlib missing: everything else is still useful
            if "matplotlib" not in str(exc) and "plot" not in str(exc):
                raise
            figure_note = f"Figures not made: {exc}"
            warnings.warn(f"figures not written: {exc}", SigmaTauWarning, stacklevel=caller_stacklevel())
        else:
            figure_note = _figure_cap_note(analysis)
            if figure_note:
                warnings.warn(figure_note, SigmaTauWarning, stacklevel=caller_stacklevel())
            if _out_of_core(analysis):
                figure_note = "; ".join(n for n in (figure_note, _OUT_OF_CORE_NOTE) if n)
    data = analysis.to_dict()
    data["figures"] = [{**f, "files": [f"{f['stem']}.{e}" for e in fmts]} for f in figs]
    if figure_note:
        data["figures_note"] = figure_note
    _write_text(folder / "results.json", json.dumps(data, indent=1, allow_nan=False, ensure_ascii=False) + "\n")
    _write_text(folder / "statistics.csv", statistics_csv(analysis))
    if any(c.model is not None for c in analysis.channels):
        _write_text(folder / "model.csv", model_csv(analysis))
    yaml_text = None
    for target in exports:
        text = _export_text(analysis, target)
        if text is not None:
            _write_text(folder / EXPORT_FILES[target], text)
        if target == "kalibr":
            yaml_text = text
    if report:
        from .html import render
        from .interactive import report_charts

        # The interactive charts follow the σ–τ figures written, within the same caps.
        charts = report_charts(analysis, figs, max_channels=MAX_CURVES_PER_FIGURE)
        _write_text(folder / "report.html", render(analysis, figures=figs, folder=folder, yaml_text=yaml_text,
                                                   figure_note=figure_note, charts=charts))
