"""The live view of ``sigmatau watch``: a snapshot of plain data, its terminal text and a local web page.

* :func:`snapshot` turns what the watcher has — per channel its :class:`~sigmatau.core.result.StabilityResult`
  by statistic, its IMU :class:`~sigmatau.imu.NoiseModel` and the recording advice — into one
  JSON-ready dictionary (NaN as null); :class:`LiveState` holds the latest one for the server.
* :func:`terminal_lines` (a table redrawn on a terminal) and :func:`status_line` (one plain line,
  for a log file) render it as text, every name escaped for the terminal (:func:`printable`);
  :class:`NoticeLimiter` keeps the notices (gaps, jitter, disorder, rotation …) to one line each,
  at most one line per kind every few seconds, the rest counted.
* :class:`LiveServer` serves :data:`PAGE` — one self-contained HTML page, no external URL, that
  polls ``data.json`` every few seconds and draws the σ–τ curves with their interval bands, the
  fitted model and the model table — with :mod:`http.server` in a thread, bound to 127.0.0.1
  only. The page puts every value from the data into the document as text (``textContent``,
  SVG attributes set to numbers), never as markup, and its Content-Security-Policy allows only
  its own inline script and style (by hash) and requests to itself; requests whose ``Host`` is
  not this server's address are refused (a web page elsewhere cannot read it through DNS
  rebinding).
* :func:`staging_folder` makes the marked temporary folder beside the output directory where the
  watcher keeps the record while it runs (removed by a later run if this one is killed, as the
  staging folders of :func:`~sigmatau.report.directory.write_directory` are).

Layer: :mod:`sigmatau.report`; it takes plain data and imports nothing of the live inputs.
"""

from __future__ import annotations

import base64
import hashlib
import json
import math
import tempfile
import threading
import time
from collections import deque
from dataclasses import dataclass, field
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Any, Mapping, Optional, Sequence

from ..core.result import json_ready
from .directory import _mark
from .formats import printable

__all__ = ["LiveChannel", "snapshot", "LiveState", "LiveServer", "NoticeLimiter", "terminal_lines", "status_line",
           "staging_folder", "PAGE", "TERMS_SHOWN"]

#: The IMU terms in the terminal table (the page shows all five and the Gauss–Markov term).
TERMS_SHOWN = ("N", "B", "K")
_TERMS = ("Q", "N", "B", "K", "R")


@dataclass
class LiveChannel:
    """One channel of the live view: plain data only.

    Attributes
    ----------
    name, group, unit : str
    results : mapping of str to StabilityResult
        The statistics computed so far, by name.
    model : NoiseModel or None
        The IMU model of the channel (gyro and accel channels with a known unit).
    advice : str
        The recording advice ("N known to ±x %, …"), empty when there is none.
    note : str
        Why something is missing (too few samples, no model for this unit …).
    advice_detail : str
        The advice in full (several lines), shown on the page.
    """

    name: str
    group: str
    unit: str
    results: Mapping[str, Any] = field(default_factory=dict)
    model: Any = None
    advice: str = ""
    note: str = ""
    advice_detail: str = ""


def _pretty(unit: str) -> str:
    from ..imu.units import pretty

    return pretty(unit) if unit else ""


def _curve(r: Any) -> dict:
    return {"tau": r.taus, "dev": r.dev, "low": r.ci_low if r.ci_low is not None else r.dev,
            "high": r.ci_high if r.ci_high is not None else r.dev, "n": r.n,
            "alpha": r.alpha if r.alpha is not None else [None] * len(r)}


def _term(p: Any) -> dict:
    from ..pipeline.results import format_parameter

    return {"name": p.name, "text": format_parameter(p), "resolved": bool(p.resolved), "value": p.value,
            "low": p.low, "high": p.high, "unit": _pretty(p.unit)}


def _model(model: Any) -> Optional[dict]:
    if model is None:
        return None
    taus = model.result.taus
    out = {"terms": [_term(getattr(model, t)) for t in _TERMS], "curve": {"tau": taus, "dev": model.deviation(taus)},
           "gauss_markov": model.gauss_markov.format(3) if model.gauss_markov is not None else "",
           "flags": [str(f) for f in model.flags][:8]}
    return out


