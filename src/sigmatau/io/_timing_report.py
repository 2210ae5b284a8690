"""The timing report of a sensor log: its rate, jitter and gaps."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

__all__ = ["Gap", "TimingReport"]


def _fmt_rate(rate: float | None) -> str:
    return "—" if rate is None else f"{rate:.6g} Hz"


def _fmt_seconds(s: float | None) -> str:
    if s is None:
        return "—"
    a = abs(s)
    if a == 0:
        return "0 s"
    if a < 1e-9:
        return f"{s:.3g} s"
    if a < 1e-6:
        return f"{s * 1e9:.3g} ns"
    if a < 1e-3:
        return f"{s * 1e6:.3g} µs"
    if a < 1:
        return f"{s * 1e3:.3g} ms"
    return f"{s:.6g} s"


@dataclass(frozen=True)
class Gap:
    """A step between two timestamps longer than ``gap_threshold`` nominal periods.

    Attributes
    ----------
    index : int
        Index of the first sample after the gap (the log's samples ``index - 1`` and
        ``index`` straddle it).
    time : float
        Time of the last sample before the gap, in s from the first sample.
    duration : float
        The step across the gap, in s.
    missing : int
        Samples missing at the nominal rate (``round(duration·rate) - 1``).
    """

    index: int
    time: float
    duration: float
    missing: int


@dataclass(frozen=True)
class TimingReport:
    """What the timestamps said and what was done about them.

    Attributes
    ----------
    samples : int
        Samples in the log (after sorting and dropping duplicates).
    rows : int
        Rows (or messages) read from the file.
    rate : float
        The sample rate used (Hz): the one given, the file's, or 1/median step.
    rate_source : str
        "given", "file" or "timestamps".
    measured_rate : float or None
        1 / median step between timestamps (None without timestamps).
    mean_rate : float or None
        (samples - 1) / span: below ``measured_rate`` when samples are missing.
    span : float
        Last minus first timestamp in s ((samples - 1)/rate without timestamps).
    jitter_rms, jitter_max : float or None
        Standard deviation and largest deviation from the median of the steps that
        are not gaps, in s.
    out_of_order : int
        Timestamps earlier than the one before them, in file order.
    duplicates : int
        Samples whose timestamp equals the previous one (after sorting);
        ``duplicates_differing`` of them carry values different from the kept sample.
    gaps : tuple of Gap
    gap_threshold : float
        Steps longer than this many median steps are gaps.
    time_column, time_unit, time_unit_reason : str or None
        Where the timestamps came from, their unit and how it was decided.
    unsorted_policy, duplicates_policy, gaps_policy : str
        The policies in force (see :func:`sigmatau.io.read`).
    actions : tuple of str
        What was done to the samples, in words.
    """

    samples: int
    rows: int
    rate: float
    rate_source: str
    measured_rate: float | None = None
    mean_rate: float | None = None
    span: float = 0.0
    jitter_rms: float | None = None
    jitter_max: float | None = None
    out_of_order: int = 0
    duplicates: int = 0
    duplicates_differing: int = 0
    gaps: tuple[Gap, ...] = ()
    gap_threshold: float = 1.5
    time_column: str | None = None
    time_unit: str | None = None
    time_unit_reason: str = ""
    unsorted_policy: str = "sort"
    duplicates_policy: str = "drop"
    gaps_policy: str = "refuse"
    actions: tuple[str, ...] = ()

    @property
    def has_timestamps(self) -> bool:
        return self.time_column is not None

    @property
    def missing(self) -> int:
        """Samples missing in all gaps together, at the nominal rate."""
        return sum(g.missing for g in self.gaps)

    def to_dict(self) -> dict[str, Any]:
        """Plain-Python dictionary (gaps as a list of dicts)."""
        out = {k: getattr(self, k) for k in self.__dataclass_fields__}
        out["gaps"] = [vars(g).copy() for g in self.gaps]
        out["actions"] = list(self.actions)
        return out

    def summary(self) -> str:
        """A few lines of text for a report."""
        lines = [f"samples: {self.samples} (rows read: {self.rows})",
                 f"rate: {_fmt_rate(self.rate)} ({self.rate_source})"]
        if self.has_timestamps:
            lines.append(
                f"timestamps: column {self.time_column!r} in {self.time_unit} ({self.time_unit_reason})"
            )
            lines.append(
                f"measured rate: {_fmt_rate(self.measured_rate)} (median step), mean {_fmt_rate(self.mean_rate)};"
                f" span {_fmt_seconds(self.span)}"
            )
            lines.append(f"jitter: rms {_fmt_seconds(self.jitter_rms)}, max {_fmt_seconds(self.jitter_max)}")
            lines.append(
                f"out of order: {self.out_of_order} (policy {self.unsorted_policy});"
                f" duplicated: {self.duplicates}, {self.duplicates_differing} with different values"
                f" (policy {self.duplicates_policy})"
            )
            gap_text = f"gaps (> {self.gap_threshold:g} steps): {len(self.gaps)}"
            if self.gaps:
                first = ", ".join(f"{_fmt_seconds(g.duration)} at {g.time:.6g} s" for g in self.gaps[:3])
                more = f", … {len(self.gaps) - 3} more" if len(self.gaps) > 3 else ""
                share = self.missing / self.samples if self.gaps_policy == "mark" and self.samples else None
                of = f" ({100 * share:.3g} % of the {self.samples})" if share is not None else ""
                gap_text += f", {self.missing} samples missing{of}: {first}{more}"
            lines.append(f"{gap_text} (policy {self.gaps_policy})")
        else:
            lines.append("timestamps: none (uniform sampling assumed)")
        lines.extend(f"action: {a}" for a in self.actions)
        return "\n".join(lines)
