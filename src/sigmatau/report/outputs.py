"""Writing a :class:`~sigmatau.analysis.LogAnalysis` to a directory.

:func:`write_outputs` produces, in one directory:

- ``results.json`` — tool version, input file and SHA-256, every setting, the
  timing report, and per channel every statistic (τ, m, n, α, EDF, interval),
  the noise model with intervals in SI and customary units, flags and checks;
- ``statistics.csv`` (one row per channel, statistic and τ) and ``model.csv``
  (one row per channel and term, SI and customary units);
- ``imu.yaml`` — the Kalibr IMU file (:func:`kalibr_yaml`), when the log has
  gyroscope and accelerometer models;
- figures (:mod:`sigmatau.plots`, needs the ``plot`` extra): ``sigma_tau_<group>``
  per sensor group and ``signal_<channel>`` (time series, Welch PSD, lag plot)
  per channel, as PNG and SVG (PDF on request);
- ``report.html`` — one self-contained page (:mod:`sigmatau.htmlreport`).

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

import csv
import io
import json
import math
import numbers
import os
import re
import shutil
import tempfile
import warnings
from pathlib import Path
from typing import Any, Optional, Sequence, Union

from ..errors import ParameterError, SigmaTauError, SigmaTauWarning

__all__ = ["write_outputs", "check_output_dir", "read_manifest", "remove_stale_partials", "kalibr_yaml",
           "statistics_csv", "model_csv", "csv_cell", "printable", "OutputExistsError", "FIGURE_FORMATS",
           "KALIBR_KEYS", "MANIFEST", "PARTIAL_MARKER", "MAX_SIGNAL_FIGURES", "MAX_SIGMA_TAU_FIGURES",
           "MAX_CURVES_PER_FIGURE"]

#: Figure formats :func:`write_outputs` can write.
FIGURE_FORMATS = ("png", "svg", "pdf")


class OutputExistsError(SigmaTauError, FileExistsError):
    """The output directory exists and ``force`` was not given."""


def umask() -> int:
    """The process's file-creation mask (tempfile makes 0600/0700; outputs get the usual modes)."""
    mask = os.umask(0)
    os.umask(mask)
    return mask


#: First characters that make a spreadsheet read a text cell as a formula (OWASP, "CSV Injection").
FORMULA_TRIGGERS = ("=", "+", "-", "@", "\t", "\r", "\n")


def csv_cell(value: Any) -> str:
    """One CSV cell that a spreadsheet shows as the value and never evaluates.

    Numbers are written unchanged (``repr`` of the float: round-trips exactly;
    NaN, inf and None give an empty cell). Text that starts with ``=``, ``+``,
    ``-``, ``@``, tab, CR or LF — which Excel, LibreOffice and Google Sheets
    would run as a formula — gets a leading ``'``, the OWASP rule.

    Parameters
    ----------
    value : str, number, bool or None

    Returns
    -------
    str

    References
    ----------
    OWASP, "CSV Injection", https://owasp.org/www-community/attacks/CSV_Injection

    Examples
    --------
    >>> csv_cell("=1+2"), csv_cell("@SUM(A1)"), csv_cell(-1.5), csv_cell("gyro_x"), csv_cell(None)
    ("'=1+2", "'@SUM(A1)", '-1.5', 'gyro_x', '')
    """
    if value is None:
        return ""
    if isinstance(value, bool):
        return str(value)
    if isinstance(value, numbers.Integral):
        return str(int(value))
    if isinstance(value, numbers.Real):
        v = float(value)
        return repr(v) if math.isfinite(v) else ""
    text = str(value)
    return "'" + text if text.startswith(FORMULA_TRIGGERS) else text


def _g(v: Any) -> Optional[float]:
    """A float for :func:`csv_cell` (None stays None: an empty cell)."""
    return None if v is None else float(v)


def _row(cells: Sequence[Any]) -> list[str]:
    return [csv_cell(c) for c in cells]