def snapshot(channels: Sequence[LiveChannel], *, source: str, status: str, samples: int, rate: Optional[float],
             timing: Optional[Mapping[str, Any]] = None, notices: Sequence[Mapping[str, Any]] = (),
             elapsed: float = 0.0, computed_at: Optional[int] = None, live_bytes: int = 0) -> dict:
    """Everything the live view shows, JSON-ready (NaN and inf as None).

    Parameters
    ----------
    channels : sequence of LiveChannel
    source : str
        The watched source as named on the command line.
    status : str
        ``running``, ``finishing``, ``finished`` or a sentence saying why the run stopped.
    samples : int
        Samples received per channel (on the time grid).
    rate : float or None
        Sample rate in Hz (None before the layout is known).
    timing : mapping, optional
        Counts and jitter of the timestamps.
    notices : sequence of mapping
        The latest notices (``kind``, ``text``, ``time``).
    elapsed : float
        Seconds since the watcher started.
    computed_at : int, optional
        The samples the statistics were computed on (they lag the samples received).
    live_bytes : int
        Memory held by the live statistics.
    """
    chans = [{"name": c.name, "group": c.group, "unit": _pretty(c.unit),
              "statistics": {k: _curve(r) for k, r in c.results.items()}, "model": _model(c.model),
              "advice": c.advice, "advice_detail": c.advice_detail or c.advice, "note": c.note} for c in channels]
    duration = samples / rate if rate else 0.0
    return json_ready({"source": source, "status": status, "samples": samples, "rate": rate, "duration": duration,
                       "computed_at": samples if computed_at is None else computed_at, "elapsed": elapsed,
                       "timing": dict(timing or {}), "notices": list(notices), "channels": chans,
                       "live_bytes": live_bytes, "updated": time.time()})


