"""``report.html``: one self-contained page of a :class:`~sigmatau.analysis.LogAnalysis`.

The page holds the input and its data checks, the noise model of every channel
with intervals in SI and customary units, the datasheet comparison, the Kalibr
YAML, the figures (PNG embedded as data URIs) and every statistic's table
(Stable32 layout: AF, τ, n, α, min σ, σ, max σ). It needs no network and no
other file, so it can be mailed or archived as it is. With the ``interactive``
extra each σ–τ figure has an interactive chart under it
(:mod:`sigmatau.report.interactive`: its library is inlined, its data escaped
there); without it the page has no script.
"""

from __future__ import annotations

import base64
import datetime as _dt
import html
import json
import math
from pathlib import Path
from typing import Any, Optional, Sequence

__all__ = ["render"]

_CSS = """
body{font-family:system-ui,-apple-system,"Segoe UI",Roboto,Helvetica,Arial,sans-serif;margin:0 auto;
max-width:1200px;padding:0 1.5em 3em;color:#1d1d1f;line-height:1.45}
h1{font-size:1.6em;margin:1.2em 0 .2em}h2{font-size:1.25em;margin-top:2em;border-bottom:1px solid #ccc}
h3{font-size:1.05em;margin:1.4em 0 .4em}
table{border-collapse:collapse;margin:.5em 0;font-size:.88em}
th,td{border:1px solid #d0d0d0;padding:.2em .5em;text-align:right;vertical-align:top}
th{background:#f2f2f2}td.l,th.l{text-align:left}
pre{background:#f6f6f6;border:1px solid #ddd;padding:.7em;overflow-x:auto;font-size:.85em}
figure{margin:1em 0}figure img{max-width:100%;height:auto;border:1px solid #eee}
.ichart{width:100%;margin:.6em 0 .3em}.ichart.vega-embed{display:flex;width:100%}
figcaption{font-size:.88em;color:#444}
.flag{color:#8a4b00}.warn{color:#a00}.muted{color:#666}.ok{color:#185c18}
details{margin:.3em 0}summary{cursor:pointer}
.kv td:first-child{text-align:left;font-weight:600}.kv td{text-align:left}
"""


def _e(text: Any) -> str:
    return html.escape(str(text), quote=True)


def _num(v: Any, fmt: str = ".4g") -> str:
    if v is None:
        return "–"
    v = float(v)
    return format(v, fmt) if math.isfinite(v) else "–"


def _pretty(unit: str) -> str:
    from ..imu.units import pretty

    return pretty(unit) if unit else ""


def _param(p: Any) -> str:
    from ..pipeline.results import format_parameter

    return _e(format_parameter(p))


def _input_section(a: Any) -> str:
    log = a.log
    src = log.source
    rows = [("file", src.path), ("format", src.format + (f" — {src.detail}" if src.detail else "")),
            ("size", f"{src.size:,} bytes"), ("SHA-256", src.sha256)]
    if src.topic:
        rows.append(("topic", src.topic))
    rows += [("channels", ", ".join(f"{n} [{log.units.get(n) or '?'}]" for n in log.names)),
             ("samples", f"{len(log):,} per channel at {log.rate:.6g} Hz ({len(log) / log.rate:.6g} s)"),
             ("data type", log.data_type)]
    body = "".join(f"<tr><td>{_e(k)}</td><td>{_e(v)}</td></tr>" for k, v in rows)
    return f'<h2 id="input">Input</h2><table class="kv">{body}</table>'