def statistics_csv(analysis: Any) -> str:
    """Every statistic of every channel as CSV text, one row per τ.

    Columns: channel, group, unit, statistic, m, tau_s, n, alpha, edf, dev_low,
    dev, dev_high, confidence, bias.
    """
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["channel", "group", "unit", "statistic", "m", "tau_s", "n", "alpha", "edf",
                "dev_low", "dev", "dev_high", "confidence", "bias"])
    for ch in analysis.channels:
        for stat, r in ch.results.items():
            for i in range(len(r.taus)):
                alpha = r.alpha[i] if r.alpha is not None else math.nan
                w.writerow(_row([ch.name, ch.group, ch.unit, stat, int(r.m[i]), _g(r.taus[i]), int(r.n[i]),
                            "" if not math.isfinite(alpha) else int(alpha),
                            _g(r.edf[i]) if r.edf is not None else "",
                            _g(r.ci_low[i]) if r.ci_low is not None else "", _g(r.dev[i]),
                            _g(r.ci_high[i]) if r.ci_high is not None else "",
                            _g(r.confidence) if r.confidence is not None else "", r.bias]))
    return buf.getvalue()


def model_csv(analysis: Any) -> str:
    """The IMU noise model of every channel as CSV text, one row per channel, term and unit.

    Each term appears in the samples' unit, in SI and in each customary unit
    (``unit_kind`` says which); ``value`` is empty when the term is not
    resolved and ``high`` is then its upper bound.
    """
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["channel", "kind", "term", "unit_kind", "unit", "resolved", "value", "low", "high",
                "confidence", "method", "readoff_value", "readoff_low", "readoff_high"])
    for ch in analysis.channels:
        m = ch.model
        if m is None:
            continue
        for t in ("Q", "N", "B", "K", "R"):
            p = getattr(m, t)
            ro = m.readoff.get(t)
            for kind, q in [("samples", p), ("si", p.si())] + [("customary", c) for c in p.customary()]:
                r = ro.to(q.unit) if ro is not None else None
                w.writerow(_row([ch.name, m.kind, t, kind, q.unit, q.resolved, _g(q.value) if q.resolved else "",
                            _g(q.low), _g(q.high), _g(q.confidence), q.method,
                            _g(r.value) if r is not None and r.resolved else "",
                            _g(r.low) if r is not None else "", _g(r.high) if r is not None else ""]))
    return buf.getvalue()


#: Characters that end a line or drive a terminal: C0 (tab and newline included), DEL, C1 (NEL
#: included), the Unicode line and paragraph separators (line breaks for YAML 1.1) and the
#: bidirectional overrides that reorder what a reader sees ("Trojan Source").
_CONTROL = re.compile("[\x00-\x1f\x7f-\x9f\u2028\u2029\u202a-\u202e\u2066-\u2069]")
_CONTROL_KEEP_NEWLINE = re.compile("[\x00-\x09\x0b-\x1f\x7f-\x9f\u2028\u2029\u202a-\u202e\u2066-\u2069]")
_NAMED = {"\n": "\\n", "\r": "\\r", "\t": "\\t"}


def _escape_char(match: "re.Match[str]") -> str:
    ch = match.group(0)
    if ch in _NAMED:
        return _NAMED[ch]
    code = ord(ch)
    return f"\\x{code:02x}" if code < 0x100 else f"\\u{code:04x}"


def printable(text: Any, *, multiline: bool = False) -> str:
    """``text`` with every control character shown as a Python escape (``\\x1b``, ``\\n``).

    For text that reaches a terminal or a one-line comment: names and messages
    come from the user's files, and an escape sequence (ESC, CSI, OSC), a
    carriage return or a bidirectional override in them must not drive the
    terminal or add lines. Escaped: C0 (U+0000–U+001F, tab included), DEL,
    C1 (U+0080–U+009F), U+2028/U+2029 and the bidirectional controls
    U+202A–U+202E, U+2066–U+2069.

    Parameters
    ----------
    text : object
        Converted with ``str``.
    multiline : bool
        Keep ``\\n`` (text of ours made of several lines, such as the summary).

    Returns
    -------
    str

    Examples
    --------
    >>> printable("gyro\\x1b[2Jx\\nupdate_rate: 1")
    'gyro\\\\x1b[2Jx\\\\nupdate_rate: 1'
    >>> printable("a\\nb", multiline=True)
    'a\\nb'
    """
    pattern = _CONTROL_KEEP_NEWLINE if multiline else _CONTROL
    return pattern.sub(_escape_char, str(text))


KALIBR_KEYS = ("accelerometer_noise_density", "accelerometer_random_walk", "gyroscope_noise_density",
               "gyroscope_random_walk")