class LiveState:
    """The latest snapshot as JSON bytes, shared between the watcher and the server's threads."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._data = b"{}"
        self.title = "sigmatau watch"

    def publish(self, snap: Mapping[str, Any]) -> None:
        data = json.dumps(snap, allow_nan=False, ensure_ascii=True, separators=(",", ":")).encode("ascii")
        with self._lock:
            self._data = data

    def data(self) -> bytes:
        with self._lock:
            return self._data


class NoticeLimiter:
    """Notices as lines for the terminal: one line per kind at most every ``interval`` seconds, the
    others counted and summed up in the next line of that kind; the latest kept for the page."""

    def __init__(self, interval: float = 10.0, keep: int = 50, clock: Any = time.monotonic) -> None:
        self.interval = interval
        self.clock = clock
        self.recent: deque = deque(maxlen=keep)
        self._last: dict[str, float] = {}
        self._held: dict[str, tuple[int, str]] = {}

    def add(self, kind: str, text: str) -> list[str]:
        """Lines to print now for this notice (none while its kind is held back)."""
        now = self.clock()
        self.recent.append({"kind": kind, "text": text, "time": time.time()})
        if now - self._last.get(kind, -math.inf) < self.interval:
            n, _ = self._held.get(kind, (0, ""))
            self._held[kind] = (n + 1, text)
            return []
        self._last[kind] = now
        lines = self.flush(kind)
        return lines + [text]

    def flush(self, only: Optional[str] = None, *, force: bool = False) -> list[str]:
        """Summary lines of the notices held back whose kind may speak again (all with ``force``)."""
        now = self.clock()
        lines = []
        for kind in [only] if only is not None else list(self._held):
            n, text = self._held.get(kind, (0, ""))
            if n and (force or only is not None or now - self._last.get(kind, -math.inf) >= self.interval):
                lines.append(f"{n} more {kind} notice(s) since the last one shown; the latest: {text}")
                del self._held[kind]
                self._last[kind] = now
        return lines

    def latest(self) -> list[dict]:
        return list(self.recent)[::-1][:20]


def _cell(term: Mapping[str, Any]) -> str:
    """A term for the terminal: ``value ±x %``, ``< bound`` or ``–``."""
    v, lo, hi = term.get("value"), term.get("low"), term.get("high")
    if term.get("resolved") and v:
        half = 100.0 * (hi - lo) / (2.0 * v) if hi is not None and lo is not None else float("nan")
        return f"{v:.3g} ±{half:.2g} % {term['unit']}"
    return f"< {hi:.2g} {term['unit']}" if hi is not None else "–"


def _duration(s: float) -> str:
    s = int(s)
    return f"{s // 3600:d}:{s % 3600 // 60:02d}:{s % 60:02d}"


def _headline(snap: Mapping[str, Any]) -> str:
    t = snap.get("timing") or {}
    rate = snap.get("rate")
    parts = [f"{snap['samples']:,} samples", _duration(snap.get("duration") or 0.0)]
    if rate:
        parts.append(f"{rate:.6g} Hz")
    if t:
        jit = t.get("jitter_rms")
        parts.append(f"gaps {t.get('gaps', 0)} ({t.get('missing', 0)} missing), backwards {t.get('out_of_order', 0)},"
                     f" repeated {t.get('duplicates', 0)}" + (f", jitter rms {jit:.2g} s" if jit else ""))
    return f"{snap['source']} [{snap['status']}]: " + ", ".join(parts)


def terminal_lines(snap: Mapping[str, Any], width: int = 100) -> list[str]:
    """The live table for a terminal: a headline, then per channel N, B, K and the advice; every
    line escaped (:func:`printable`) and cut to ``width`` characters."""
    rows = [_headline(snap)]
    chans = snap.get("channels") or []
    if chans:
        name_w = min(max(len(printable(c["name"])) for c in chans), 24)
        rows.append(f"{'channel':<{name_w}}  " + "  ".join(f"{t:<28}" for t in TERMS_SHOWN))
    for c in chans:
        name = printable(c["name"])[:name_w]
        model = c.get("model")
        if model:
            terms = {t["name"]: t for t in model["terms"]}
            cells = [_cell(terms[t]) for t in TERMS_SHOWN]
            rows.append(f"{name:<{name_w}}  " + "  ".join(f"{x:<28}" for x in cells))
        else:
            stats = ", ".join(c.get("statistics") or {}) or "no statistic yet"
            rows.append(f"{name:<{name_w}}  {stats}" + (f" ({c['note']})" if c.get("note") else ""))
        if c.get("advice"):
            rows.append(f"{'':<{name_w}}  {c['advice']}")
    return [_cut(printable(r), width - 1) for r in rows]  # a full-width line would wrap on some terminals


def _cut(line: str, width: int) -> str:
    return line if len(line) <= width else line[:max(width - 1, 1)] + "…"


def status_line(snap: Mapping[str, Any]) -> str:
    """One plain line of the live state (not a terminal): the headline and each channel's N, B, K."""
    parts = [_headline(snap)]
    for c in snap.get("channels") or []:
        model = c.get("model")
        if model:
            terms = {t["name"]: t for t in model["terms"]}
            parts.append(f"{c['name']}: " + ", ".join(f"{t} {_cell(terms[t])}" for t in TERMS_SHOWN))
    return printable("; ".join(parts))


def staging_folder(out_dir: Path) -> Path:
    """A new temporary folder beside ``out_dir`` for the record of a run, marked with this process
    (``.OUT.partial-*``): a later run removes it once this process is gone."""
    target = Path(out_dir).resolve()
    folder = Path(tempfile.mkdtemp(prefix=f".{target.name}.partial-", dir=target.parent))
    _mark(folder)
    return folder


# ------------------------------------------------------------------------------------------- page

_STYLE = """
body{font-family:system-ui,-apple-system,"Segoe UI",Roboto,Helvetica,Arial,sans-serif;margin:0 auto;max-width:1200px;
padding:0 1.2em 2em;color:#1d1d1f;line-height:1.4}h1{font-size:1.4em;margin:.8em 0 .2em}
h2{font-size:1.1em;margin:1.4em 0 .3em;border-bottom:1px solid #ccc}.muted{color:#666}.warn{color:#a00}
table{border-collapse:collapse;font-size:.85em;margin:.4em 0}th,td{border:1px solid #d0d0d0;padding:.2em .45em;
text-align:left;vertical-align:top}th{background:#f2f2f2}svg{background:#fff;border:1px solid #e3e3e3}
.legend span{display:inline-block;margin-right:1.2em;font-size:.85em}.sw{display:inline-block;width:1.6em;height:.6em;
margin-right:.3em;vertical-align:middle}ul.notices{font-size:.85em;max-height:12em;overflow-y:auto}
"""