def _checks_section(a: Any) -> str:
    parts = ['<h2 id="checks">Data checks</h2>', "<h3>Timing</h3>",
             f"<pre>{_e(a.log.timing.summary())}</pre>"]
    for n in a.notes:
        parts.append(f'<p class="flag">{_e(n)}</p>')
    rows = []
    for ch in a.channels:
        checks = ch.model.checks if ch.model is not None else None
        if checks is None:
            continue
        findings = "<br>".join(_e(f) for f in checks.findings) or '<span class="ok">no problem found</span>'
        rows.append(f'<tr><td class="l">{_e(ch.name)}</td><td>{_num(checks.std)}</td>'
                    f'<td>{_e(checks.levels if checks.levels is not None else "continuous")}</td>'
                    f'<td class="l">{_e(checks.rolloff)}</td><td class="l">{findings}</td></tr>')
    if rows:
        parts.append("<h3>Samples</h3><table><tr><th class='l'>channel</th><th>std</th><th>levels</th>"
                     "<th class='l'>spectrum near f/2</th><th class='l'>findings</th></tr>" + "".join(rows) + "</table>")
    parts.append(_prep_table(a))
    if a.warnings:
        parts.append("<h3>Warnings</h3><ul>" + "".join(f'<li class="warn">{_e(w)}</li>' for w in a.warnings)
                     + "</ul>")
    return "".join(parts)


def _prep_table(a: Any) -> str:
    """The preparation steps of each channel, in order, with what each did (empty without any)."""
    rows = []
    for ch in a.channels:
        for step in getattr(ch, "prep", ()):
            est = "; ".join(f"{k} {_num(v.get('value'))} ± {_num(v.get('stderr'))}"
                            for k, v in (step.get("estimates") or {}).items())
            notes = " ".join(step.get("notes") or ())
            rows.append(f'<tr><td class="l">{_e(ch.name)}</td><td class="l">{_e(step.get("step", ""))}</td>'
                        f'<td class="l">{_e(est)}</td><td class="l">{_e(notes)}</td></tr>')
    if not rows:
        return ""
    return ("<h3>Preparation</h3><table><tr><th class='l'>channel</th><th class='l'>step</th>"
            "<th class='l'>estimates (± standard error)</th><th class='l'>what was done</th></tr>"
            + "".join(rows) + "</table>")


def _overview_section(a: Any) -> str:
    """One row per modelled channel: each term in its first customary unit, flags counted."""
    models = [ch for ch in a.channels if ch.model is not None]
    if not models:
        return ""
    rows = []
    for ch in models:
        m = ch.model
        cells = []
        for t in ("Q", "N", "B", "K", "R"):
            p = getattr(m, t)
            cust = p.customary()
            cells.append(f"<td>{_param(cust[0] if cust else p.si())}</td>")
        flags = sum(1 for f in m.flags if f.code != "not-resolved")
        rows.append(f"<tr><td class='l'>{_e(ch.name)}</td>{''.join(cells)}<td>{flags}</td></tr>")
    return ('<h2 id="overview">Overview</h2><p>The noise model of each channel in customary units; details, SI'
            " values, read-offs and flags under <a href=\"#model\">Noise model</a>.</p><table><tr><th class='l'>"
            "channel</th><th>Q</th><th>N</th><th>B</th><th>K</th><th>R</th><th>flags</th></tr>"
            + "".join(rows) + "</table>")


