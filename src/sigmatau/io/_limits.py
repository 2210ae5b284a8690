"""Limits that keep a hostile or broken file from exhausting the machine.

* :data:`MAX_CHANNELS`: channels read from one log (a 10,000-column table would
  otherwise plan 20,000 figures); more must be chosen with ``--columns``.
* :data:`MAX_LINE_CHARS`: characters in one line of a text file.
* :func:`memory_budget` / :func:`check_allocation`: a reader states what it is about
  to allocate (from declared sizes: a ``.npy`` header's shape × itemsize, a zip
  member's uncompressed size, an HDF5 or Parquet row count) and is refused when
  that exceeds the memory available — before allocating, so a zip bomb or a
  header that lies ends in one line instead of a MemoryError.
"""

from __future__ import annotations

import os
from pathlib import Path

from ..errors import DataError
from ._errors import option_hint

__all__ = ["MAX_CHANNELS", "MAX_LINE_CHARS", "memory_budget", "check_allocation", "check_channels", "fmt_bytes",
           "cgroup_available"]

#: Most channels read from one log; select others with ``columns=`` (``--columns``).
MAX_CHANNELS = 256

#: Longest line of a text log, in characters (a 10,000-column line of 20-character
#: numbers is 200,000; nothing legitimate comes near this).
MAX_LINE_CHARS = 1 << 20


def fmt_bytes(n: float) -> str:
    """Bytes in a short human form (binary prefixes).

    >>> fmt_bytes(2 * 1024**3), fmt_bytes(512)
    ('2.0 GiB', '512 B')
    """
    for unit, size in (("TiB", 1 << 40), ("GiB", 1 << 30), ("MiB", 1 << 20), ("KiB", 1 << 10)):
        if n >= size:
            return f"{n / size:.1f} {unit}"
    return f"{int(n)} B"


def _meminfo_available() -> int | None:
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemAvailable:"):
                return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):
        return None


def cgroup_available(root: Path = Path("/sys/fs/cgroup")) -> int | None:
    """Room left under a cgroup v2 memory limit.

    ``memory.current`` counts the page cache, which the kernel reclaims on demand
    (a container that has just read a 3 GB log is not out of memory): the cache
    (``file`` in ``memory.stat``) is not counted as used.
    """
    try:
        limit = (root / "memory.max").read_text().strip()
        if limit == "max":
            return None
        used = int((root / "memory.current").read_text().strip())
        cache = 0
        for line in (root / "memory.stat").read_text().splitlines():
            key, _, value = line.partition(" ")
            if key == "file":
                cache = int(value)
        return max(int(limit) - max(used - cache, 0), 0)
    except (OSError, ValueError):
        return None


def _rlimit_available() -> int | None:
    try:
        import resource
    except ImportError:  # not on Windows
        return None
    soft = resource.getrlimit(resource.RLIMIT_AS)[0]
    if soft == resource.RLIM_INFINITY:
        return None
    used = 0
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmSize:"):
                used = int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    return max(soft - used, 0)


def memory_budget() -> int | None:
    """Bytes this process can still allocate: the least of the free physical memory,
    the cgroup limit and the address-space limit (``ulimit -v``); None when none is known."""
    known = [b for b in (_meminfo_available(), cgroup_available(), _rlimit_available()) if b is not None]
    return min(known) if known else None


def check_allocation(display: str, nbytes: int, what: str) -> None:
    """Refuse, in one line naming the file, to allocate more than :func:`memory_budget`.

    ``what`` says what the bytes are for ("array 'x' of shape (…)").
    """
    budget = memory_budget()
    if budget is not None and nbytes > budget:
        raise DataError(
            f"{display}: {what} needs {fmt_bytes(nbytes)} of memory, more than the"
            f" {fmt_bytes(budget)} available; refused before allocating"
        )


def check_channels(display: str, count: int, what: str = "column") -> None:
    """Refuse to read more than :data:`MAX_CHANNELS` channels at once."""
    if count > MAX_CHANNELS:
        raise DataError(
            f"{display}: {count} numeric {what}s to read; at most {MAX_CHANNELS} channels are read at once:"
            f" choose them with {option_hint('--columns a,b,c', 'columns=[...]')}"
        )
