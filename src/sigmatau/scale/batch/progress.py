"""The progress of a batch: a bar on a terminal, a line per log, or a callable of the caller's."""

from __future__ import annotations

import sys
import time
from typing import Any, Mapping


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