def _yaml_module() -> Any:
    """PyYAML, or a MissingDependencyError naming the extra."""
    try:
        import yaml
    except ImportError:
        from ..io import MissingDependencyError

        raise MissingDependencyError('imu.yaml needs PyYAML: pip install "sigmatau[yaml]"') from None
    return yaml


def _one_line_dumper(yaml: Any) -> Any:
    """PyYAML's SafeDumper writing any string with a control character double-quoted and escaped.

    Single-quoted and plain scalars may span lines; the double-quoted style
    escapes line breaks, and ``allow_unicode=False`` escapes everything outside
    ASCII (ROS names are ASCII), so each key stays on one line.
    """

    class OneLineDumper(yaml.SafeDumper):
        pass

    def represent_str(dumper: Any, value: str) -> Any:
        style = '"' if _CONTROL.search(value) else None
        return dumper.represent_scalar("tag:yaml.org,2002:str", value, style=style)

    OneLineDumper.add_representer(str, represent_str)
    return OneLineDumper


def kalibr_yaml(analysis: Any) -> str:
    """The Kalibr ``imu.yaml`` text of an analysis with gyroscope and accelerometer models.

    The four Kalibr keys (continuous-time noise densities and random walks, SI),
    ``rostopic`` and ``update_rate``, written by PyYAML's safe dumper (names
    from the user's files can hold newlines, ``: ``, quotes or ``!!`` tags and
    must stay one string), with comments that state the source file, how the
    axes were combined and each axis's value, which values are upper bounds of
    unresolved terms, and the discrete-time equivalents ``σ_d = N·√f`` and
    ``σ_bd = K/√f`` (Kalibr wiki, "IMU Noise Model"). Every name in a comment
    has its control characters escaped (:func:`printable`), so no comment can
    end its line.

    Raises
    ------
    ParameterError
        The analysis has no Kalibr entry.
    MissingDependencyError
        PyYAML is not installed (extra ``yaml``).
    """
    k = analysis.kalibr
    if k is None:
        raise ParameterError(f"no Kalibr entry: {analysis.kalibr_note or 'no IMU model'}")
    yaml = _yaml_module()
    src = analysis.log.source
    topic = f", topic {src.topic}" if src.topic else ""
    head = [
        f"IMU noise model for Kalibr, written by sigmatau {analysis.version}",
        f"input: {src.path} ({src.format}{topic}), sha256 {src.sha256}",
        f"axes combined: {k['axis_rule']}; inflation factor {k['inflation']:g}"
        + (f"; fewer than three axes: {k['axes_note']}" if k.get("axes_note") else ""),
        "continuous-time values (densities), SI units; Kalibr discretises them with update_rate",
    ]
    units = k["units"]
    for key in KALIBR_KEYS:
        sensor, _, suffix = key.partition("_")
        names = k.get("axes", {}).get(sensor, [])
        per = ", ".join(f"{n} {v:.4g}" if v is not None else f"{n} -" for n, v in zip(names, k["per_axis"][key]))
        what = "noise density (continuous time)" if suffix == "noise_density" else "bias random walk"
        note = "; includes upper bounds of unresolved axes" if any(b.startswith(key) for b in k["bounds_used"]) else ""
        head.append(f"{key}: {k[key]:.6e}, {what} [{units[key]}]; per axis: {per}{note}")
    head.append("rostopic: the IMU topic; update_rate: Hz, for discretisation of the values above")
    data = {key: float(k[key]) for key in KALIBR_KEYS}
    data["rostopic"] = str(k["rostopic"])
    data["update_rate"] = float(k["update_rate"])
    body = yaml.dump(data, Dumper=_one_line_dumper(yaml), sort_keys=False, allow_unicode=False,
                     default_flow_style=False, width=1 << 30)
    d = k["discrete"]
    tail = [f"discrete-time equivalents at {float(k['update_rate']):g} Hz (standard deviations, not densities):"]
    tail += [f"  {key}: {d[key]:.6e}" for key in ("accelerometer_sigma_d", "accelerometer_sigma_bd",
                                                   "gyroscope_sigma_d", "gyroscope_sigma_bd")]
    comment = "".join(f"# {printable(line)}\n" for line in head)
    return comment + body + "".join(f"# {printable(line)}\n" for line in tail)


