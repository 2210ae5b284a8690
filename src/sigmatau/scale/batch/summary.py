"""The fleet summary: rows per log × channel × term, their distribution, outliers and verdicts.

:class:`FleetSummary` is what :func:`~sigmatau.scale.batch.analyze_many`
returns; the tables here are the content of ``fleet.csv``, ``fleet_logs.csv``
and ``fleet.json`` (written by :mod:`.report`).
"""

from __future__ import annotations

import csv
import io as _io
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping, Sequence

from ..._version import __version__
from ...pipeline.analysis import IMU_GROUPS, TERMS, json_ready
from .common import OUTLIER_Z


@dataclass(frozen=True)
class FleetSummary:
    """What :func:`analyze_many` did and found.

    Attributes
    ----------
    out : Path
        The output directory.
    records : tuple of dict
        One per analysed log (each distinct content once), sorted by path:
        ``path``, ``name`` (its directory under ``out/logs``), ``sha256``,
        per channel the model terms in SI (``value``/``low``/``high``/
        ``resolved``), flags, warnings; ``reused`` when taken from an
        earlier run; ``verdict`` and ``outliers`` from the fleet summary.
    errors : tuple of dict
        One per log that failed: ``path`` and ``error`` (``type``, ``kind``
        "data"/"usage"/"internal", one-line ``message``).
    rows : tuple of dict
        One per log × channel × term (the rows of ``fleet.csv``).
    distribution : tuple of dict
        Per group and term: counts, median, spread, limit, failures, outliers.
    limits : dict
        The limits applied (:func:`load_limits`).
    computed, reused : int
        Logs analysed in this run, and taken from an earlier one.
    seconds : float
        Wall time of the run.
    files : tuple of Path
        Fleet files written.
    """

    out: Path
    records: tuple[dict, ...]
    errors: tuple[dict, ...]
    rows: tuple[dict, ...]
    distribution: tuple[dict, ...]
    limits: Mapping[str, Any]
    computed: int
    reused: int
    seconds: float
    files: tuple[Path, ...] = ()

    @property
    def ok(self) -> bool:
        """True when every log was analysed."""
        return not self.errors

    def __repr__(self) -> str:
        return (f"FleetSummary(out={str(self.out)!r}, logs={len(self.records)}, errors={len(self.errors)},"
                f" computed={self.computed}, reused={self.reused}, seconds={self.seconds:.1f})")

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary (the content of ``fleet.json``)."""
        return json_ready({
            "tool": {"name": "sigmatau", "version": __version__},
            "logs": len(self.records) + len(self.errors), "analysed": len(self.records), "failed": len(self.errors),
            "computed": self.computed, "reused": self.reused, "seconds": self.seconds,
            "limits": self.limits, "outlier_rule": _OUTLIER_RULE, "limit_rule": _LIMIT_RULE,
            "distribution": list(self.distribution), "records": list(self.records), "errors": list(self.errors),
        })

    def summary(self) -> str:
        """A few lines for the terminal: counts, verdicts, outliers, errors."""
        n = len(self.records) + len(self.errors)
        lines = [f"{n} log(s): {len(self.records)} analysed ({self.computed} now, {self.reused} done before),"
                 f" {len(self.errors)} failed, in {self.seconds:.1f} s"]
        if self.limits:
            fails = [r for r in self.records if r.get("verdict") == "fail"]
            lines.append(f"limits: {len(self.records) - len(fails)} pass, {len(fails)} fail")
            lines += [f"  FAIL {r['path']}: {'; '.join(r['limit_failures'])}" for r in fails]
        out = [r for r in self.records if r.get("outliers")]
        if out:
            lines.append(f"outliers against the fleet (|z| > {OUTLIER_Z:g}): {len(out)} log(s)")
            lines += [f"  {r['path']}: {', '.join(r['outliers'])}" for r in out]
        for e in self.errors:
            lines.append(f"  ERROR {e['path']}: {e['error']['type']}: {e['error']['message']}")
        return "\n".join(lines)


_OUTLIER_RULE = (f"per group (gyro, accel; axes pooled) and term, over the resolved values of every log: robust"
                 f" z = 0.6745·(log10 v − median)/MAD of log10 v; an outlier has |z| > {OUTLIER_Z:g} and an"
                 " interval [low, high] that excludes the fleet median (needs ≥ 5 resolved values)")
_LIMIT_RULE = ("a term passes when its estimate is ≤ the limit; a term the record does not resolve passes only when"
               " its upper bound is ≤ the limit; a log passes when every limited term of every channel passes,"
               " and is 'untested' when it has no model to test")


def _rows(records: Sequence[dict], limits: Mapping[str, Any]) -> list[dict[str, Any]]:
    """One row per record × channel × term (SI), with the limit and its verdict; z and outlier filled in later."""
    rows = []
    for rec in records:
        for ch in rec["channels"]:
            if not ch.get("terms"):
                continue
            for t in TERMS:
                p = ch["terms"][t]
                lim = limits.get(ch["group"], {}).get(t)
                verdict = ""
                if lim is not None:
                    x = p["value"] if p["resolved"] else p["high"]
                    verdict = "pass" if x is not None and x <= lim["max"] else "fail"
                rows.append({"path": rec["path"], "log": rec["name"], "sha256": rec["sha256"],
                             "channel": ch["name"], "group": ch["group"], "term": t, "unit": p["unit"],
                             "value": p["value"], "low": p["low"], "high": p["high"], "resolved": p["resolved"],
                             "method": p["method"], "z": None, "outlier": False,
                             "limit": lim["max"] if lim else None, "verdict": verdict})
    return rows


def _outliers_and_distribution(rows: list[dict], limits: Mapping[str, Any], z_max: float) -> list[dict]:
    """Mark the outliers of every group and term in ``rows`` (robust z of log10 values); their distribution."""
    import numpy as np

    dist = []
    keys = sorted({(r["group"], r["term"]) for r in rows}, key=lambda k: (IMU_GROUPS.index(k[0])
                                                                           if k[0] in IMU_GROUPS else 9,
                                                                           TERMS.index(k[1])))
    for group, term in keys:
        sel = [r for r in rows if r["group"] == group and r["term"] == term]
        res = [r for r in sel if r["resolved"] and r["value"] is not None and r["value"] > 0]
        lx = np.log10([r["value"] for r in res]) if res else np.array([])
        med = float(np.median(lx)) if lx.size else math.nan
        mad = float(np.median(np.abs(lx - med))) if lx.size else math.nan
        n_out = 0
        if lx.size >= 5 and mad > 0:
            for r, v in zip(res, lx):
                r["z"] = 0.6745 * (v - med) / mad
                excludes = not (r["low"] <= 10**med <= r["high"])
                r["outlier"] = bool(abs(r["z"]) > z_max and excludes)
                n_out += r["outlier"]
        lim = limits.get(group, {}).get(term)
        values = [r["value"] for r in res]
        dist.append({"group": group, "term": term, "unit": sel[0]["unit"], "channels": len(sel),
                     "logs": len({r["sha256"] for r in sel}), "resolved": len(res), "bounds": len(sel) - len(res),
                     "median": 10**med if lx.size else None, "min": min(values) if values else None,
                     "max": max(values) if values else None,
                     "p05": float(10 ** np.percentile(lx, 5)) if lx.size else None,
                     "p95": float(10 ** np.percentile(lx, 95)) if lx.size else None,
                     "spread_factor": 10 ** (1.4826 * mad) if lx.size and math.isfinite(mad) else None,
                     "outliers": n_out, "limit": lim["max"] if lim else None,
                     "fail": sum(r["verdict"] == "fail" for r in sel),
                     "pass": sum(r["verdict"] == "pass" for r in sel)})
    return dist


def _annotate(records: list[dict], rows: list[dict], limits: Mapping[str, Any]) -> None:
    """Per log: verdict against the limits, the limit failures and the outlier terms."""
    by_log: dict[str, list[dict]] = {}
    for r in rows:
        by_log.setdefault(r["sha256"], []).append(r)
    for rec in records:
        mine = by_log.get(rec["sha256"], [])
        rec["outliers"] = [f"{r['channel']}.{r['term']} (z {r['z']:+.1f})" for r in mine if r["outlier"]]
        rec["limit_failures"] = [
            f"{r['channel']}.{r['term']} {'= ' + format(r['value'], '.4g') if r['resolved'] else '< ' + format(r['high'] or math.inf, '.4g')}"
            f" > {r['limit']:.4g} {r['unit']}" for r in mine if r["verdict"] == "fail"]
        if limits:
            tested = [r for r in mine if r["verdict"]]
            rec["verdict"] = "fail" if rec["limit_failures"] else ("pass" if tested else "untested")
        else:
            rec["verdict"] = ""


def _csv_text(header: Sequence[str], rows: Sequence[Mapping[str, Any]]) -> str:
    """CSV text whose cells a spreadsheet never runs as a formula (:func:`sigmatau.outputs.csv_cell`:
    a log named ``-2+3.csv`` or an error message starting with ``=`` is shown as text)."""
    from ...report.outputs import csv_cell

    buf = _io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(header)
    for r in rows:
        w.writerow([csv_cell(r.get(h)) for h in header])
    return buf.getvalue()


_ROW_COLUMNS = ("path", "log", "sha256", "channel", "group", "term", "unit", "value", "low", "high", "resolved",
                "method", "z", "outlier", "limit", "verdict")
_LOG_COLUMNS = ("path", "status", "log", "sha256", "size", "format", "rate", "duration_s", "verdict", "outliers",
                "limit_failures", "warnings", "error_type", "error_kind", "error_message", "seconds", "reused")


def _log_rows(records: Sequence[dict], errors: Sequence[dict]) -> list[dict]:
    """The rows of ``fleet_logs.csv``: one per log, analysed or failed, sorted by path."""
    out = []
    for r in [*records, *errors]:
        e = r.get("error") or {}
        out.append({**{k: r.get(k) for k in _LOG_COLUMNS}, "log": r.get("name"),
                    "outliers": "; ".join(r.get("outliers", [])), "limit_failures": "; ".join(r.get("limit_failures", [])),
                    "warnings": len(r.get("warnings", [])), "error_type": e.get("type"), "error_kind": e.get("kind"),
                    "error_message": e.get("message"), "reused": bool(r.get("reused"))})
    return sorted(out, key=lambda r: r["path"])


def _tally(files: Sequence[str], results: Mapping[str, dict[str, Any]]) -> tuple[list[dict], list[dict], int, int]:
    """The records of a run sorted into what the fleet summary counts.

    Parameters
    ----------
    files : sequence of str
        The logs of the run, in order.
    results : mapping
        Path → record, for every path of ``files``.

    Returns
    -------
    ok : list of dict
        One record per distinct content (the same content under another path is
        counted once, its other paths listed in ``same_content``).
    errors : list of dict
        The error records, in the order of ``files``.
    computed, reused : int
        Records of a successful analysis made in this run, and taken from an earlier one.
    """
    ok: dict[str, dict] = {}
    errors = []
    for p in files:
        rec = results[p]
        if rec["status"] != "ok":
            errors.append(rec)
        elif rec["sha256"] in ok:  # the same content under another path: counted once
            ok[rec["sha256"]].setdefault("same_content", []).append(p)
        else:
            ok[rec["sha256"]] = dict(rec)
    computed = sum(1 for r in results.values() if r["status"] == "ok" and not r.get("reused"))
    reused = sum(1 for r in results.values() if r["status"] == "ok" and r.get("reused"))
    return list(ok.values()), errors, computed, reused