_SCRIPT = r"""
"use strict";
const NS = "http://www.w3.org/2000/svg";
const COLORS = ["#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#17becf"];
let statistic = "oadev";
function E(tag, text, cls) {
  const e = document.createElement(tag);
  if (text !== undefined && text !== null) e.textContent = String(text);
  if (cls) e.className = cls;
  return e;
}
function S(tag, attrs) {
  const e = document.createElementNS(NS, tag);
  for (const k in attrs) e.setAttribute(k, String(attrs[k]));
  return e;
}
function fmt(v, d) { return (v === null || v === undefined || !isFinite(v)) ? "–" : Number(v).toPrecision(d || 4); }
function hms(s) {
  s = Math.floor(s || 0);
  const h = Math.floor(s / 3600), m = Math.floor(s % 3600 / 60), r = s % 60;
  return h + ":" + String(m).padStart(2, "0") + ":" + String(r).padStart(2, "0");
}
function points(tau, dev) {
  const out = [];
  for (let i = 0; i < tau.length; i++) {
    if (tau[i] > 0 && dev[i] > 0 && isFinite(tau[i]) && isFinite(dev[i])) {
      out.push([Math.log10(tau[i]), Math.log10(dev[i])]);
    }
  }
  return out;
}
function plot(chans) {
  const W = 720, H = 420, L = 72, R = 12, T = 12, B = 44;
  const series = [];
  chans.forEach((c, k) => {
    const s = (c.statistics || {})[statistic];
    const color = COLORS[k % COLORS.length];
    if (s) {
      series.push({color: color, line: points(s.tau, s.dev), high: points(s.tau, s.high), low: points(s.tau, s.low)});
    }
    if (c.model && statistic === "oadev") {
      series.push({color: color, line: points(c.model.curve.tau, c.model.curve.dev), dash: true});
    }
  });
  const all = [];
  series.forEach(s => { all.push(...s.line); if (s.high) all.push(...s.high, ...s.low); });
  const svg = S("svg", {viewBox: "0 0 " + W + " " + H, width: W, height: H, role: "img"});
  if (!all.length) {
    const t = S("text", {x: L, y: H / 2});
    t.textContent = "no " + statistic + " yet";
    svg.appendChild(t);
    return svg;
  }
  let x0 = Math.floor(Math.min(...all.map(p => p[0]))), x1 = Math.ceil(Math.max(...all.map(p => p[0])));
  let y0 = Math.floor(Math.min(...all.map(p => p[1]))), y1 = Math.ceil(Math.max(...all.map(p => p[1])));
  if (x1 <= x0) x1 = x0 + 1;
  if (y1 <= y0) y1 = y0 + 1;
  const X = v => L + (v - x0) / (x1 - x0) * (W - L - R), Y = v => H - B - (v - y0) / (y1 - y0) * (H - T - B);
  for (let d = x0; d <= x1; d++) {
    svg.appendChild(S("line", {x1: X(d), x2: X(d), y1: T, y2: H - B, stroke: "#e6e6e6"}));
    const t = S("text", {x: X(d), y: H - B + 16, "text-anchor": "middle", "font-size": 11});
    t.textContent = "1e" + d;
    svg.appendChild(t);
  }
  for (let d = y0; d <= y1; d++) {
    svg.appendChild(S("line", {x1: L, x2: W - R, y1: Y(d), y2: Y(d), stroke: "#e6e6e6"}));
    const t = S("text", {x: L - 6, y: Y(d) + 4, "text-anchor": "end", "font-size": 11});
    t.textContent = "1e" + d;
    svg.appendChild(t);
  }
  const xl = S("text", {x: (L + W - R) / 2, y: H - 8, "text-anchor": "middle", "font-size": 12});
  xl.textContent = "τ [s]";
  svg.appendChild(xl);
  const pts = a => a.map(p => X(p[0]).toFixed(1) + "," + Y(p[1]).toFixed(1)).join(" ");
  series.forEach(s => {
    if (s.high && s.high.length === s.low.length && s.high.length > 1) {
      const band = pts(s.high.concat(s.low.slice().reverse()));
      svg.appendChild(S("polygon", {points: band, fill: s.color, "fill-opacity": 0.15, stroke: "none"}));
    }
    const attrs = {points: pts(s.line), fill: "none", stroke: s.color, "stroke-width": s.dash ? 1.2 : 1.8};
    if (s.dash) attrs["stroke-dasharray"] = "5 4";
    svg.appendChild(S("polyline", attrs));
  });
  return svg;
}
function render(d) {
  const root = document.getElementById("live");
  root.replaceChildren();
  document.title = "sigmatau watch: " + d.source;
  const t = d.timing || {};
  root.appendChild(E("h1", "sigmatau watch: " + d.source));
  let line = d.status + " — " + Number(d.samples || 0).toLocaleString() + " samples, " + hms(d.duration);
  if (d.rate) line += " at " + fmt(d.rate, 6) + " Hz";
  if (t.rows !== undefined) {
    line += "; gaps " + t.gaps + " (" + t.missing + " samples missing), backwards " + t.out_of_order
      + ", repeated " + t.duplicates + ", jitter rms " + fmt(t.jitter_rms, 2) + " s";
  }
  root.appendChild(E("p", line, "muted"));
  const stats = new Set();
  (d.channels || []).forEach(c => Object.keys(c.statistics || {}).forEach(k => stats.add(k)));
  if (stats.size) {
    const p = E("p", "statistic: ");
    [...stats].forEach(k => {
      const b = E("button", k);
      b.disabled = (k === statistic);
      b.addEventListener("click", () => { statistic = k; render(d); });
      p.appendChild(b);
    });
    root.appendChild(p);
  }
  const groups = {};
  (d.channels || []).forEach(c => { (groups[c.group] = groups[c.group] || []).push(c); });
  for (const g in groups) {
    const chans = groups[g];
    root.appendChild(E("h2", g + ": " + statistic + (statistic === "oadev" ? " with the fitted model (dashed)" : "")));
    root.appendChild(plot(chans));
    const leg = E("div", null, "legend");
    chans.forEach((c, k) => {
      const s = E("span"); const sw = E("span", null, "sw"); sw.style.background = COLORS[k % COLORS.length];
      s.appendChild(sw); s.appendChild(document.createTextNode(c.name + (c.unit ? " [" + c.unit + "]" : "")));
      leg.appendChild(s);
    });
    root.appendChild(leg);
  }
  root.appendChild(E("h2", "IMU noise model (" + (d.computed_at || 0).toLocaleString() + " samples)"));
  const table = E("table"), head = E("tr");
  ["channel", "Q", "N", "B", "K", "R", "Gauss–Markov", "advice"].forEach(h => head.appendChild(E("th", h)));
  table.appendChild(head);
  (d.channels || []).forEach(c => {
    const tr = E("tr");
    tr.appendChild(E("td", c.name));
    if (c.model) {
      c.model.terms.forEach(term => tr.appendChild(E("td", term.text, term.resolved ? "" : "muted")));
      tr.appendChild(E("td", c.model.gauss_markov || "–"));
    } else {
      const td = E("td", c.note || "no model", "muted"); td.colSpan = 6; tr.appendChild(td);
    }
    const adv = E("td", c.advice || "");
    if (c.advice_detail) adv.title = c.advice_detail;
    tr.appendChild(adv);
    table.appendChild(tr);
  });
  root.appendChild(table);
  if ((d.notices || []).length) {
    root.appendChild(E("h2", "Notices"));
    const ul = E("ul", null, "notices");
    d.notices.forEach(n => {
      ul.appendChild(E("li", new Date(n.time * 1000).toLocaleTimeString() + " " + n.kind + ": " + n.text));
    });
    root.appendChild(ul);
  }
}
async function poll() {
  try {
    const r = await fetch("data.json", {cache: "no-store"});
    if (!r.ok) throw new Error(String(r.status));
    render(await r.json());
    document.getElementById("conn").textContent = "";
  } catch (e) {
    document.getElementById("conn").textContent =
      "The watcher does not answer (the run has ended?); the page shows the last data.";
  }
}
poll();
setInterval(poll, REFRESH_MS);
"""


