"""``OUT/batch.lock``: one run per output directory at a time, and a lock left by a dead run taken over."""

from __future__ import annotations

import contextlib
import json
import os
import socket
import time
import uuid
from pathlib import Path
from typing import Any, Mapping, Optional

from ...errors import ParameterError
from .common import _LOCK


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
    """This boot's id (``/proc/sys/kernel/random/boot_id``); None off Linux."""
    try:
        return Path("/proc/sys/kernel/random/boot_id").read_text(encoding="ascii").strip() or None
    except OSError:
        return None


def _pid_alive(pid: int) -> bool:
    """Whether a process ``pid`` exists on this host (``kill(pid, 0)``; another user's counts)."""
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
