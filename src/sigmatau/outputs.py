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

Everything is written into a temporary sibling directory that is renamed into
place at the end, so an interrupted or failed run leaves nothing half-written,
and an existing directory is replaced only with ``force=True``.
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

from .errors import ParameterError, SigmaTauError, SigmaTauWarning

__all__ = ["write_outputs", "kalibr_yaml", "statistics_csv", "model_csv", "csv_cell", "printable", "OutputExistsError",
           "FIGURE_FORMATS", "KALIBR_KEYS"]

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
        from .io import MissingDependencyError

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
        f"axes combined: {k['axis_rule']}; inflation factor {k['inflation']:g}",
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
    from .io import MissingDependencyError

    if analysis.kalibr is None:
        return None
    try:
        return kalibr_yaml(analysis)
    except MissingDependencyError as exc:  # everything else is still useful
        warnings.warn(f"imu.yaml not written: {exc}", SigmaTauWarning, stacklevel=3)
        return None


def _datasheet_for(analysis: Any, group: str, unit: str) -> Optional[dict[str, float]]:
    """Datasheet terms of ``group`` in the unit of the group's channels (for the figures)."""
    from .units import convert, term_unit

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


def _figures(analysis: Any, folder: Path, formats: Sequence[str]) -> list[dict[str, Any]]:
    """Write the figures; return their descriptions (file stem, caption, kind)."""
    from . import plots

    made: list[dict[str, Any]] = []
    taken: set[str] = set()
    for group, chans in analysis.groups().items():
        with_results = [c for c in chans if c.results]
        if not with_results:
            continue
        curves = [plots.ChannelCurves(c.name, c.unit, c.results, c.model) for c in with_results]
        unit = with_results[0].unit
        title = f"{group}: {', '.join(c.name for c in with_results)}"
        fig = plots.sigma_tau_figure(curves, title=title, datasheet=_datasheet_for(analysis, group, unit))
        stem = _safe_stem(f"sigma_tau_{group}", taken)
        plots.save_figure(fig, folder / stem, formats=formats)
        made.append({"stem": stem, "kind": "sigma-tau", "group": group,
                     "caption": f"σ–τ of the {group} channels with {analysis.settings['confidence']:.1%} intervals"
                                " (bands), the fitted noise model and its terms, read-off points and slope guides"})
    log = analysis.log
    for c in analysis.channels:
        fig = plots.signal_figure(log[c.name], rate=log.rate, name=c.name, unit=c.unit, model=c.model)
        stem = _safe_stem(f"signal_{c.name}", taken)
        plots.save_figure(fig, folder / stem, formats=formats)
        made.append({"stem": stem, "kind": "signal", "group": c.group,
                     "caption": f"{c.name}: time series, power spectral density (Welch) and lag plot"})
    return made


def _write_text(path: Path, text: str) -> None:
    with open(path, "w", encoding="utf-8", newline="") as fh:
        fh.write(text)


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

    Parameters
    ----------
    analysis : LogAnalysis
    out_dir : path
        Directory to create. It must not exist unless ``force`` is true, in
        which case it is replaced as a whole once the new one is complete.
    force : bool
        Replace an existing ``out_dir`` that holds a previous output (a
        ``results.json``) or nothing. The current directory, its parents and
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
        The files written, in ``out_dir``.
    """
    out = Path(out_dir)
    fmts = [str(f).lower() for f in (figures or ())]
    for f in fmts:
        if f not in FIGURE_FORMATS:
            raise ParameterError(f"figure format {f!r} must be one of {', '.join(FIGURE_FORMATS)}")
    if report and fmts and "png" not in fmts:  # the report embeds the PNG files
        fmts.insert(0, "png")
    target = out.resolve()
    for p in protect:
        q = Path(p).resolve()
        if q == target or target in q.parents:
            raise ParameterError(f"the output directory {str(out)!r} contains the input {str(p)!r}; choose another --out")
    if out.exists() and not out.is_dir():
        raise OutputExistsError(f"{str(out)!r} exists and is not a directory")
    if out.exists() and not force:
        raise OutputExistsError(f"output directory {str(out)!r} exists; use --force to replace it")
    cwd = Path.cwd().resolve()
    if target == cwd or target in cwd.parents or target == Path.home().resolve():
        raise ParameterError(f"the output directory {str(out)!r} is the current directory, one of its parents or"
                             " the home directory; choose a directory of its own")
    if out.exists() and any(out.iterdir()) and not (out / "results.json").is_file():
        raise OutputExistsError(f"{str(out)!r} is not empty and holds no sigmatau results (no results.json);"
                                " --force replaces only a previous sigmatau output directory")
    parent = target.parent
    if not parent.is_dir():
        raise ParameterError(f"the parent directory of {str(out)!r} does not exist")
    tmp = Path(tempfile.mkdtemp(prefix=f".{target.name}.partial-", dir=parent))
    try:
        figs: list[dict[str, Any]] = []
        figure_note = ""
        if fmts:
            try:
                figs = _figures(analysis, tmp, fmts)
            except SigmaTauError as exc:  # matplotlib missing: everything else is still useful
                if "matplotlib" not in str(exc) and "plot" not in str(exc):
                    raise
                figure_note = str(exc)
                warnings.warn(f"figures not written: {exc}", SigmaTauWarning, stacklevel=2)
        data = analysis.to_dict()
        data["figures"] = [{**f, "files": [f"{f['stem']}.{e}" for e in fmts]} for f in figs]
        if figure_note:
            data["figures_note"] = figure_note
        _write_text(tmp / "results.json", json.dumps(data, indent=1, allow_nan=False, ensure_ascii=False) + "\n")
        _write_text(tmp / "statistics.csv", statistics_csv(analysis))
        if any(c.model is not None for c in analysis.channels):
            _write_text(tmp / "model.csv", model_csv(analysis))
        yaml_text = _kalibr_text(analysis)
        if yaml_text is not None:
            _write_text(tmp / "imu.yaml", yaml_text)
        if report:
            from .htmlreport import render

            _write_text(tmp / "report.html", render(analysis, figures=figs, folder=tmp, yaml_text=yaml_text,
                                                    figure_note=figure_note))
        os.chmod(tmp, 0o777 & ~umask())  # mkdtemp makes 0700; give the folder the usual mode
        if out.exists():
            old = Path(tempfile.mkdtemp(prefix=f".{target.name}.old-", dir=parent))
            os.replace(target, old / "previous")
            try:
                os.replace(tmp, target)
            except BaseException:
                os.replace(old / "previous", target)  # put the previous output back
                shutil.rmtree(old, ignore_errors=True)
                raise
            shutil.rmtree(old, ignore_errors=True)
        else:
            os.replace(tmp, target)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return sorted(p for p in target.iterdir() if p.is_file())