def _page(refresh_ms: int) -> tuple[bytes, str]:
    script = _SCRIPT.replace("REFRESH_MS", str(int(refresh_ms)))

    def digest(text: str) -> str:
        return "'sha256-" + base64.b64encode(hashlib.sha256(text.encode("utf-8")).digest()).decode("ascii") + "'"

    csp = (f"default-src 'none'; script-src {digest(script)}; style-src {digest(_STYLE)}; connect-src 'self';"
           " img-src 'none'; base-uri 'none'; form-action 'none'; frame-ancestors 'none'")
    body = (f'<!DOCTYPE html><html lang="en"><head><meta charset="utf-8"><title>sigmatau watch</title>'
            f'<meta name="viewport" content="width=device-width, initial-scale=1"><style>{_STYLE}</style></head>'
            f'<body><p id="conn" class="warn"></p><div id="live"><p>waiting for data…</p></div>'
            f'<script>{script}</script></body></html>')
    return body.encode("utf-8"), csp


#: The page served at ``/`` (and its Content-Security-Policy), refreshing every 3 s.
PAGE, _CSP = _page(3000)


class _Handler(BaseHTTPRequestHandler):
    server_version = "sigmatau-watch"
    sys_version = ""
    timeout = 10  # a client that sends nothing does not hold a thread for ever
    state: LiveState
    page: bytes
    csp: str

    def log_message(self, format: str, *args: Any) -> None:  # the terminal belongs to the live table
        pass

    def _host_ok(self) -> bool:
        port = self.server.server_address[1]
        return (self.headers.get("Host") or "").lower() in (f"127.0.0.1:{port}", f"localhost:{port}")

    def _send(self, code: int, body: bytes, ctype: str, head: bool = False) -> None:
        self.send_response(code)
        self.send_header("Content-Type", ctype)
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Cache-Control", "no-store")
        self.send_header("X-Content-Type-Options", "nosniff")
        self.send_header("Referrer-Policy", "no-referrer")
        self.send_header("Content-Security-Policy", self.csp)
        self.end_headers()
        if not head:
            self.wfile.write(body)

    def _answer(self, head: bool) -> None:
        if not self._host_ok():
            self._send(403, b"forbidden: use http://127.0.0.1:PORT/\n", "text/plain; charset=utf-8", head)
            return
        path = self.path.split("?", 1)[0]
        if path in ("/", "/index.html"):
            self._send(200, self.page, "text/html; charset=utf-8", head)
        elif path == "/data.json":
            self._send(200, self.state.data(), "application/json", head)
        else:
            self._send(404, b"not found\n", "text/plain; charset=utf-8", head)

    def do_GET(self) -> None:  # noqa: N802 (http.server's naming)
        self._answer(False)

    def do_HEAD(self) -> None:  # noqa: N802
        self._answer(True)


class LiveServer:
    """The live page and its data on ``http://127.0.0.1:PORT/``, served from a thread.

    Parameters
    ----------
    state : LiveState
    port : int
        0 for any free port (:attr:`url` tells which).
    refresh : float
        Seconds between the page's requests for new data.
    """

    HOST = "127.0.0.1"

    def __init__(self, state: LiveState, port: int = 0, refresh: float = 3.0) -> None:
        page, csp = (PAGE, _CSP) if refresh == 3.0 else _page(int(refresh * 1000))
        handler = type("Handler", (_Handler,), {"state": state, "page": page, "csp": csp})
        self.httpd = ThreadingHTTPServer((self.HOST, port), handler)
        self.httpd.daemon_threads = True
        self.port = int(self.httpd.server_address[1])
        self.url = f"http://{self.HOST}:{self.port}/"
        self._thread = threading.Thread(target=self.httpd.serve_forever, kwargs={"poll_interval": 0.2},
                                        name="sigmatau-watch-http", daemon=True)
        self._thread.start()

    def close(self) -> None:
        self.httpd.shutdown()
        self.httpd.server_close()
        self._thread.join(timeout=2.0)