def _kalibr_text(analysis: Any) -> Optional[str]:
    """The imu.yaml text; None without a Kalibr entry or, with one warning, without PyYAML."""
    from ..io import MissingDependencyError

    if analysis.kalibr is None:
        return None
    try:
        return kalibr_yaml(analysis)
    except MissingDependencyError as exc:  # everything else is still useful
        warnings.warn(f"imu.yaml not written: {exc}", SigmaTauWarning, stacklevel=4)
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
    for c in analysis.channels[:MAX_SIGNAL_FIGURES]:
        fig = plots.signal_figure(log[c.name], rate=log.rate, name=c.name, unit=c.unit, model=c.model)
        stem = _safe_stem(f"signal_{c.name}", taken)
        plots.save_figure(fig, folder / stem, formats=formats)
        made.append({"stem": stem, "kind": "signal", "group": c.group,
                     "caption": f"{c.name}: time series, power spectral density (Welch) and lag plot"})
    return made


def _write_text(path: Path, text: str) -> None:
    with open(path, "w", encoding="utf-8", newline="") as fh:
        fh.write(text)


# ------------------------------------------------------------- our own files only

#: The file listing what sigmatau wrote into an output directory (name, size, SHA-256 of each):
#: ``force`` replaces those files and nothing else.
MANIFEST = "sigmatau-manifest.json"
#: Marker in sigmatau's temporary directories (``.OUT.partial-*``, ``.OUT.old-*``): host and PID of
#: the process that made it, so a later run removes it once that process is gone, and only it.
PARTIAL_MARKER = ".sigmatau-partial"
_MANIFEST_FORMAT = "sigmatau output manifest 1"


def _sha256(path: Path) -> str:
    import hashlib

    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _entry(path: Path) -> dict[str, Any]:
    return {"name": path.name, "size": path.stat().st_size, "sha256": _sha256(path)}


def _manifest_text(entries: Sequence[dict[str, Any]], version: str) -> str:
    return json.dumps({"format": _MANIFEST_FORMAT, "tool": f"sigmatau {version}", "files": list(entries)},
                      indent=1) + "\n"


def _plain_name(name: Any) -> bool:
    """A file name of ours: no directory part, not '.', '..' or the manifest itself."""
    return (isinstance(name, str) and name not in ("", ".", "..", MANIFEST) and "/" not in name
            and "\\" not in name and "\x00" not in name)


def read_manifest(folder: Union[str, os.PathLike]) -> Optional[list[dict[str, Any]]]:
    """The files sigmatau recorded as its own in ``folder``; None when there is no valid manifest.

    Parameters
    ----------
    folder : path

    Returns
    -------
    list of dict or None
        One ``{"name", "size", "sha256"}`` per file (a name may appear twice
        while a replacement is under way: its old and its new content).
    """
    path = Path(folder) / MANIFEST
    if path.is_symlink() or not path.is_file():
        return None
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if not isinstance(data, dict) or data.get("format") != _MANIFEST_FORMAT or not isinstance(data.get("files"), list):
        return None
    files = [f for f in data["files"] if isinstance(f, dict) and _plain_name(f.get("name"))
             and isinstance(f.get("size"), int) and isinstance(f.get("sha256"), str)]
    return files if len(files) == len(data["files"]) else None


def _ours(folder: Path, entries: Sequence[dict[str, Any]]) -> list[str]:
    """The listed files present in ``folder`` (a changed one is refused: it may hold the user's edits)."""
    names: list[str] = []
    for name in dict.fromkeys(e["name"] for e in entries):
        path = folder / name
        if not os.path.lexists(path):
            continue
        versions = [(e["size"], e["sha256"]) for e in entries if e["name"] == name]
        if path.is_symlink() or not path.is_file() or (path.stat().st_size, _sha256(path)) not in versions:
            raise OutputExistsError(f"{name!r} in {str(folder)!r} changed since sigmatau wrote it; move it"
                                    " elsewhere first, sigmatau replaces only its own unchanged files")
        names.append(name)
    return names


#: Files every analysis writes (figures depend on the channels); checked before the analysis runs.
_FIXED_NAMES = ("results.json", "statistics.csv", "model.csv", "imu.yaml", "report.html")


