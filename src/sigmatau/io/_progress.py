"""A small progress bar on stderr for long reads (no dependency).

It draws only when enabled (by default: when stderr is a terminal) and only
once a read has lasted ``delay`` seconds, so short reads print nothing.
"""

from __future__ import annotations

import sys
import time
from typing import TextIO

__all__ = ["Progress"]


def _human(n: float, unit: str) -> str:
    if unit != "bytes":
        return f"{n:,.0f}"
    for suffix, scale in (("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if n >= scale:
            return f"{n / scale:.1f} {suffix}"
    return f"{n:.0f} B"


class Progress:
    """Progress of one read: ``update(done)`` with bytes (or messages) done so far.

    Parameters
    ----------
    total : int or None
        Amount expected (None: unknown, the bar shows the amount done).
    label : str
        Text before the bar.
    enabled : bool or None
        True: draw; False: never draw; None: draw when ``stream`` is a terminal.
    unit : str
        "bytes" or a noun for counted items ("messages", "rows").
    stream : file, optional
        Where to draw (default: ``sys.stderr`` at construction).
    delay : float, optional
        Seconds before the first drawing (default: the class attribute ``DELAY``).
    """

    width = 24
    DELAY = 0.5
    clock = staticmethod(time.monotonic)

    def __init__(
        self,
        total: int | None,
        label: str,
        *,
        enabled: bool | None = None,
        unit: str = "bytes",
        stream: TextIO | None = None,
        delay: float | None = None,
    ) -> None:
        self.stream = sys.stderr if stream is None else stream
        if enabled is None:
            isatty = getattr(self.stream, "isatty", None)
            enabled = bool(isatty and isatty())
        self.enabled = enabled
        self.total = total if total and total > 0 else None
        self.label = label
        self.unit = unit
        self.delay = self.DELAY if delay is None else delay
        self.start = self.clock()
        self.last = 0.0
        self.drawn = 0  # length of the last line drawn

    def set_total(self, total: int | None, unit: str | None = None) -> None:
        self.total = total if total and total > 0 else None
        if unit is not None:
            self.unit = unit

    def update(self, done: float) -> None:
        if not self.enabled:
            return
        now = self.clock()
        if now - self.start < self.delay or now - self.last < 0.1:
            return
        self.last = now
        self._draw(done)

    def _draw(self, done: float) -> None:
        if self.total:
            frac = min(max(done / self.total, 0.0), 1.0)
            filled = int(round(frac * self.width))
            bar = "#" * filled + "-" * (self.width - filled)
            text = (
                f"{self.label} [{bar}] {100 * frac:3.0f}% "
                f"{_human(done, self.unit)}/{_human(self.total, self.unit)}"
            )
        else:
            text = f"{self.label} {_human(done, self.unit)}"
        if self.unit not in ("bytes",):
            text += f" {self.unit}"
        pad = " " * max(self.drawn - len(text), 0)
        self.stream.write("\r" + text + pad)
        self.stream.flush()
        self.drawn = len(text)

    def close(self) -> None:
        """Erase the bar (a finished read leaves the terminal as it was)."""
        if self.drawn:
            self.stream.write("\r" + " " * self.drawn + "\r")
            self.stream.flush()
            self.drawn = 0

    def __enter__(self) -> "Progress":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
