"""One log, one Dask task: hash it, skip it when done, else read, analyse and write its outputs.

The task returns a small record (:func:`_record`), never an exception (a
failure becomes :func:`_error_record`). Its directory is written under a hidden
staging name and renamed into place (:func:`_publish`), so it exists only
complete and a task retried after a worker died keeps the one that got there
first.
"""

from __future__ import annotations

import json
import os
import shutil
import time
import uuid
import warnings
from pathlib import Path
from typing import Any, Mapping, Optional, Sequence

from ..._version import __version__
from ...errors import ParameterError, SigmaTauError
from ...pipeline.analysis import TERMS, json_ready
from .common import _RECORD, _SCHEMA, _one_line, _stem, _write_json


def _file_sha256(path: Path) -> tuple[str, int]:
    """``(SHA-256 hex digest, size)`` of a log file or bag directory (:func:`sigmatau.io.file_sha256`)."""
    from ...io import file_sha256

    return file_sha256(path)


def _error_kind(exc: BaseException) -> str:
    """``usage`` or ``data`` as ``sigmatau analyze`` would exit (2 or 1); ``internal`` for a bug."""
    from ...report.outputs import OutputExistsError

    if isinstance(exc, (ParameterError, OutputExistsError)):
        return "usage"
    if isinstance(exc, (SigmaTauError, OSError)):
        return "data"
    return "internal"


def _error_record(path: str, exc: BaseException, *, sha256: Optional[str] = None, size: Optional[int] = None,
                  seconds: float = 0.0) -> dict[str, Any]:
    """The record of a log that failed: the exception's class, kind and one-line message."""
    return {"schema": _SCHEMA, "status": "error", "path": path, "name": None, "sha256": sha256, "size": size,
            "error": {"type": type(exc).__name__, "kind": _error_kind(exc), "message": _one_line(exc)},
            "seconds": seconds, "version": __version__}


def _record(analysis: Any, *, path: str, sha256: str, size: int, name: str, token: str,
            warns: Sequence[str], seconds: float) -> dict[str, Any]:
    """The small summary of one analysis that the fleet summary is built from (SI units)."""
    log = analysis.log
    channels = []
    for ch in analysis.channels:
        m = ch.model
        terms = None
        if m is not None:
            terms = {}
            for t in TERMS:
                p = getattr(m, t).si()
                terms[t] = {"value": p.value if p.resolved else None, "low": p.low, "high": p.high,
                            "unit": p.unit, "resolved": bool(p.resolved), "method": p.method}
        channels.append({"name": ch.name, "group": ch.group, "unit": ch.unit, "n_samples": ch.n_samples,
                         "statistics": list(ch.results), "skipped": dict(ch.skipped), "terms": terms,
                         "model_note": ch.model_note,
                         "flags": [f._asdict() for f in m.flags] if m is not None else []})
    k = analysis.kalibr
    kalibr = None if k is None else {key: k[key] for key in (
        "gyroscope_noise_density", "gyroscope_random_walk", "accelerometer_noise_density",
        "accelerometer_random_walk", "bounds_used")}
    return json_ready({
        "schema": _SCHEMA, "status": "ok", "path": path, "name": name, "sha256": sha256, "size": size,
        "format": log.source.format, "topic": log.source.topic, "rate": log.rate, "samples": len(log),
        "duration_s": len(log) / log.rate, "data_type": log.data_type,
        "confidence": analysis.settings["confidence"], "channels": channels, "kalibr": kalibr,
        "kalibr_note": analysis.kalibr_note, "notes": list(analysis.notes),
        "warnings": list(dict.fromkeys([*warns, *analysis.warnings])), "settings_token": token,
        "seconds": seconds, "version": __version__,
    })


def _find_done(logs_dir: Path, sha256: str, token: str) -> Optional[Path]:
    """The finished directory of the content ``sha256`` made with the settings ``token``, if any
    (whatever the file was called); a result of other settings is not reused."""
    for d in logs_dir.glob(f"*-{sha256[:12]}"):
        try:
            rec = json.loads((d / _RECORD).read_text(encoding="utf-8"))
        except (OSError, ValueError):
            continue
        if rec.get("sha256") == sha256 and rec.get("settings_token") == token:
            return d
    return None


def _stale(final: Path, token: str) -> bool:
    """``final`` holds a finished result of other settings (to be replaced, not reused)."""
    try:
        rec = json.loads((final / _RECORD).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return False
    return rec.get("settings_token") != token


def _publish(staging: Path, final: Path, force: bool) -> bool:
    """Rename ``staging`` to ``final``; False when another attempt got there first (``staging`` removed)."""
    if final.exists() and (force or not (final / _RECORD).is_file()):
        trash = final.with_name(f".{final.name}.old-{uuid.uuid4().hex[:8]}")
        try:
            os.rename(final, trash)
        except FileNotFoundError:
            pass
        else:
            shutil.rmtree(trash, ignore_errors=True)
    try:
        os.rename(staging, final)  # atomic; refuses to replace a non-empty directory
        return True
    except OSError:
        if (final / _RECORD).is_file():
            shutil.rmtree(staging, ignore_errors=True)
            return False
        raise


def _analyse_one(path: str, logs_dir: str, read_kw: Mapping[str, Any], analysis_kw: Mapping[str, Any],
                 figures: Sequence[str], report: bool, force: bool, token: str,
                 exports: Sequence[str] = ("kalibr",)) -> dict[str, Any]:
    """One task: hash, skip when done, else read, analyse, write; a record, never an exception.

    Idempotent: run twice (a retry after a worker died, or two paths with the same
    content), one directory survives and both calls return its record.
    """
    from ... import io
    from ...pipeline.analysis import analyze_log
    from ...pipeline.prepare import Preparation
    from ...report.outputs import write_outputs

    t0 = time.perf_counter()
    folder = Path(logs_dir)
    sha: Optional[str] = None
    size: Optional[int] = None
    try:
        p = Path(path)
        if not p.exists():
            raise io.InputNotFoundError(f"{path}: no such file or directory")
        sha, size = _file_sha256(p)
        if not force:
            done = _find_done(folder, sha, token)
            if done is not None:
                rec = json.loads((done / _RECORD).read_text(encoding="utf-8"))
                return {**rec, "reused": True}
        name = f"{_stem(path)}-{sha[:12]}"
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            log = io.read(path, progress=False, **read_kw)
            kw = dict(analysis_kw)
            prep = Preparation(warmup=kw.pop("warmup", None), temperature=kw.pop("temperature", None))
            analysis = analyze_log(log, workers=1, prep=prep or None, **kw)
        warns = [f"{w.category.__name__}: {w.message}" for w in caught
                 if not w.category.__name__.startswith("Imu")]
        staging = folder / f".{name}.staging-{uuid.uuid4().hex[:8]}"
        write_outputs(analysis, staging, figures=list(figures), report=report, protect=[path], exports=exports)
        rec = _record(analysis, path=path, sha256=sha, size=size, name=name, token=token, warns=warns,
                      seconds=time.perf_counter() - t0)
        _write_json(staging / _RECORD, rec)
        if not _publish(staging, folder / name, force or _stale(folder / name, token)):
            rec = {**json.loads((folder / name / _RECORD).read_text(encoding="utf-8")), "reused": True}
        return rec
    except Exception as exc:  # every failure is a result: the other logs go on
        return _error_record(path, exc, sha256=sha, size=size, seconds=time.perf_counter() - t0)