def check_output_dir(out_dir: Union[str, os.PathLike], *, force: bool = False,
                     protect: Sequence[Union[str, os.PathLike]] = ()) -> None:
    """Refuse, before any computation, an output directory :func:`write_outputs` would refuse.

    Allowed: a directory that does not exist (in an existing parent); with
    ``force``, an empty directory or one sigmatau wrote (it holds
    ``sigmatau-manifest.json``), whose listed files are replaced if unchanged
    and whose other files are left alone. Never the current directory, its
    parents or the home directory, nor a directory holding a path of
    ``protect``.

    Raises
    ------
    OutputExistsError
        ``out_dir`` exists and ``force`` is not given, it is not a directory,
        it is not a sigmatau output, or a file sigmatau wrote there was changed.
    ParameterError
        ``out_dir`` is the current directory, one of its parents or the home
        directory, its parent does not exist, or it contains a path of ``protect``
        (the input).
    """
    out = Path(out_dir)
    target = out.resolve()
    cwd = Path.cwd().resolve()
    if target == cwd or target in cwd.parents or target == Path.home().resolve():
        raise ParameterError(f"the output directory {str(out)!r} is the current directory, one of its parents or"
                             " the home directory; choose a directory of its own")
    for p in protect:
        q = Path(p).resolve()
        if q == target or target in q.parents:
            raise ParameterError(f"the output directory {str(out)!r} contains the input {str(p)!r}; choose another"
                                 " output directory")
    if os.path.lexists(out) and not out.is_dir():
        raise OutputExistsError(f"{str(out)!r} exists and is not a directory; choose another output directory")
    if not target.parent.is_dir():
        raise ParameterError(f"the parent directory of {str(out)!r} does not exist")
    if not out.exists():
        return
    if not any(out.iterdir()):
        if not force:
            raise OutputExistsError(f"output directory {str(out)!r} exists (empty); use --force to write into it")
        return
    entries = read_manifest(out)
    if entries is None:
        raise OutputExistsError(f"{str(out)!r} exists and is not a sigmatau output directory (no {MANIFEST});"
                                " choose another output directory")
    if not force:
        raise OutputExistsError(f"output directory {str(out)!r} exists; use --force to replace the sigmatau"
                                " outputs in it")
    ours = set(_ours(out, entries))
    for name in _FIXED_NAMES:
        if name not in ours and os.path.lexists(out / name):
            raise OutputExistsError(f"{name!r} in {str(out)!r} is not a file sigmatau wrote; move it elsewhere"
                                    " first")


def _pid_alive(pid: int) -> bool:
    if os.name == "nt":  # os.kill(pid, 0) would terminate the process there: never judge, keep the directory
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError, ValueError):
        return True  # someone else's process, or not a PID we can judge: keep its directory
    return True


def _mark(folder: Path) -> None:
    import socket

    _write_text(folder / PARTIAL_MARKER, json.dumps({"host": socket.gethostname(), "pid": os.getpid()}) + "\n")


def remove_stale_partials(parent: Union[str, os.PathLike]) -> list[Path]:
    """Remove the temporary directories sigmatau left in ``parent`` when a run was killed.

    Only directories named ``.*.partial-*`` or ``.*.old-*`` that hold
    sigmatau's marker naming this host and a process that no longer exists;
    a directory of a running process, of another host or without the marker
    is left alone.

    Returns
    -------
    list of Path
        The directories removed.
    """
    import socket

    removed: list[Path] = []
    folder = Path(parent)
    candidates = [*folder.glob(".*.partial-*"), *folder.glob(".*.old-*")]
    for d in candidates:
        marker = d / PARTIAL_MARKER
        if d.is_symlink() or not d.is_dir() or marker.is_symlink() or not marker.is_file():
            continue
        try:
            who = json.loads(marker.read_text(encoding="utf-8"))
            host, pid = who["host"], int(who["pid"])
        except (OSError, ValueError, KeyError, TypeError):
            continue
        if host != socket.gethostname() or pid == os.getpid() or _pid_alive(pid):
            continue
        shutil.rmtree(d, ignore_errors=True)
        removed.append(d)
    return removed


