"""Many logs at once on a Dask cluster: one task per log, per-log outputs and a fleet summary.

:func:`analyze_many` runs the analysis of ``sigmatau analyze``
(:func:`sigmatau.io.read`, :func:`sigmatau.analysis.analyze_log`,
:func:`sigmatau.outputs.write_outputs`) on every log, one task per log, on a
`dask.distributed <https://distributed.dask.org>`_ cluster: a
``LocalCluster`` of single-threaded worker processes by default, or an
existing cluster given by its scheduler address. Dask is the optional extra
``dask`` (``pip install "sigmatau[dask]"``); ``import sigmatau`` does not load it.

Layout of the output directory ``OUT``::

    OUT/batch.json            settings of the run (the same on every rerun)
    OUT/index.jsonl           a line per log as it finishes (append-only journal; one per
                              path, content hash and outcome, however often rerun)
    OUT/batch.lock            while a run writes: its host, PID, process start time, boot id
    OUT/logs/<stem>-<sha12>/  the outputs of one log (results.json, CSVs, figures,
                              report.html, imu.yaml) and record.json, its summary
    OUT/fleet.csv             one row per log × channel × term: value, interval, limit, outlier
    OUT/fleet_logs.csv        one row per log: status, verdict, outliers, error and reason
    OUT/fleet.json            all of it, with the distribution of every term
    OUT/fleet_hist.png, OUT/fleet_strip.png, OUT/fleet.html

Resuming: a log's directory is named after the SHA-256 of its content and
appears only complete (it is written under a hidden name and renamed into
place, record.json included), so a rerun of the same command skips every log
whose directory exists — whatever interrupted the previous run — and a task
retried after a worker died keeps the one directory that got there first.

On an existing cluster: the workers need sigmatau (with its ``dask`` extra)
and must see the logs and ``OUT`` under the same paths (a shared file
system); one thread per worker process suits this work (each task is one log)::

    dask scheduler                                             # prints tcp://10.0.0.5:8786
    dask worker tcp://10.0.0.5:8786 --nworkers 8 --nthreads 1  # on each machine
    sigmatau batch '/data/line3/*.csv' --out /data/line3-fleet --scheduler tcp://10.0.0.5:8786

or ``analyze_many(paths, out, client=distributed.Client("tcp://10.0.0.5:8786"))``.

Examples
--------
>>> from sigmatau.batch import analyze_many                            # doctest: +SKIP
>>> fleet = analyze_many(["line3/*.csv"], "fleet-out", workers=2, limits="lsm6dsl")  # doctest: +SKIP
>>> fleet.summary()                                                    # doctest: +SKIP
"""

from __future__ import annotations

import base64
import contextlib
import csv
import glob
import hashlib
import html
import io as _io
import json
import math
import os
import re
import shutil
import socket
import sys
import time
import uuid
import warnings
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Callable, Mapping, Optional, Sequence, Union

from .._version import __version__
from ..pipeline.analysis import DEFAULT_STATISTICS, IMU_GROUPS, TERMS, SI_TERM_UNITS, json_ready
from ..uncertainty.confidence import ONE_SIGMA
from ..errors import ParameterError, SigmaTauError, SigmaTauWarning

__all__ = [
    "analyze_many",
    "expand_patterns",
    "load_limits",
    "FleetSummary",
    "check_scheduler_address",
    "ClusterError",
    "OUTLIER_Z",
    "LIMIT_MARGIN",
    "CONNECT_TIMEOUT",
]

#: Robust z-score (0.6745·|x − median|/MAD on log10 values) beyond which a term is an
#: outlier of its fleet (Iglewicz & Hoaglin's 3.5).
OUTLIER_Z = 3.5

#: Factor applied to a datasheet preset's typical value to make it a limit: datasheets
#: give typical, not maximum, noise densities, so about half of good parts exceed them.
LIMIT_MARGIN = 1.5

#: Seconds allowed to reach an existing scheduler (``--scheduler``) before giving up: a
#: scheduler that answers does so in milliseconds, and a wrong address should not hang.
CONNECT_TIMEOUT = 10.0

_RECORD = "record.json"
_INDEX = "index.jsonl"
_SETTINGS = "batch.json"
_LOCK = "batch.lock"
LOGS_DIR = "logs"
_SCHEMA = 1
_HIST_TERMS = ("N", "B", "K")

PathLike = Union[str, "os.PathLike[str]"]


class ClusterError(SigmaTauError):
    """The Dask cluster could not be reached or started."""


def _distributed() -> Any:
    try:
        import distributed
    except ImportError:
        from ..io import MissingDependencyError

        raise MissingDependencyError(
            "batch analysis needs the optional packages dask and distributed, which are not installed;"
            ' install them with: pip install "sigmatau[dask]"'
        ) from None
    return distributed


# ------------------------------------------------------------------------- inputs


def _is_bag_dir(p: Path) -> bool:
    return p.is_dir() and (p / "metadata.yaml").is_file()


def expand_patterns(patterns: Sequence[PathLike], *, exclude: Optional[PathLike] = None) -> list[str]:
    """Absolute paths of the logs named by files, directories and glob patterns.

    Patterns are expanded by Python (``*``, ``?``, ``[…]`` and ``**`` for any
    depth), so they work the same on every shell, also when quoted. A ROS 2 bag
    directory (one holding ``metadata.yaml``) is one log; other directories a
    pattern matches are passed over, and a directory named literally is an error.
    Paths inside ``exclude`` (the output directory) are left out; duplicates
    are removed, the order is sorted.

    Raises
    ------
    ParameterError
        A pattern matches no log.
    """
    if isinstance(patterns, (str, os.PathLike)):
        patterns = [patterns]
    skip = Path(exclude).resolve() if exclude is not None else None
    found: dict[str, None] = {}
    for pat in patterns:
        text = os.fspath(pat)
        literal = not glob.has_magic(text)
        if literal:
            p = Path(text)
            if p.is_dir() and not _is_bag_dir(p):
                raise ParameterError(f"{text!r} is a directory, not a log (nor a ROS 2 bag); give files or a pattern"
                                     f" such as {os.path.join(text, '*.csv')!r}")
            # A missing literal path is kept: its task reports it like any unreadable log.
            matches = [text]
        else:
            matches = [m for m in sorted(glob.glob(text, recursive=True))
                       if Path(m).is_file() or _is_bag_dir(Path(m))]
            if not matches:
                raise ParameterError(f"pattern {text!r} matches no log")
        for m in matches:
            a = Path(os.path.abspath(m))
            if skip is not None and (a.resolve() == skip or skip in a.resolve().parents):
                continue
            found[str(a)] = None
    if not found:
        raise ParameterError("no log to analyse")
    return sorted(found)


def _stem(path: str) -> str:
    name = Path(path).name.split(".")[0] or "log"
    return "".join(c if c.isalnum() or c in "-_" else "_" for c in name)[:60]


def _file_sha256(path: Path) -> tuple[str, int]:
    from ..io import file_sha256

    return file_sha256(path)


# ------------------------------------------------------------------- one log (task)


def _error_kind(exc: BaseException) -> str:
    """``usage`` or ``data`` as ``sigmatau analyze`` would exit (2 or 1); ``internal`` for a bug."""
    from ..report.outputs import OutputExistsError

    if isinstance(exc, (ParameterError, OutputExistsError)):
        return "usage"
    if isinstance(exc, (SigmaTauError, OSError)):
        return "data"
    return "internal"


def _one_line(exc: BaseException) -> str:
    if isinstance(exc, OSError) and not isinstance(exc, SigmaTauError) and exc.filename:
        text = f"{exc.strerror or exc}: {exc.filename}"
    else:
        text = str(exc) or type(exc).__name__
    return text.strip().splitlines()[0] if text.strip() else type(exc).__name__


def _error_record(path: str, exc: BaseException, *, sha256: Optional[str] = None, size: Optional[int] = None,
                  seconds: float = 0.0) -> dict[str, Any]:
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