def _model_section(a: Any) -> str:
    models = [ch for ch in a.channels if ch.model is not None]
    out = ['<h2 id="model">Noise model</h2>']
    if not models:
        notes = "".join(f"<li>{_e(ch.name)}: {_e(ch.model_note)}</li>" for ch in a.channels if ch.model_note)
        return out[0] + "<p>No IMU noise model was fitted.</p>" + (f"<ul>{notes}</ul>" if notes else "")
    conf = models[0].model.confidence
    out.append(f"<p>Intervals are two-sided at {conf:.1%}; a value shown as “&lt; x” is an upper bound of a term the"
               " record does not resolve. Method: weighted fit of the five-term Allan-variance model to the OADEV"
               " curve (IEEE Std 952 Annex C), with read-offs on the slope lines as a cross-check; a first-order"
               " Gauss–Markov term (σ, correlation time T<sub>c</sub>) is added when the Bayesian information"
               " criterion favours it clearly.</p>")
    for ch in models:
        m = ch.model
        rows = []
        for t in ("Q", "N", "B", "K", "R"):
            p = getattr(m, t)
            cust = "<br>".join(_param(c) for c in p.customary())
            ro = m.readoff.get(t)
            reg = m.regions.get(t)
            region = (f"{reg.tau_low:.3g}–{reg.tau_high:.3g} s" if reg is not None and reg.resolved else "–")
            rows.append(f"<tr><td class='l'>{t}</td><td>{_param(p.si())}</td><td>{cust}</td>"
                        f"<td>{_param(ro.si()) if ro is not None else '–'}</td><td>{region}</td></tr>")
        gm = getattr(m, "gauss_markov", None)
        if gm is not None:
            # The Gauss–Markov term (σ, T_c): fitted only, no read-off; how it was chosen in the title.
            why = _e(f"{gm.criterion}: ΔBIC = {gm.delta_bic:.3g} (kept when > {gm.margin:g}); {gm.note}")
            for q, label in ((gm.sigma, "GM σ"), (gm.tau_c, "GM T<sub>c</sub>")):
                rows.append(f"<tr title='{why}'><td class='l'>{label}</td><td>{_param(q.si())}</td><td>–</td>"
                            "<td>–</td><td>–</td></tr>")
        flags = "".join(f'<li class="flag">[{_e(f.code)}{" " + _e(f.term) if f.term else ""}] {_e(f.message)}</li>'
                        for f in m.flags)
        out.append(f"<h3>{_e(ch.name)} ({_e(m.kind)}, samples in {_e(_pretty(m.unit))})</h3>"
                   "<table><tr><th class='l'>term</th><th>value (SI)</th><th>customary units</th>"
                   "<th>read-off (SI)</th><th>read-off region</th></tr>" + "".join(rows) + "</table>"
                   + (f"<ul>{flags}</ul>" if flags else ""))
        if ch.datasheet:
            drows = "".join(
                f"<tr><td class='l'>{_e(r['term'])}</td><td>{_e(r['reference_given'])}</td>"
                f"<td>{_num(r['measured'])} [{_num(r['low'])}, {_num(r['high'])}] {_e(_pretty(r['unit']))}</td>"
                f"<td>{_num(r['ratio'], '.3g')}</td><td>{'yes' if r['covers'] else 'no'}</td></tr>"
                for r in ch.datasheet)
            out.append("<table><tr><th class='l'>term</th><th>datasheet</th><th>measured</th><th>ratio</th>"
                       "<th>interval covers it</th></tr>" + drows + "</table>")
    for ch in a.channels:
        if ch.model is None and ch.model_note:
            out.append(f'<p class="muted">{_e(ch.name)}: no model — {_e(ch.model_note)}</p>')
    return "".join(out)


def _kalibr_section(a: Any, yaml_text: Optional[str]) -> str:
    if yaml_text is None:
        return f'<h2 id="kalibr">Kalibr imu.yaml</h2><p class="muted">{_e(a.kalibr_note or "not written")}</p>'
    return ('<h2 id="kalibr">Kalibr imu.yaml</h2><p>Written as <code>imu.yaml</code>; values are continuous-time'
            f" densities in SI units.</p><pre>{_e(yaml_text)}</pre>")


def _figures_section(figures: Sequence[dict], folder: Optional[Path], note: str, charts: Any = None) -> str:
    """The figures, each PNG embedded; under each σ–τ figure its interactive chart when ``charts`` has one.

    ``charts`` is a :class:`~sigmatau.report.interactive.InteractiveCharts`: its
    fragments are HTML built (and escaped) there, placed as they are. (Typed
    ``Any``: this module may not import that one, which imports it through
    :mod:`~sigmatau.report.spectrum`.)
    """
    out = ['<h2 id="figures">Figures</h2>']
    if note:
        out.append(f'<p class="flag">{_e(note)}</p>')
    fragments = getattr(charts, "fragments", None) or {}
    if getattr(charts, "note", ""):
        out.append(f'<p class="muted" id="interactive-note">{_e(charts.note)}</p>')
    for f in figures:
        path = folder / f"{f['stem']}.png" if folder is not None else None
        if path is None or not path.is_file():
            continue
        b64 = base64.b64encode(path.read_bytes()).decode("ascii")
        out.append(f'<figure id="fig-{_e(f["stem"])}"><img src="data:image/png;base64,{b64}" '
                   f'alt="{_e(f["caption"])}">{fragments.get(f["stem"], "")}'
                   f'<figcaption>{_e(f["caption"])}</figcaption></figure>')
    return "".join(out)