def _replace_files(new: Path, target: Path, entries: list[dict[str, Any]], version: str) -> None:
    """Move the files of ``new`` into the existing ``target``, replacing only sigmatau's own files.

    The previous files go to a marked backup directory first and come back if
    anything fails; while files move, the manifest lists old and new
    versions, so a run killed half-way leaves a directory a later ``--force``
    still recognises.
    """
    old_entries = read_manifest(target) or []
    old_text = (target / MANIFEST).read_text(encoding="utf-8") if old_entries else None
    ours = _ours(target, old_entries)
    for e in entries:
        if e["name"] not in ours and os.path.lexists(target / e["name"]):
            raise OutputExistsError(f"{e['name']!r} in {str(target)!r} is not a file sigmatau wrote; move it"
                                    " elsewhere first")
    backup = Path(tempfile.mkdtemp(prefix=f".{target.name}.old-", dir=target.parent))
    moved: list[str] = []
    placed: list[str] = []
    try:
        _mark(backup)
        _replace_manifest(target, _manifest_text([*old_entries, *entries], version))
        for name in ours:
            os.replace(target / name, backup / name)
            moved.append(name)
        for e in entries:
            os.replace(new / e["name"], target / e["name"])
            placed.append(e["name"])
        _replace_manifest(target, _manifest_text(entries, version))
    except BaseException:
        for name in placed:  # put everything back as it was
            os.replace(target / name, new / name)
        for name in moved:
            os.replace(backup / name, target / name)
        if old_text is not None:
            _replace_manifest(target, old_text)
        elif (target / MANIFEST).exists():
            os.unlink(target / MANIFEST)
        shutil.rmtree(backup, ignore_errors=True)
        raise
    shutil.rmtree(backup, ignore_errors=True)


def _replace_manifest(folder: Path, text: str) -> None:
    fd, tmp = tempfile.mkstemp(prefix=".sigmatau-manifest.", suffix=".partial", dir=folder)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(text)
        os.chmod(tmp, 0o666 & ~umask())
        os.replace(tmp, folder / MANIFEST)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def write_outputs(
    analysis: Any,
    out_dir: Union[str, os.PathLike],
    *,
    force: bool = False,
    figures: Optional[Sequence[str]] = ("png", "svg"),
    report: bool = True,
    protect: Sequence[Union[str, os.PathLike]] = (),
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

    Returns
    -------
    list of Path
        The files written, in ``out_dir`` (the manifest included).
    """
    out = Path(out_dir)
    fmts = [str(f).lower() for f in (figures or ())]
    for f in fmts:
        if f not in FIGURE_FORMATS:
            raise ParameterError(f"figure format {f!r} must be one of {', '.join(FIGURE_FORMATS)}")
    if report and fmts and "png" not in fmts:  # the report embeds the PNG files
        fmts.insert(0, "png")
    target = out.resolve()
    check_output_dir(out, force=force, protect=protect)
    parent = target.parent
    remove_stale_partials(parent)
    tmp = Path(tempfile.mkdtemp(prefix=f".{target.name}.partial-", dir=parent))
    try:
        _mark(tmp)
        _write_all(analysis, tmp, fmts, report)
        os.unlink(tmp / PARTIAL_MARKER)
        entries = [_entry(p) for p in sorted(tmp.iterdir()) if p.is_file()]
        if out.exists():
            _replace_files(tmp, target, entries, analysis.version)
            shutil.rmtree(tmp, ignore_errors=True)
        else:
            _write_text(tmp / MANIFEST, _manifest_text(entries, analysis.version))
            os.chmod(tmp, 0o777 & ~umask())  # mkdtemp makes 0700; give the folder the usual mode
            os.replace(tmp, target)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return sorted(target / n for n in [*(e["name"] for e in entries), MANIFEST])


def _write_all(analysis: Any, folder: Path, fmts: Sequence[str], report: bool) -> None:
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
            warnings.warn(f"figures not written: {exc}", SigmaTauWarning, stacklevel=3)
        else:
            figure_note = _figure_cap_note(analysis)
            if figure_note:
                warnings.warn(figure_note, SigmaTauWarning, stacklevel=3)
    data = analysis.to_dict()
    data["figures"] = [{**f, "files": [f"{f['stem']}.{e}" for e in fmts]} for f in figs]
    if figure_note:
        data["figures_note"] = figure_note
    _write_text(folder / "results.json", json.dumps(data, indent=1, allow_nan=False, ensure_ascii=False) + "\n")
    _write_text(folder / "statistics.csv", statistics_csv(analysis))
    if any(c.model is not None for c in analysis.channels):
        _write_text(folder / "model.csv", model_csv(analysis))
    yaml_text = _kalibr_text(analysis)
    if yaml_text is not None:
        _write_text(folder / "imu.yaml", yaml_text)
    if report:
        from .html import render

        _write_text(folder / "report.html", render(analysis, figures=figs, folder=folder, yaml_text=yaml_text,
                                                   figure_note=figure_note))
