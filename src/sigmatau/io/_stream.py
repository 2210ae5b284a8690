"""Inputs that can be read only once: FIFOs, ``<(cat log.csv)``, ``/dev/stdin``, character devices.

Opening such a path a second time does not start it again: whatever the first
reader took is gone (the first ~160 rows of a CSV went to format detection).
A :class:`OnceInput` opens the path once, keeps the first bytes for detection,
and hands the reader a stream that replays them before the rest.
"""

from __future__ import annotations

import io
import stat
from pathlib import Path

__all__ = ["OnceInput", "is_once", "HEAD_BYTES"]

#: Bytes kept for format detection (the magic numbers and the first text lines).
HEAD_BYTES = 8192


def is_once(path: Path) -> bool:
    """Whether an existing path can be read only once (not a regular file nor a directory)."""
    mode = path.stat().st_mode
    return not (stat.S_ISREG(mode) or stat.S_ISDIR(mode))


class _Replay(io.RawIOBase):
    """The kept head, then the rest of the underlying stream."""

    def __init__(self, head: bytes, rest: io.RawIOBase) -> None:
        self._head = memoryview(head)
        self._rest = rest

    def readable(self) -> bool:
        return True

    def readinto(self, b) -> int:  # type: ignore[no-untyped-def]
        if self._head:
            n = min(len(b), len(self._head))
            b[:n] = self._head[:n]
            self._head = self._head[n:]
            return n
        return self._rest.readinto(b) or 0

    def close(self) -> None:
        self._rest.close()
        super().close()


class OnceInput:
    """A path opened a single time: ``head`` for detection, :meth:`stream` for the reader.

    Examples
    --------
    >>> import os, tempfile, threading
    >>> fifo = os.path.join(tempfile.mkdtemp(), "pipe")
    >>> os.mkfifo(fifo)
    >>> def write() -> None:
    ...     with open(fifo, "w") as fh:
    ...         _ = fh.write("a,b\\n1,2\\n")
    >>> writer = threading.Thread(target=write)
    >>> writer.start()
    >>> once = OnceInput(Path(fifo))
    >>> once.head, once.stream().read()
    (b'a,b\\n1,2\\n', b'a,b\\n1,2\\n')
    >>> once.close(); writer.join()
    """

    def __init__(self, path: Path) -> None:
        self._raw = open(path, "rb", buffering=0)
        chunks: list[bytes] = []
        have = 0
        # a pipe returns what has been written so far: keep reading up to HEAD_BYTES or EOF
        while have < HEAD_BYTES:
            block = self._raw.read(HEAD_BYTES - have)
            if not block:
                break
            chunks.append(block)
            have += len(block)
        self.head = b"".join(chunks)
        self._taken = False

    def stream(self) -> io.RawIOBase:
        """The whole input from its first byte (only once)."""
        if self._taken:
            raise RuntimeError("the input was already handed to a reader")
        self._taken = True
        return _Replay(self.head, self._raw)

    def close(self) -> None:
        self._raw.close()