def _tables_section(a: Any) -> str:
    out = ['<h2 id="tables">Statistics</h2><p>Per channel and statistic: averaging factor AF, τ, number of terms n,'
           " noise type α (power-law exponent of S_y), equivalent degrees of freedom and the interval of σ.</p>"]
    for ch in a.channels:
        out.append(f"<h3>{_e(ch.name)} [{_e(_pretty(ch.unit) or '?')}]</h3>")
        for stat, why in ch.skipped.items():
            out.append(f'<p class="muted">{_e(stat)}: not computed — {_e(why)}</p>')
        for stat, r in ch.results.items():
            rows = []
            for i in range(len(r.taus)):
                alpha = r.alpha[i] if r.alpha is not None else math.nan
                rows.append(f"<tr><td>{int(r.m[i])}</td><td>{_num(r.taus[i], '.4g')}</td><td>{int(r.n[i])}</td>"
                            f"<td>{int(alpha) if math.isfinite(alpha) else '–'}</td>"
                            f"<td>{_num(r.edf[i] if r.edf is not None else None, '.4g')}</td>"
                            f"<td>{_num(r.ci_low[i] if r.ci_low is not None else None, '.4e')}</td>"
                            f"<td>{_num(r.dev[i], '.4e')}</td>"
                            f"<td>{_num(r.ci_high[i] if r.ci_high is not None else None, '.4e')}</td></tr>")
            out.append(f"<details><summary>{_e(stat.upper())} ({len(r.taus)} τ, {_e(r.bias)} bias)</summary>"
                       "<table><tr><th>AF</th><th>τ [s]</th><th>n</th><th>α</th><th>EDF</th><th>min σ</th>"
                       "<th>σ</th><th>max σ</th></tr>" + "".join(rows) + "</table></details>")
    return "".join(out)


def render(analysis: Any, *, figures: Sequence[dict] = (), folder: Optional[Path] = None,
           yaml_text: Optional[str] = None, figure_note: str = "", charts: Any = None) -> str:
    """The report page as HTML text.

    Parameters
    ----------
    analysis : LogAnalysis
    figures : sequence of dict
        Figure descriptions from :func:`sigmatau.outputs.write_outputs`
        (``stem``, ``caption``); their PNG files are read from ``folder`` and
        embedded.
    folder : Path, optional
        Where the PNG files are.
    yaml_text : str, optional
        The Kalibr YAML to show.
    figure_note : str
        Why figures are missing or fewer than the channels, when they are (shown as given).
    charts : InteractiveCharts, optional
        The interactive σ–τ charts (:func:`sigmatau.report.interactive.report_charts`):
        each fragment under its figure, the note atop the figures, the script at the
        end of the page. None: static figures only.
    """
    a = analysis
    title = f"sigmatau report — {Path(a.log.source.path).name}"
    stamp = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    nav = " · ".join(f'<a href="#{k}">{v}</a>' for k, v in
                     (("overview", "overview"), ("input", "input"), ("checks", "data checks"), ("model", "noise model"),
                      ("kalibr", "Kalibr"), ("figures", "figures"), ("tables", "statistics"),
                      ("settings", "settings")))
    settings = json.dumps(a.settings, indent=1, ensure_ascii=False)
    parts = [
        "<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        f"<title>{_e(title)}</title><style>{_CSS}</style></head><body>",
        f"<h1>{_e(title)}</h1>",
        f'<p class="muted">sigmatau {_e(a.version)}, {stamp}; analysis took {a.seconds:.1f} s. {nav}</p>',
        _overview_section(a), _input_section(a), _checks_section(a), _model_section(a), _kalibr_section(a, yaml_text),
        _figures_section(figures, folder, figure_note, charts), _tables_section(a),
        f'<h2 id="settings">Settings</h2><pre>{_e(settings)}</pre>',
        # The charts' library and drawing code, after everything they draw into.
        getattr(charts, "script", "") or "",
        "</body></html>",
    ]
    return "\n".join(parts) + "\n"
