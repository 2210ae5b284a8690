"""Text formats of an analysis, each escaped for where it is read: CSV cells, the terminal, Kalibr's imu.yaml.

Holds :func:`csv_cell` (no spreadsheet formulas), :func:`statistics_csv` and
:func:`model_csv`, :func:`printable` (control and bidirectional characters shown
as escapes on a terminal) and :func:`kalibr_yaml` (PyYAML's safe dumper, one
line per value). Public through :mod:`sigmatau.outputs`.
"""

from __future__ import annotations

import csv
import io
import math
import numbers
import re
from typing import Any, Optional, Sequence

from ..errors import ParameterError

__all__ = [
    "FORMULA_TRIGGERS", "csv_cell", "statistics_csv", "model_csv", "printable", "KALIBR_KEYS", "kalibr_yaml",
]


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