def _write_json(path: Path, data: Any, *, fsync: bool = True) -> None:
    tmp = path.with_name(f".{path.name}.{uuid.uuid4().hex[:8]}.tmp")
    with open(tmp, "w", encoding="utf-8", newline="") as fh:
        fh.write(json.dumps(data, indent=1, allow_nan=False, ensure_ascii=False) + "\n")
        fh.flush()
        if fsync:
            os.fsync(fh.fileno())
    os.replace(tmp, path)


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
                 figures: Sequence[str], report: bool, force: bool, token: str) -> dict[str, Any]:
    """One task: hash, skip when done, else read, analyse, write; a record, never an exception.

    Idempotent: run twice (a retry after a worker died, or two paths with the same
    content), one directory survives and both calls return its record.
    """
    from .. import io
    from ..pipeline.analysis import analyze_log
    from ..report.outputs import write_outputs

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
            analysis = analyze_log(log, workers=1, **analysis_kw)
        warns = [f"{w.category.__name__}: {w.message}" for w in caught
                 if not w.category.__name__.startswith("Imu")]
        staging = folder / f".{name}.staging-{uuid.uuid4().hex[:8]}"
        write_outputs(analysis, staging, figures=list(figures), report=report, protect=[path])
        rec = _record(analysis, path=path, sha256=sha, size=size, name=name, token=token, warns=warns,
                      seconds=time.perf_counter() - t0)
        _write_json(staging / _RECORD, rec)
        if not _publish(staging, folder / name, force or _stale(folder / name, token)):
            rec = {**json.loads((folder / name / _RECORD).read_text(encoding="utf-8")), "reused": True}
        return rec
    except Exception as exc:  # every failure is a result: the other logs go on
        return _error_record(path, exc, sha256=sha, size=size, seconds=time.perf_counter() - t0)


# ----------------------------------------------------------------------- settings


def _read_kwargs(read: Optional[Mapping[str, Any]]) -> dict[str, Any]:
    """``read`` checked against :func:`sigmatau.io.read` before anything is submitted."""
    from .. import io

    kw = dict(read or {})
    for bad in ("path", "progress"):
        if bad in kw:
            raise ParameterError(f"read option {bad!r} is set by the batch itself")
    io.check_read_options(**kw)  # raises ParameterError naming an unknown option or a bad value
    return kw


def _analysis_kwargs(statistics: Any, taus: Any, confidence: float, model: bool, axis_rule: str, inflate: float,
                     rostopic: str, datasheet: Any) -> dict[str, Any]:
    from ..pipeline.analysis import check_statistics, datasheet_reference

    if axis_rule not in ("max", "rms", "mean"):
        raise ParameterError(f"axis_rule={axis_rule!r} must be 'max', 'rms' or 'mean'")
    if isinstance(confidence, bool) or not isinstance(confidence, (int, float)) or not 0 < confidence < 1:
        raise ParameterError(f"confidence={confidence!r} must be a number between 0 and 1")
    if not isinstance(taus, str):
        import numpy as np

        taus = [float(t) for t in np.asarray(taus, dtype=float).ravel()]
    return {"statistics": list(check_statistics(statistics)), "taus": taus, "confidence": float(confidence),
            "model": bool(model), "axis_rule": axis_rule, "inflate": float(inflate), "rostopic": str(rostopic),
            "datasheet": {g: {t: list(v) for t, v in terms.items()}
                          for g, terms in datasheet_reference(datasheet).items()} or None}


def _check_settings(out: Path, settings: dict[str, Any], force: bool) -> str:
    """Record the settings in ``OUT/batch.json``; refuse to mix results of other settings."""
    token = hashlib.sha256(json.dumps(settings, sort_keys=True).encode()).hexdigest()[:16]
    path = out / _SETTINGS
    if path.is_file() and not force:
        try:
            old = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            old = {}
        if old.get("token") != token:
            was, now = old.get("settings", {}), settings
            diff = [k for k in sorted(set(was) | set(now)) if was.get(k) != now.get(k)]
            raise ParameterError(f"{str(out)!r} holds results of other settings (differing: {', '.join(diff)});"
                                 " use --force-rerun to recompute them all, or another --out")
    _write_json(path, {"token": token, "settings": settings})
    return token


