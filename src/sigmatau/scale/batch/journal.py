"""``OUT/index.jsonl`` and resuming: which logs a rerun skips, and the cleanup of what a run leaves.

The journal gets a line per log as it finishes (append-only, fsynced); a rerun
takes a log whose size and modification time match its journal entry, and whose
directory holds the record of the same settings, without submitting it.
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import time
from pathlib import Path
from typing import Any, Mapping, Optional

from .common import _INDEX, _RECORD, _SETTINGS, LOGS_DIR


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
    """``(size, mtime_ns)`` of a log (a ROS 2 bag: total size, newest file); None when unreadable."""
    try:
        st = os.stat(path)
    except OSError:
        return None
    if os.path.isdir(path):  # a ROS 2 bag: its newest file
        times = [st.st_mtime_ns] + [q.stat().st_mtime_ns for q in Path(path).rglob("*") if q.is_file()]
        return (sum(q.stat().st_size for q in Path(path).rglob("*") if q.is_file()), max(times))
    return (st.st_size, st.st_mtime_ns)


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


def _remove_leftovers(logs_dir: Path) -> None:
    """Remove the staging, partial and replaced directories that unfinished attempts left in ``logs_dir``."""
    for d in logs_dir.glob(".*"):
        if not any(tag in d.name for tag in (".staging-", ".partial-", ".old-")):
            continue
        shutil.rmtree(d, ignore_errors=True) if d.is_dir() else d.unlink(missing_ok=True)


def _done_before(out: Path, files: list[str], stats: Mapping[str, Optional[tuple[int, int]]], token: str,
                 force: bool) -> dict[str, dict[str, Any]]:
    """Records of the logs a rerun takes from an earlier run without submitting them.

    A log is done before when its latest journal entry is ``ok``, names a
    directory, and has the log's current size and modification time, and that
    directory's ``record.json`` holds the same content hash and settings token.

    Parameters
    ----------
    out : Path
        The output directory.
    files : list of str
        The logs of this run.
    stats : mapping
        Path → ``(size, mtime_ns)`` now (:func:`_stat`), or None.
    token : str
        The settings token of this run.
    force : bool
        Recompute everything: nothing is done before.

    Returns
    -------
    dict
        Path → its record, marked ``reused``.
    """
    logs_dir = out / LOGS_DIR
    results: dict[str, dict[str, Any]] = {}
    index = {} if force else _read_index(out)
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
    return results