class _Lock:
    """``OUT/batch.lock``: one run per output directory at a time; a stale lock is taken over.

    The lock is a JSON object naming its holder: ``host``, ``pid``, ``start`` (the
    process start time in clock ticks after boot, field 22 of ``/proc/<pid>/stat``,
    proc(5)) and ``boot_id`` (``/proc/sys/kernel/random/boot_id``), the last two
    None where the system has no ``/proc``. A PID alone cannot tell the holder from
    an unrelated process that was given the same PID later (after a reboot, or
    once PIDs wrap); the start time and boot id can. See :func:`_holder_alive`.
    """

    def __init__(self, out: Path) -> None:
        self.path = out / _LOCK
        self.held = False

    def __enter__(self) -> "_Lock":
        me = json.dumps({"host": socket.gethostname(), "pid": os.getpid(), "start": _start_ticks(os.getpid()),
                         "boot_id": _boot_id()})
        for _ in range(3):
            try:
                fd = os.open(self.path, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
            except FileExistsError:
                self._take_over_if_stale()
                continue
            with os.fdopen(fd, "w") as fh:
                fh.write(me)
            self.held = True
            return self
        raise ParameterError(f"cannot lock {str(self.path)!r}: another sigmatau batch keeps taking it")

    def __exit__(self, *exc: Any) -> None:
        if self.held:
            self.path.unlink(missing_ok=True)

    def _take_over_if_stale(self) -> None:
        """Remove the lock when its holder is gone; raise ParameterError when it is alive."""
        try:
            st = self.path.stat()
            text = self.path.read_text(encoding="utf-8", errors="replace")
        except FileNotFoundError:
            return  # released meanwhile: try again
        except OSError:
            st, text = None, ""
        holder = _parse_lock(text)
        age = time.time() - st.st_mtime if st is not None else 0.0
        if _holder_alive(holder, lock_mtime=st.st_mtime if st is not None else None, age=age):
            who = f"process {holder['pid']}" if holder else "a process"
            if holder and holder["host"] != socket.gethostname():
                who += f" on {holder['host']}"
            raise ParameterError(f"another sigmatau batch ({who}) is writing to {str(self.path.parent)!r}; wait for"
                                 f" it, use another --out, or delete {str(self.path)!r} if that run is gone")
        # Stale: move it aside (atomic) and check it is still the one judged stale, not a lock
        # that another run took over and wrote in between; that one is put back.
        aside = self.path.with_name(f".{_LOCK}.stale-{uuid.uuid4().hex[:8]}")
        try:
            os.rename(self.path, aside)
        except FileNotFoundError:
            return
        try:
            if aside.read_text(encoding="utf-8", errors="replace") != text:
                with contextlib.suppress(OSError):
                    os.link(aside, self.path)  # fails if yet another run holds it now: theirs stands
        finally:
            aside.unlink(missing_ok=True)


def _parse_lock(text: str) -> Optional[dict[str, Any]]:
    """The holder named by a lock's text: the JSON object, or the ``host pid`` of earlier versions."""
    try:
        data = json.loads(text)
    except ValueError:
        parts = text.split()
        if len(parts) == 2 and parts[1].isdigit():
            return {"host": parts[0], "pid": int(parts[1]), "start": None, "boot_id": None}
        return None
    if isinstance(data, dict) and isinstance(data.get("pid"), int) and isinstance(data.get("host"), str):
        return {"host": data["host"], "pid": data["pid"],
                "start": data.get("start") if isinstance(data.get("start"), int) else None,
                "boot_id": data.get("boot_id") if isinstance(data.get("boot_id"), str) else None}
    return None


def _holder_alive(holder: Optional[Mapping[str, Any]], *, lock_mtime: Optional[float], age: float) -> bool:
    """Whether the run that wrote a lock may still be running.

    On the same host: not when the boot id differs (rebooted since), nor when the
    PID is dead, nor when the live PID's start time differs from the one recorded
    (the PID was reused). A lock without a start time (earlier versions, systems
    without ``/proc``) is compared with the file's modification time: a process
    that started after its own lock was written is another process. Where neither
    can be read, a live PID holds. A lock of another host holds for a day (its
    process cannot be checked from here); an unreadable lock for a minute (it may
    be being written this instant).
    """
    if holder is None:
        return age < 60
    if holder["host"] != socket.gethostname():
        return age < 86400
    boot = _boot_id()
    if holder["boot_id"] and boot and holder["boot_id"] != boot:
        return False
    pid = holder["pid"]
    if not _pid_alive(pid):
        return False
    now = _start_ticks(pid)
    if now is None:
        return True
    if holder["start"] is not None:
        return holder["start"] == now
    started = _start_epoch(now)
    return not (started is not None and lock_mtime is not None and started > lock_mtime + 1.0)


def _start_ticks(pid: int) -> Optional[int]:
    """Start time of process ``pid`` in clock ticks after boot (``/proc/<pid>/stat`` field 22); None off Linux."""
    try:
        text = Path(f"/proc/{pid}/stat").read_text(encoding="ascii", errors="replace")
        return int(text[text.rindex(")") + 2:].split()[19])  # the name in (…) may hold spaces
    except (OSError, ValueError, IndexError):
        return None


def _start_epoch(ticks: int) -> Optional[float]:
    """A start time in ticks as Unix time (boot time ``btime`` of ``/proc/stat`` + ticks / ``SC_CLK_TCK``)."""
    try:
        for line in Path("/proc/stat").read_text(encoding="ascii", errors="replace").splitlines():
            if line.startswith("btime "):
                return int(line.split()[1]) + ticks / os.sysconf("SC_CLK_TCK")
    except (OSError, ValueError, AttributeError):
        pass
    return None


def _boot_id() -> Optional[str]:
    try:
        return Path("/proc/sys/kernel/random/boot_id").read_text(encoding="ascii").strip() or None
    except OSError:
        return None


def _pid_alive(pid: int) -> bool:
    if pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # alive, another user's
        return True
    except OSError:
        return False
    return True


def _read_index(out: Path) -> dict[str, dict[str, Any]]:
    """Latest journal entry per path; a line cut short by a crash is passed over."""
    latest: dict[str, dict[str, Any]] = {}
    try:
        text = (out / _INDEX).read_text(encoding="utf-8")
    except FileNotFoundError:
        return latest
    for line in text.splitlines():
        try:
            e = json.loads(line)
        except ValueError:
            continue
        if isinstance(e, dict) and "path" in e:
            latest[e["path"]] = e
    return latest


class _Journal:
    """``OUT/index.jsonl``, append-only: at most one line per log path, content hash and outcome, ever.

    A rerun of a log that fails again, or of one found done on a worker, writes nothing new.
    """

    def __init__(self, out: Path) -> None:
        self.seen: set[tuple[Any, Any, Any]] = set()
        with contextlib.suppress(FileNotFoundError):
            for line in (out / _INDEX).read_text(encoding="utf-8").splitlines():
                try:
                    e = json.loads(line)
                except ValueError:  # a line cut short by a crash
                    continue
                if isinstance(e, dict):
                    self.seen.add(self._key(e))
        self.fh = open(out / _INDEX, "a", encoding="utf-8")

    @staticmethod
    def _key(entry: Mapping[str, Any]) -> tuple[Any, Any, Any]:
        return (entry.get("path"), entry.get("sha256"), entry.get("status"))

    def append(self, rec: Mapping[str, Any], stat: Optional[tuple[int, int]]) -> None:
        if self._key(rec) in self.seen:
            return
        self.seen.add(self._key(rec))
        entry = {"path": rec["path"], "status": rec["status"], "sha256": rec.get("sha256"), "name": rec.get("name"),
                 "size": stat[0] if stat else None, "mtime_ns": stat[1] if stat else None,
                 "reused": bool(rec.get("reused")), "error": rec.get("error"), "time": time.time()}
        self.fh.write(json.dumps(entry, ensure_ascii=False) + "\n")
        self.fh.flush()
        os.fsync(self.fh.fileno())

    def close(self) -> None:
        self.fh.close()


def _stat(path: str) -> Optional[tuple[int, int]]:
    try:
        st = os.stat(path)
    except OSError:
        return None
    if os.path.isdir(path):  # a ROS 2 bag: its newest file
        times = [st.st_mtime_ns] + [q.stat().st_mtime_ns for q in Path(path).rglob("*") if q.is_file()]
        return (sum(q.stat().st_size for q in Path(path).rglob("*") if q.is_file()), max(times))
    return (st.st_size, st.st_mtime_ns)


# ----------------------------------------------------------------------- progress


class _Progress:
    """A bar on a terminal, else one line per log; or a callable of the caller's."""

    def __init__(self, total: int, mode: Any) -> None:
        self.total, self.done, self.failed, self.reused = total, 0, 0, 0
        self.t0 = time.perf_counter()
        self.call = mode if callable(mode) else None
        if self.call is not None:
            self.mode = "call"
        elif mode is None:
            self.mode = "bar" if sys.stderr.isatty() else "none"
        elif mode in ("bar", "lines", "none"):
            self.mode = mode
        else:
            self.mode = "bar" if mode and sys.stderr.isatty() else ("lines" if mode else "none")

    def update(self, rec: Mapping[str, Any]) -> None:
        self.done += 1
        self.failed += rec["status"] != "ok"
        self.reused += bool(rec.get("reused"))
        if self.mode == "call":
            self.call(rec, self.done, self.total)  # type: ignore[misc]
            return
        if self.mode == "lines":
            if rec.get("reused"):  # a rerun of thousands of logs: said once, at the end
                return
            what = ("done before" if rec.get("reused") else f"{rec.get('seconds', 0):.1f} s") if rec["status"] == "ok" \
                else f"{rec['error']['type']}: {rec['error']['message']}"
            print(f"[{self.done}/{self.total}] {rec['status']:<5} {rec['path']} ({what})", file=sys.stderr, flush=True)
        elif self.mode == "bar":
            width = 30
            fill = int(width * self.done / max(self.total, 1))
            el = time.perf_counter() - self.t0
            eta = el / self.done * (self.total - self.done) if self.done else 0.0
            print(f"\r[{'#' * fill}{'.' * (width - fill)}] {self.done}/{self.total} logs, {self.failed} failed,"
                  f" {self.reused} done before, {el:.0f} s elapsed, ~{eta:.0f} s left ", end="", file=sys.stderr,
                  flush=True)

    def close(self) -> None:
        if self.mode == "bar" and self.done:
            print(file=sys.stderr, flush=True)
        elif self.mode == "lines" and self.reused:
            print(f"{self.reused} log(s) done before: skipped", file=sys.stderr, flush=True)


# ------------------------------------------------------------------------ limits


def load_limits(spec: Any, *, margin: float = LIMIT_MARGIN) -> dict[str, dict[str, dict[str, Any]]]:
    """Upper limits of noise terms, in SI: ``{group: {term: {"max": float, "unit": str, "source": str}}}``.

    Parameters
    ----------
    spec : str, path or mapping or None
        A part with presets in :data:`sigmatau.imu.PRESETS` (``"lsm6dsl"`` …):
        its typical datasheet figures × ``margin``; or a file — JSON or YAML
        ``{"gyro": {"N": "6 mdps/sqrt(Hz)", "B": [1e-4, "rad/s"]}}``, or CSV
        with the columns ``group, term, max, unit`` (UTF-8, a byte-order mark
        allowed) — whose values are the limits as given; or such a mapping.
        A value without unit is SI.
    margin : float
        Factor applied to a preset's typical values (default 1.5); not to
        limits given explicitly (a warning says so when another margin is given).

    Raises
    ------
    ParameterError
        An unknown part, a missing, unreadable or malformed file (the message
        names it and what is wrong), an unknown group, term or unit, a value
        that is not a positive number, a term given twice, or a margin that is
        not a positive finite number.
    """
    from ..pipeline.analysis import datasheet_reference
    from ..imu.units import convert

    if isinstance(margin, bool) or not isinstance(margin, (int, float)) or not (math.isfinite(margin) and margin > 0):
        raise ParameterError(f"limit margin {margin!r} must be a positive finite number")
    if spec is None:
        return {}
    raw: Mapping[str, Any]
    factor, source, where, part = 1.0, "given", "limits: ", False
    if isinstance(spec, (str, os.PathLike)):
        p = Path(spec)
        if p.is_file():
            raw, source = _limits_file(p), f"file {os.fspath(spec)}"
            where = f"limits file {str(p)!r}: "
        elif os.fspath(spec).lower().endswith((".json", ".yaml", ".yml", ".csv")):
            raise ParameterError(f"limits file {os.fspath(spec)!r} does not exist")
        else:
            raw = datasheet_reference(os.fspath(spec))
            factor, source, part = float(margin), f"datasheet {os.fspath(spec)} typical × {float(margin):g}", True
    elif isinstance(spec, Mapping):
        raw = spec
    else:
        raise ParameterError(f"limits={spec!r} must be a part name, a file or a mapping group → term → value")
    if not part and margin != LIMIT_MARGIN:
        warnings.warn(f"limit margin {margin:g} not applied: it multiplies a datasheet part's typical values, and"
                      f" the limits of {'the file' if where != 'limits: ' else 'the mapping'} are used as given",
                      SigmaTauWarning, stacklevel=2)
    out: dict[str, dict[str, dict[str, Any]]] = {}
    for group, terms in raw.items():
        if group not in IMU_GROUPS:
            raise ParameterError(f"{where}group {group!r} must be 'gyro' or 'accel'")
        if not isinstance(terms, Mapping):
            raise ParameterError(f"{where}{group!r} must map terms to values, e.g. {{N: '6 mdps/sqrt(Hz)'}}")
        for term, value in terms.items():
            if term not in TERMS:
                raise ParameterError(f"{where}term {group}.{term} must be one of {', '.join(TERMS)}")
            si = SI_TERM_UNITS[group][term]
            v, unit = _limit_value(value, f"{where}{group}.{term}", si)
            try:
                v_si = float(convert(v, unit, si))
            except SigmaTauError:
                raise ParameterError(f"{where}{group}.{term} unit {unit!r} is not a unit of {si}") from None
            out.setdefault(group, {})[term] = {"max": v_si * factor, "unit": si, "source": source,
                                               "given": f"{v:g} {unit}" + (f" × {factor:g}" if factor != 1 else "")}
    return out


def _limit_value(value: Any, what: str, si: str) -> tuple[float, str]:
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        v, unit = float(value), si
    elif isinstance(value, str):
        num, _, unit = value.strip().partition(" ")
        try:
            v = float(num)
        except ValueError:
            raise ParameterError(f"{what}={value!r} must be 'value unit', e.g. '6 mdps/sqrt(Hz)'") from None
        unit = unit.strip() or si
    elif isinstance(value, (list, tuple)) and len(value) == 2:
        try:
            v, unit = float(value[0]), str(value[1])
        except (TypeError, ValueError):
            raise ParameterError(f"{what}={value!r} must be (value, unit)") from None
    else:
        raise ParameterError(f"{what}={value!r} must be a number, 'value unit' or (value, unit)")
    if not (math.isfinite(v) and v > 0):
        raise ParameterError(f"{what}={value!r} must be positive")
    return v, unit


def _limits_file(p: Path) -> dict[str, Any]:
    """The mapping group → term → value of a limits file (JSON, YAML or CSV by its suffix)."""
    name = str(p)
    try:
        text = p.read_text(encoding="utf-8-sig")  # -sig: spreadsheets save CSV with a byte-order mark
    except UnicodeDecodeError as exc:
        raise ParameterError(f"limits file {name!r} is not UTF-8 text (byte {exc.start})") from None
    except OSError as exc:
        raise ParameterError(f"limits file {name!r} cannot be read: {exc.strerror or exc}") from None
    suffix = p.suffix.lower()
    if suffix == ".csv":
        return _limits_csv(text, name)
    if suffix in (".yaml", ".yml"):
        try:
            import yaml
        except ImportError:
            from ..io import MissingDependencyError

            raise MissingDependencyError("YAML limits need PyYAML; install it with: pip install pyyaml,"
                                         " or give the limits as JSON or CSV") from None
        try:
            data = yaml.safe_load(text)
        except yaml.YAMLError as exc:
            mark = getattr(exc, "problem_mark", None)
            at = f" at line {mark.line + 1}, column {mark.column + 1}" if mark is not None else ""
            problem = getattr(exc, "problem", None) or type(exc).__name__
            raise ParameterError(f"limits file {name!r} is not valid YAML{at}: {problem}") from None
    else:
        try:
            data = json.loads(text, object_pairs_hook=_no_duplicate_keys)
        except ValueError as exc:
            raise ParameterError(f"limits file {name!r} is not valid JSON: {exc}") from None
    if not isinstance(data, Mapping):
        raise ParameterError(f"limits file {name!r} must map groups to terms to values, e.g."
                             " {gyro: {N: '6 mdps/sqrt(Hz)'}}")
    return dict(data)


def _no_duplicate_keys(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    """A JSON object, refused when a key appears twice (JSON would keep the last silently)."""
    keys = [k for k, _ in pairs]
    twice = sorted({k for k in keys if keys.count(k) > 1})
    if twice:
        raise ValueError(f"{', '.join(map(repr, twice))} given twice")
    return dict(pairs)


def _limits_csv(text: str, name: str) -> dict[str, Any]:
    try:
        rows = list(csv.reader(_io.StringIO(text)))
    except csv.Error as exc:
        raise ParameterError(f"limits file {name!r} is not valid CSV: {exc}") from None
    header = [h.strip().lower() for h in rows[0]] if rows else []
    if not {"group", "term", "max"} <= set(header):
        raise ParameterError(f"limits file {name!r}: CSV needs the columns group, term, max (and unit)")
    col = {h: i for i, h in enumerate(header)}
    data: dict[str, dict[str, Any]] = {}
    for number, row in enumerate(rows[1:], start=2):
        if not any(c.strip() for c in row):
            continue
        cells = {h: (row[i].strip() if i < len(row) else "") for h, i in col.items()}
        if not (cells["group"] and cells["term"] and cells["max"]):
            raise ParameterError(f"limits file {name!r}: row {number} needs a group, a term and a max")
        try:
            v = float(cells["max"])
        except ValueError:
            raise ParameterError(f"limits file {name!r}: row {number}: max={cells['max']!r} is not a number") from None
        terms = data.setdefault(cells["group"], {})
        if cells["term"] in terms:
            raise ParameterError(f"limits file {name!r}: row {number}: {cells['group']}.{cells['term']} is given"
                                 " twice")
        unit = cells.get("unit", "")
        terms[cells["term"]] = (v, unit) if unit else v
    return data


# ------------------------------------------------------------------------- fleet


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
    from ..report.outputs import csv_cell

    buf = _io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(header)
    for r in rows:
        w.writerow([csv_cell(r.get(h)) for h in header])
    return buf.getvalue()


def _write_text(path: Path, text: Union[str, bytes]) -> None:
    tmp = path.with_name(f".{path.name}.{uuid.uuid4().hex[:8]}.tmp")
    tmp.write_bytes(text.encode("utf-8") if isinstance(text, str) else text)
    os.replace(tmp, path)


_ROW_COLUMNS = ("path", "log", "sha256", "channel", "group", "term", "unit", "value", "low", "high", "resolved",
                "method", "z", "outlier", "limit", "verdict")
_LOG_COLUMNS = ("path", "status", "log", "sha256", "size", "format", "rate", "duration_s", "verdict", "outliers",
                "limit_failures", "warnings", "error_type", "error_kind", "error_message", "seconds", "reused")


def _log_rows(records: Sequence[dict], errors: Sequence[dict]) -> list[dict]:
    out = []
    for r in [*records, *errors]:
        e = r.get("error") or {}
        out.append({**{k: r.get(k) for k in _LOG_COLUMNS}, "log": r.get("name"),
                    "outliers": "; ".join(r.get("outliers", [])), "limit_failures": "; ".join(r.get("limit_failures", [])),
                    "warnings": len(r.get("warnings", [])), "error_type": e.get("type"), "error_kind": e.get("kind"),
                    "error_message": e.get("message"), "reused": bool(r.get("reused"))})
    return sorted(out, key=lambda r: r["path"])


def _fleet_figures(rows: Sequence[dict], limits: Mapping[str, Any]) -> dict[str, bytes]:
    """Histograms and a strip plot with intervals of N, B, K per group (PNG bytes)."""
    import numpy as np

    from ..report import plots
    from ..imu.units import pretty

    plots.matplotlib_modules()  # MissingDependencyError naming the extra when matplotlib is missing
    from matplotlib.ticker import LogLocator, NullLocator

    groups = [g for g in IMU_GROUPS if any(r["group"] == g for r in rows)]
    if not groups:
        return {}
    out = {}
    logs = sorted({r["path"] for r in rows})
    pos = {p: i for i, p in enumerate(logs)}
    axis_colors = {"x": "#0072B2", "y": "#E69F00", "z": "#009E73"}
    for kind in ("hist", "strip"):
        fig = plots.new_figure((4.0 * len(_HIST_TERMS), 3.0 * len(groups) + 0.4))
        axes = fig.subplots(len(groups), len(_HIST_TERMS), squeeze=False)
        for i, g in enumerate(groups):
            for j, t in enumerate(_HIST_TERMS):
                ax = axes[i][j]
                sel = [r for r in rows if r["group"] == g and r["term"] == t]
                res = [r for r in sel if r["resolved"] and r["value"]]
                lim = limits.get(g, {}).get(t)
                unit = pretty(sel[0]["unit"]) if sel else ""
                ax.set_title(f"{g} {t} [{unit}]", fontsize=9)
                ax.tick_params(labelsize=8)
                ax.grid(True, color="0.88", linewidth=0.5)
                if kind == "hist":
                    if res:
                        ax.set_xscale("log")
                        v = np.array([r["value"] for r in res])
                        lo, hi = v.min(), v.max()
                        if lim:
                            lo, hi = min(lo, lim["max"]), max(hi, lim["max"])
                        bins = np.logspace(np.log10(lo) - 0.05, np.log10(hi) + 0.05, 25)
                        ax.hist(v, bins=bins, color="#56B4E9", edgecolor="#0072B2", linewidth=0.6)
                        ax.axvline(float(np.median(v)), color="black", linewidth=1.0, label="median")
                        bad = [r["value"] for r in res if r["outlier"]]
                        if bad:
                            ax.plot(bad, [0] * len(bad), "v", color="#D55E00", markersize=7, clip_on=False,
                                    label="outlier")
                    else:
                        ax.text(0.5, 0.5, "not resolved in any log", ha="center", va="center",
                                transform=ax.transAxes, fontsize=8, color="0.4")
                        ax.set_xticks([])
                        ax.set_yticks([])
                        lim = None
                    ax.set_xlabel(f"{t} [{unit}]", fontsize=8)
                    ax.set_ylabel("channels", fontsize=8)
                else:
                    ax.set_yscale("log")
                    for letter, color in axis_colors.items():  # one call per axis: thousands of logs stay fast
                        mine = [r for r in sel if r["channel"].rsplit("_", 1)[-1] == letter or
                                (letter == "x" and r["channel"].rsplit("_", 1)[-1] not in axis_colors)]
                        shift = {"x": -0.2, "y": 0.0, "z": 0.2}[letter]
                        good = [r for r in mine if r["resolved"] and r["value"]]
                        if good:
                            x = np.array([pos[r["path"]] for r in good]) + shift
                            v = np.array([r["value"] for r in good])
                            lo = np.array([max(r["low"], r["value"] / 100) for r in good])
                            hi = np.array([r["high"] if math.isfinite(r["high"]) else r["value"] for r in good])
                            ax.errorbar(x, v, yerr=np.clip([v - lo, hi - v], 0, None), fmt="o", color=color, markersize=3,
                                        elinewidth=0.8, linestyle="none")
                            bad = [(xi, r["value"]) for xi, r in zip(x, good) if r["outlier"]]
                            if bad:
                                ax.plot(*zip(*bad), "o", mfc="none", mec="#D55E00", markersize=9, mew=1.2,
                                        linestyle="none")
                        bounds = [r for r in mine if not r["resolved"] and r["high"] and math.isfinite(r["high"])]
                        if bounds:
                            ax.plot(np.array([pos[r["path"]] for r in bounds]) + shift, [r["high"] for r in bounds],
                                    "v", color=color, markersize=4, alpha=0.6, linestyle="none")
                    ax.set_xlabel("log (sorted by path); ▼ upper bound, not resolved", fontsize=8)
                    ax.set_xlim(-0.8, len(logs) - 0.2)
                if lim:
                    (ax.axvline if kind == "hist" else ax.axhline)(lim["max"], color="#D55E00", linestyle="--",
                                                                   linewidth=1.0, label="limit")
                if kind == "hist" and ax.get_legend_handles_labels()[0]:
                    ax.legend(fontsize=7, frameon=False)
        fig.suptitle("Fleet distribution of the noise terms" if kind == "hist" else
                     "Noise terms per log with intervals (colour: x, y, z axis)", fontsize=10)
        for ax in fig.axes:  # minor log ticks over many decades make the layout slow
            for axis in (ax.xaxis, ax.yaxis):
                if axis.get_scale() == "log":
                    axis.set_major_locator(LogLocator(numticks=6))
                    axis.set_minor_locator(NullLocator())
        out[f"fleet_{kind}"] = plots.figure_to_bytes(fig, "png")
    return out


_CSS = """
body{font-family:system-ui,-apple-system,"Segoe UI",Roboto,Helvetica,Arial,sans-serif;margin:0 auto;
max-width:1200px;padding:0 1.5em 3em;color:#1d1d1f;line-height:1.45}
h1{font-size:1.6em;margin:1.2em 0 .2em}h2{font-size:1.25em;margin-top:2em;border-bottom:1px solid #ccc}
table{border-collapse:collapse;margin:.5em 0;font-size:.86em}
th,td{border:1px solid #d0d0d0;padding:.2em .5em;text-align:right;vertical-align:top}
th{background:#f2f2f2}td.l,th.l{text-align:left}
figure{margin:1em 0}figure img{max-width:100%;height:auto;border:1px solid #eee}
.fail{color:#a00;font-weight:600}.pass{color:#185c18}.muted{color:#666}.flag{color:#8a4b00}
"""


def _h(text: Any) -> str:
    return html.escape(str(text), quote=True)


def _n(v: Any, fmt: str = ".4g") -> str:
    return "–" if v is None or (isinstance(v, float) and not math.isfinite(v)) else format(float(v), fmt)


def _fleet_html(fleet: FleetSummary, figs: Mapping[str, bytes], figure_note: str) -> str:
    from ..imu.units import pretty

    recs, errs = fleet.records, fleet.errors
    n = len(recs) + len(errs)
    fails = [r for r in recs if r.get("verdict") == "fail"]
    parts = ["<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
             '<meta name="viewport" content="width=device-width, initial-scale=1">',
             f"<title>sigmatau fleet report — {n} logs</title><style>{_CSS}</style></head><body>",
             f"<h1>sigmatau fleet report — {n} logs</h1>",
             f'<p class="muted">sigmatau {_h(__version__)}; {len(recs)} analysed ({fleet.computed} in this run,'
             f" {fleet.reused} done before), {len(errs)} failed; {fleet.seconds:.1f} s."
             ' <a href="#dist">distribution</a> · <a href="#figures">figures</a> · <a href="#limits">limits</a> ·'
             ' <a href="#outliers">outliers</a> · <a href="#errors">errors</a> · <a href="#logs">logs</a></p>']
    parts.append('<h2 id="dist">Distribution across the fleet</h2>'
                 "<p>SI units; values of resolved terms only (bounds counted apart); spread ×/÷ is 10^(1.4826·MAD)"
                 " of log10 values.</p><table><tr><th class=l>group</th><th>term</th><th class=l>unit</th>"
                 "<th>logs</th><th>resolved</th><th>bounds</th><th>median</th><th>spread ×/÷</th><th>5 %</th>"
                 "<th>95 %</th><th>min</th><th>max</th><th>limit</th><th>fail</th><th>outliers</th></tr>")
    for d in fleet.distribution:
        parts.append(f"<tr><td class=l>{_h(d['group'])}</td><td>{_h(d['term'])}</td><td class=l>"
                     f"{_h(pretty(d['unit']))}</td><td>{d['logs']}</td><td>{d['resolved']}</td><td>{d['bounds']}</td>"
                     f"<td>{_n(d['median'])}</td><td>{_n(d['spread_factor'], '.3g')}</td><td>{_n(d['p05'])}</td>"
                     f"<td>{_n(d['p95'])}</td><td>{_n(d['min'])}</td><td>{_n(d['max'])}</td><td>{_n(d['limit'])}</td>"
                     f"<td{' class=fail' if d['fail'] else ''}>{d['fail']}</td><td>{d['outliers']}</td></tr>")
    parts.append("</table>")
    parts.append('<h2 id="figures">Figures</h2>')
    if figure_note:
        parts.append(f'<p class="flag">Figures not made: {_h(figure_note)}</p>')
    for stem, data in figs.items():
        cap = ("Histograms of the resolved N, B, K of every channel; median (black), limit (dashed), outliers (▼)"
               if stem.endswith("hist") else "N, B, K of every log with their intervals; outliers circled;"
               " ▼ marks the upper bound of a term the record does not resolve")
        parts.append(f'<figure><img src="data:image/png;base64,{base64.b64encode(data).decode("ascii")}"'
                     f' alt="{_h(cap)}"><figcaption>{_h(cap)}</figcaption></figure>')
    parts.append('<h2 id="limits">Limits</h2>')
    if fleet.limits:
        parts.append(f"<p>{_h(_LIMIT_RULE)}.</p><ul>" + "".join(
            f"<li>{_h(g)} {_h(t)} ≤ {_n(v['max'])} {_h(pretty(v['unit']))} ({_h(v['given'])}; {_h(v['source'])})</li>"
            for g, terms in fleet.limits.items() for t, v in terms.items()) + "</ul>")
        parts.append(f"<p><span class=pass>{sum(r.get('verdict') == 'pass' for r in recs)} pass</span>,"
                     f" <span class=fail>{len(fails)} fail</span>,"
                     f" {sum(r.get('verdict') == 'untested' for r in recs)} untested.</p>")
        if fails:
            parts.append("<table><tr><th class=l>log</th><th class=l>failures</th></tr>" + "".join(
                f"<tr><td class=l>{_link(r)}</td><td class=l>{_h('; '.join(r['limit_failures']))}</td></tr>"
                for r in fails) + "</table>")
    else:
        parts.append('<p class="muted">No limits given (--limits).</p>')
    parts.append(f'<h2 id="outliers">Outliers against the fleet</h2><p>{_h(_OUTLIER_RULE)}.</p>')
    outl = [r for r in recs if r.get("outliers")]
    parts.append("<table><tr><th class=l>log</th><th class=l>terms</th></tr>" + "".join(
        f"<tr><td class=l>{_link(r)}</td><td class=l>{_h(', '.join(r['outliers']))}</td></tr>" for r in outl)
        + "</table>" if outl else '<p class="muted">None.</p>')
    parts.append('<h2 id="errors">Logs that could not be analysed</h2>')
    parts.append("<table><tr><th class=l>path</th><th class=l>error</th><th class=l>kind</th><th class=l>reason</th>"
                 "</tr>" + "".join(f"<tr><td class=l>{_h(e['path'])}</td><td class=l>{_h(e['error']['type'])}</td>"
                                   f"<td class=l>{_h(e['error']['kind'])}</td><td class=l>{_h(e['error']['message'])}"
                                   "</td></tr>" for e in errs) + "</table>" if errs else '<p class="muted">None.</p>')
    parts.append('<h2 id="logs">Logs</h2><table><tr><th class=l>log</th><th>duration</th><th>rate [Hz]</th>'
                 "<th class=l>verdict</th><th>gyro N max</th><th>accel N max</th><th>outliers</th><th>warnings</th>"
                 "<th class=l>sha256</th></tr>")
    for r in recs:
        nmax = {}
        for g in IMU_GROUPS:
            vs = [c["terms"]["N"]["value"] for c in r["channels"] if c["group"] == g and c.get("terms")
                  and c["terms"]["N"]["resolved"]]
            nmax[g] = max(vs) if vs else None
        v = r.get("verdict", "")
        parts.append(f"<tr><td class=l>{_link(r)}</td><td>{_n(r['duration_s'] / 3600, '.3g')} h</td>"
                     f"<td>{_n(r['rate'], '.6g')}</td><td class='l {v}'>{_h(v or '–')}</td>"
                     f"<td>{_n(nmax['gyro'])}</td><td>{_n(nmax['accel'])}</td><td>{len(r.get('outliers', []))}</td>"
                     f"<td>{len(r.get('warnings', []))}</td><td class=l><code>{_h(r['sha256'][:12])}</code></td></tr>")
    parts.append("</table></body></html>")
    return "\n".join(parts) + "\n"


def _link(r: Mapping[str, Any]) -> str:
    label = _h(r["path"])
    if r.get("name") and r.get("has_report", True):
        return f'<a href="{_h(LOGS_DIR)}/{_h(r["name"])}/report.html">{label}</a>'
    return label


def _build_fleet(out: Path, records: list[dict], errors: list[dict], *, limits: Mapping[str, Any],
                 outlier_z: float, computed: int, reused: int, seconds: float, figures: bool) -> FleetSummary:
    rows = _rows(records, limits)
    dist = _outliers_and_distribution(rows, limits, outlier_z)
    _annotate(records, rows, limits)
    for r in records:
        r["has_report"] = (out / LOGS_DIR / r["name"] / "report.html").is_file()
    figs: dict[str, bytes] = {}
    note = ""
    if figures:
        try:
            figs = _fleet_figures(rows, limits)
        except SigmaTauError as exc:  # matplotlib missing: the tables are still useful
            note = str(exc)
    files = []
    for stem, data in figs.items():
        _write_text(out / f"{stem}.png", data)
        files.append(out / f"{stem}.png")
    fleet = FleetSummary(out=out, records=tuple(records), errors=tuple(errors), rows=tuple(rows),
                         distribution=tuple(dist), limits=dict(limits), computed=computed, reused=reused,
                         seconds=seconds)
    _write_text(out / "fleet.csv", _csv_text(_ROW_COLUMNS, rows))
    _write_text(out / "fleet_logs.csv", _csv_text(_LOG_COLUMNS, _log_rows(records, errors)))
    _write_text(out / "fleet.json", json.dumps(fleet.to_dict(), indent=1, allow_nan=False, ensure_ascii=False) + "\n")
    _write_text(out / "fleet.html", _fleet_html(fleet, figs, note))
    files += [out / n for n in ("fleet.csv", "fleet_logs.csv", "fleet.json", "fleet.html")]
    return replace(fleet, files=tuple(files))


# -------------------------------------------------------------------------- main


def usable_cores() -> int:
    """Cores this process may run on (its CPU affinity where the platform tells it)."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


_SCHEMES = ("tcp", "tls", "ws", "wss", "ucx")
_ADDRESS = re.compile(r"(?:(?P<scheme>[A-Za-z][A-Za-z0-9+.-]*)://)?"
                      r"(?P<host>\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9_](?:[A-Za-z0-9_.-]*[A-Za-z0-9_])?)"
                      r":(?P<port>[0-9]{1,5})")


def check_scheduler_address(address: Any, *, name: str = "scheduler") -> str:
    """``address`` checked to be a Dask scheduler address, ``[scheme://]host:port``, before any connection.

    Parameters
    ----------
    address : str
        ``tcp://10.0.0.5:8786`` (the scheme may be ``tcp``, ``tls``, ``ws``, ``wss``
        or ``ucx``; without one, ``tcp``); the host a name, an IPv4 address or a
        bracketed IPv6 address; the port 1–65535.
    name : str
        What to call it in the message (the CLI says ``--scheduler``).

    Returns
    -------
    str
        The address as given.

    Raises
    ------
    ParameterError
        Anything else, named in a one-line message.

    Examples
    --------
    >>> check_scheduler_address("tcp://10.0.0.5:8786")
    'tcp://10.0.0.5:8786'
    """
    example = "such as tcp://host:8786"
    if not isinstance(address, str):
        raise ParameterError(f"{name} {address!r} is not a scheduler address {example}")
    m = _ADDRESS.fullmatch(address.strip())
    if m is None:
        raise ParameterError(f"{name} {address!r} is not a scheduler address {example} ([scheme://]host:port)")
    scheme = (m["scheme"] or "tcp").lower()
    if scheme not in _SCHEMES:
        raise ParameterError(f"{name} {address!r} is not a scheduler address {example}: scheme {scheme!r} is not"
                             f" one of {', '.join(_SCHEMES)}")
    if not 1 <= int(m["port"]) <= 65535:
        raise ParameterError(f"{name} {address!r} is not a scheduler address {example}: port {m['port']} is not"
                             " in 1-65535")
    return address


def _probe_scheduler(address: str) -> None:
    """Fail fast, in one line, when nothing answers at ``address`` (a TCP connection, before any
    Dask client: a client that fails to connect lingers for tens of seconds at exit)."""
    m = _ADDRESS.fullmatch(address.strip())
    if m is None or (m["scheme"] or "tcp").lower() == "ucx":  # UCX is not TCP: left to Dask's own timeout
        return
    host = m["host"].strip("[]")
    try:
        with socket.create_connection((host, int(m["port"])), timeout=CONNECT_TIMEOUT):
            pass
    except socket.gaierror as exc:
        reason = f"unknown host {host!r} ({exc.strerror or exc})"
    except (TimeoutError, socket.timeout):
        reason = "no answer"
    except OSError as exc:
        reason = (exc.strerror or str(exc)).lower()
    else:
        return
    raise ClusterError(f"cannot reach the Dask scheduler at {address!r} within {CONNECT_TIMEOUT:g} s: {reason}")


def local_worker_count(requested: Optional[int], logs: int, cores: int) -> tuple[int, str]:
    """Worker processes of a local cluster: the request (default the cores), at most the cores and the
    logs (each task is one log on one single-threaded process); and a note when a request was capped."""
    n = max(1, min(requested or cores, cores, logs))
    note = ""
    if requested is not None and requested > n:
        note = (f"workers={requested} capped to {n}: {cores} usable core(s), {logs} log(s) to analyse;"
                " more processes would only compete for them")
    return n, note


def _connect(client: Any, scheduler: Optional[str], workers: int) -> tuple[Any, Callable[[], None]]:
    """The client to use and how to close what was opened here."""
    if client is not None:
        return client, lambda: None
    distributed = _distributed()
    if scheduler is not None:
        try:
            c = distributed.Client(scheduler, timeout=f"{CONNECT_TIMEOUT:g}s", set_as_default=False)
        except (OSError, TimeoutError) as exc:
            raise ClusterError(f"cannot reach the Dask scheduler at {scheduler!r} within {CONNECT_TIMEOUT:g} s:"
                               f" {_one_line(exc)}") from None
        except (ValueError, TypeError) as exc:
            raise ParameterError(f"--scheduler {scheduler!r} is not a scheduler address such as"
                                 f" tcp://host:8786 ({_one_line(exc)})") from None
        return c, c.close
    n = workers
    import dask

    try:
        # Dask's nanny sets MALLOC_TRIM_THRESHOLD_=65536 in its workers, which also fixes glibc's mmap
        # threshold at 128 KiB: every array of a long log is then mmapped and page-faulted afresh,
        # and the analysis runs 2-3 times slower (measured). Unset here (None unsets it).
        with dask.config.set({"distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None}), \
                warnings.catch_warnings():  # the scheduler's HTTP port: another one is taken when 8787 is
            warnings.filterwarnings("ignore", message="Port .* is already in use")
            cluster = distributed.LocalCluster(n_workers=n, threads_per_worker=1, processes=True, host="127.0.0.1",
                                               dashboard_address=None)
    except Exception as exc:
        raise ClusterError(f"cannot start a local Dask cluster of {n} workers: {_one_line(exc)}") from None
    # Not the process's default client: batch submits and waits through it explicitly, and a
    # default one would leave dask's global scheduler pointing at a closed cluster afterwards.
    c = distributed.Client(cluster, set_as_default=False)

    def close() -> None:
        c.close()
        cluster.close()

    return c, close


def _remove_if_ours_and_empty(out: Path) -> None:
    """Undo the creation of ``out`` by a run that analysed nothing: remove what it wrote
    (settings, an empty journal, the lock's directory ``logs`` when empty), then ``out`` if
    empty. Never anything else."""
    with contextlib.suppress(OSError):
        if (out / _INDEX).stat().st_size == 0:
            (out / _INDEX).unlink()
    for name in (_SETTINGS,):
        with contextlib.suppress(OSError):
            (out / name).unlink()
    for d in (out / LOGS_DIR, out):
        with contextlib.suppress(OSError):
            d.rmdir()  # only when empty


def analyze_many(
    paths: Union[PathLike, Sequence[PathLike]],
    out: PathLike,
    *,
    client: Any = None,
    scheduler: Optional[str] = None,
    workers: Optional[int] = None,
    read: Optional[Mapping[str, Any]] = None,
    statistics: Union[str, Sequence[str]] = DEFAULT_STATISTICS,
    taus: Any = "octave",
    confidence: float = ONE_SIGMA,
    model: bool = True,
    axis_rule: str = "max",
    inflate: float = 1.0,
    rostopic: str = "/imu0",
    datasheet: Union[str, Mapping[str, Any], None] = None,
    figures: Optional[Sequence[str]] = ("png",),
    report: bool = True,
    limits: Any = None,
    limit_margin: float = LIMIT_MARGIN,
    outlier_z: float = OUTLIER_Z,
    fleet_figures: bool = True,
    force: bool = False,
    progress: Any = None,
) -> FleetSummary:
    """Analyse many logs on a Dask cluster, one task per log, and summarise the fleet.

    Parameters
    ----------
    paths : path, pattern or sequence of them
        Logs: files, ROS 2 bag directories or glob patterns
        (:func:`expand_patterns`). With a remote cluster, the workers must see
        the same paths (a shared file system) and write to ``out``.
    out : path
        Output directory (created; its parent must exist). Reused by a rerun,
        which skips the logs already done.
    client : distributed.Client, optional
        A client of the cluster to use (left open).
    scheduler : str, optional
        Address of an existing scheduler (``"tcp://host:8786"``) to connect to;
        checked by :func:`check_scheduler_address` and reached within
        :data:`CONNECT_TIMEOUT` seconds before ``out`` is created.
    workers : int, optional
        Without ``client`` and ``scheduler``: a ``LocalCluster`` of this many
        single-threaded worker processes (default: the usable cores), at most
        the usable cores and the logs to analyse (a ``SigmaTauWarning`` says
        so when a request is capped).
    read : mapping, optional
        Keyword arguments of :func:`sigmatau.io.read` (``columns``,
        ``time_unit``, ``rate``, ``units``, ``topic``, ``gaps`` …), the same
        for every log.
    statistics, taus, confidence, model, axis_rule, inflate, rostopic, datasheet
        As :func:`sigmatau.analysis.analyze_log`.
    figures : sequence of {"png", "svg", "pdf"} or None
        Per-log figure formats (default PNG only; None: no figures, fastest).
    report : bool
        Write each log's ``report.html``.
    limits : str, path or mapping, optional
        Pass/fail limits (:func:`load_limits`): a datasheet part, a file or a mapping.
    limit_margin : float
        Factor on a datasheet part's typical values (default 1.5).
    outlier_z : float
        Robust z beyond which a term is an outlier of its fleet (default 3.5).
    fleet_figures : bool
        Draw the fleet histograms and strip plot (needs matplotlib).
    force : bool
        Recompute every log, replacing its directory (also when the settings changed).
    progress : None, bool, "bar", "lines", "none" or callable
        None: a bar on stderr when it is a terminal. A callable is called as
        ``progress(record, done, total)`` after each log (raising
        KeyboardInterrupt from it stops the run like Ctrl-C).

    Returns
    -------
    FleetSummary

    Raises
    ------
    ParameterError
        A bad argument, pattern or limits file; ``out`` of other settings; or
        ``out`` locked by a run that is still alive (a lock left by a run that
        died, or whose PID now belongs to another process, is taken over).
    ClusterError
        The scheduler cannot be reached or the local cluster cannot start;
        an ``out`` created by this call is then removed again.

    Notes
    -----
    Each log is one task ``(hash, read, analyze_log, write_outputs, record)``
    that returns a small record and never raises: a corrupt or unreadable log
    becomes an error record with the exception's class and a one-line reason.
    The per-log directory ``out/logs/<stem>-<sha256[:12]>`` is written under a
    hidden name and renamed into place, its ``record.json`` included, so it
    exists only complete; a task finding the directory of its content already
    there returns that record. The client appends every finished record to
    ``out/index.jsonl`` (fsync) as it arrives — once per path, content hash
    and outcome, so a log failing on every rerun stays one line — and a rerun
    skips paths whose
    size and mtime match a journal entry whose directory exists, without
    submitting them; the others are hashed on the workers and skipped there.
    The fleet summary counts each content once. A worker that dies has its
    tasks rerun elsewhere by Dask; after ``distributed.scheduler.allowed-failures``
    deaths the log is reported as failed (``KilledWorker``).
    """
    from ..report.outputs import FIGURE_FORMATS

    t0 = time.perf_counter()
    out_p = Path(out)
    files = expand_patterns([paths] if isinstance(paths, (str, os.PathLike)) else list(paths), exclude=out_p)
    if client is not None and scheduler is not None:
        raise ParameterError("give client or scheduler, not both")
    if (client is not None or scheduler is not None) and workers is not None:
        raise ParameterError("workers= starts a local cluster; it cannot be combined with client or scheduler")
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int) or workers < 1):
        raise ParameterError(f"workers={workers!r} must be a positive integer")
    if scheduler is not None:
        check_scheduler_address(scheduler)
    fmts = [str(f).lower() for f in (figures or ())]
    for f in fmts:
        if f not in FIGURE_FORMATS:
            raise ParameterError(f"figure format {f!r} must be one of {', '.join(FIGURE_FORMATS)}")
    if isinstance(outlier_z, bool) or not isinstance(outlier_z, (int, float)) or not outlier_z > 0:
        raise ParameterError(f"outlier_z={outlier_z!r} must be a positive number")
    read_kw = _read_kwargs(read)
    analysis_kw = _analysis_kwargs(statistics, taus, confidence, model, axis_rule, inflate, rostopic, datasheet)
    lim = load_limits(limits, margin=limit_margin)
    if out_p.exists() and not out_p.is_dir():
        raise ParameterError(f"out {str(out_p)!r} exists and is not a directory")
    if not out_p.resolve().parent.is_dir():
        raise ParameterError(f"out {str(out_p)!r}: the parent directory does not exist")
    if out_p.is_dir() and any(out_p.iterdir()) and not (out_p / "batch.json").is_file():
        raise ParameterError(f"out {str(out_p)!r} exists, is not empty and is not a sigmatau batch directory"
                             " (no batch.json); choose another --out")
    if scheduler is not None:
        _probe_scheduler(scheduler)
    created = not out_p.exists()
    out_p.mkdir(exist_ok=True)
    try:
        return _run_batch(out_p, files, created=created, client=client, scheduler=scheduler, workers=workers,
                          read_kw=read_kw, analysis_kw=analysis_kw, fmts=fmts, report=report, lim=lim,
                          outlier_z=outlier_z, fleet_figures=fleet_figures, force=force, progress=progress, t0=t0)
    except ClusterError:
        if created:  # nothing was analysed: leave no trace of the attempt
            _remove_if_ours_and_empty(out_p)
        raise


def _run_batch(out_p: Path, files: list[str], *, created: bool, client: Any, scheduler: Optional[str],
               workers: Optional[int], read_kw: dict[str, Any], analysis_kw: dict[str, Any], fmts: list[str],
               report: bool, lim: Mapping[str, Any], outlier_z: float, fleet_figures: bool, force: bool,
               progress: Any, t0: float) -> FleetSummary:
    """The body of :func:`analyze_many` once its arguments are checked and ``out_p`` exists."""
    logs_dir = out_p / LOGS_DIR
    logs_dir.mkdir(exist_ok=True)
    settings = json_ready({"version": __version__, "read": read_kw, "analysis": analysis_kw, "figures": fmts,
                           "report": bool(report)})

    with _Lock(out_p):
        token = _check_settings(out_p, settings, force)
        results: dict[str, dict[str, Any]] = {}
        stats = {p: _stat(p) for p in files}
        todo = []
        index = {} if force else _read_index(out_p)
        for p in files:
            e = index.get(p)
            if e and e.get("status") == "ok" and e.get("name") and stats[p] is not None \
                    and [e.get("size"), e.get("mtime_ns")] == list(stats[p]):
                try:
                    rec = json.loads((logs_dir / e["name"] / _RECORD).read_text(encoding="utf-8"))
                except (OSError, ValueError):
                    rec = None
                if rec is not None and rec.get("sha256") == e.get("sha256") \
                        and rec.get("settings_token") == token:
                    results[p] = {**rec, "path": p, "reused": True}
                    continue
            todo.append(p)
        bar = _Progress(len(files), progress)
        for rec in results.values():
            bar.update(rec)
        journal = _Journal(out_p)
        closer: Callable[[], None] = lambda: None
        futures: list[Any] = []
        local = client is None and scheduler is None
        try:
            if todo:
                distributed = _distributed()
                n_workers, note = local_worker_count(workers, len(todo), usable_cores())
                if local and note:
                    warnings.warn(note, SigmaTauWarning, stacklevel=3)
                cl, closer = _connect(client, scheduler, n_workers)
                # Key: the log and settings, plus this run: a key of an interrupted run may still be
                # being cancelled on the scheduler, and reusing it would hand back its CancelledError.
                run = uuid.uuid4().hex[:8]
                keys = {}
                for p in todo:
                    st = stats[p] or (0, 0)
                    keys[p] = f"sigmatau-log-{_stem(p)}-" + hashlib.sha256(
                        f"{p}\0{st[0]}\0{st[1]}\0{logs_dir.resolve()}\0{token}\0{force}".encode()
                    ).hexdigest()[:16] + f"-{run}"
                futures = [cl.submit(_analyse_one, p, str(logs_dir.resolve()), read_kw, analysis_kw, fmts,
                                     bool(report), bool(force), token, key=keys[p], pure=False) for p in todo]
                path_of = {f.key: p for f, p in zip(futures, todo)}
                # Through this client's own event loop: as_completed() would otherwise look for the
                # process's default client, which batch never makes (and a user need not have).
                for fut in distributed.as_completed(futures, loop=cl.loop):
                    p = path_of[fut.key]
                    try:
                        rec = fut.result()
                    except Exception as exc:  # KilledWorker, CancelledError: the log failed, the rest go on
                        rec = _error_record(p, exc)
                    rec = {**rec, "path": p}
                    fut.release()
                    results[p] = rec
                    journal.append(rec, stats[p])
                    bar.update(rec)
        finally:
            bar.close()
            journal.close()
            pending = [f for f in futures if not f.done()]
            if pending:
                with contextlib.suppress(Exception):  # a cluster already gone has nothing left to cancel
                    cl.cancel(pending)
            closer()
            # Leftovers of attempts that died or were cancelled (the lock says no other run writes
            # here). Also after an interruption, but only once no task of ours can still be writing:
            # the local cluster is closed; a cancelled task may still run on a cluster of the user's.
            if local or not pending:
                _remove_leftovers(logs_dir)

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
        fleet = _build_fleet(out_p, list(ok.values()), errors, limits=lim, outlier_z=float(outlier_z),
                             computed=computed, reused=reused, seconds=time.perf_counter() - t0,
                             figures=fleet_figures)
    return replace(fleet, seconds=time.perf_counter() - t0)


def _remove_leftovers(logs_dir: Path) -> None:
    for d in logs_dir.glob(".*"):
        if not any(tag in d.name for tag in (".staging-", ".partial-", ".old-")):
            continue
        shutil.rmtree(d, ignore_errors=True) if d.is_dir() else d.unlink(missing_ok=True)
