"""What the main job returns: :class:`LogAnalysis` for a log, :class:`ChannelAnalysis` per channel.

Frozen dataclasses with their text summary and JSON-ready export; public
through :mod:`sigmatau.analysis`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Mapping, Optional

from .._version import __version__
from ..core.present import concat_frames, html_table, plot
from ..core.result import StabilityResult, json_ready
from ..errors import ParameterError

__all__ = [
    "IMU_GROUPS", "TERMS", "SI_TERM_UNITS", "ChannelAnalysis", "LogAnalysis", "format_parameter",
    "json_ready",
]


#: Groups whose channels get an IMU noise model.
IMU_GROUPS = ("gyro", "accel")


#: Terms of the IMU model, in order.
TERMS = ("Q", "N", "B", "K", "R")


#: SI unit of each term, per sensor kind (what presets are given in).
SI_TERM_UNITS = {
    "gyro": {"Q": "rad", "N": "rad/s/sqrt(Hz)", "B": "rad/s", "K": "rad/s^2/sqrt(Hz)", "R": "rad/s^2"},
    "accel": {"Q": "m/s", "N": "m/s^2/sqrt(Hz)", "B": "m/s^2", "K": "m/s^3/sqrt(Hz)", "R": "m/s^3"},
}


@dataclass(frozen=True)
class ChannelAnalysis:
    """Everything computed for one channel.

    Attributes
    ----------
    name, group, unit : str
        Channel name, its group ("gyro", "accel", "freq", "phase", "other" …)
        and the unit of its samples ("" when unknown).
    n_samples : int
    results : mapping of str to StabilityResult
        Statistic name → result, in the order asked for.
    skipped : mapping of str to str
        Statistic name → why it was not computed (record too short …).
    model : NoiseModel or None
        The IMU noise model (gyro and accel channels with a known unit).
    model_note : str
        Why there is no model, when there is none.
    datasheet : tuple of dict
        Datasheet comparison rows (:meth:`sigmatau.imu.NoiseModel.compare`).
    seconds : float
        Wall time spent on the channel.
    prep : tuple of dict
        The preparation steps applied to the channel before its statistics, in order
        (:meth:`sigmatau.prep.PrepResult.to_dict` of each; empty when none).
    dynamic : DynamicResult or None
        OADEV over sliding windows and its stationarity check (:func:`sigmatau.dynamic`),
        when asked for; ``dynamic_note`` says why there is none when it failed.
    """

    name: str
    group: str
    unit: str
    n_samples: int
    results: Mapping[str, StabilityResult]
    skipped: Mapping[str, str]
    model: Any = None
    model_note: str = ""
    datasheet: tuple[dict, ...] = ()
    seconds: float = 0.0
    prep: tuple[dict, ...] = ()
    dynamic: Any = None
    dynamic_note: str = ""

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary (NaN and inf as None)."""
        return json_ready({
            "name": self.name, "group": self.group, "unit": self.unit, "n_samples": self.n_samples,
            "prep": list(self.prep),
            "dynamic": self.dynamic.to_dict() if self.dynamic is not None else None,
            "dynamic_note": self.dynamic_note,
            "statistics": {k: r.to_dict() for k, r in self.results.items()},
            "skipped": dict(self.skipped),
            "model": self.model.to_dict() if self.model is not None else None,
            "model_note": self.model_note,
            "datasheet": list(self.datasheet),
            "seconds": self.seconds,
        })

    def _stat_rows(self) -> list[list[Any]]:
        """One row per statistic: name, τ range, deviation range, noise types seen; then the skipped ones."""
        from ..core.present import noise_name

        rows: list[list[Any]] = []
        for stat, r in self.results.items():
            types = sorted({noise_name(a) for a in (r.alpha.tolist() if r.alpha is not None else [])} - {""})
            rows.append([stat, len(r), f"{r.taus[0]:.3g} – {r.taus[-1]:.3g}" if len(r) else "—",
                         f"{r.dev[0]:.4g} – {r.dev[-1]:.4g}" if len(r) else "—", ", ".join(types) or "—"])
        rows += [[stat, 0, "—", "—", f"not computed: {why}"] for stat, why in self.skipped.items()]
        return rows

    def _repr_html_(self) -> str:
        """The channel's statistics (one row each) and its IMU model, as HTML for notebooks."""
        caption = f"{self.name}: {self.group}, unit {self.unit or '?'}, {self.n_samples:,} samples"
        table = html_table(["statistic", "τ points", "τ [s]", "deviation", "noise types"], self._stat_rows(),
                           caption=caption, notes=[f"no IMU model: {self.model_note}"] if self.model_note else ())
        return table + (self.model._repr_html_() if self.model is not None else "")

    def to_pandas(self) -> Any:
        """Every statistic of the channel in one tidy DataFrame (the rows of each
        :meth:`StabilityResult.to_pandas`, with ``channel``, ``group`` and ``unit`` columns).

        The deviations of TDEV/TTOT (time error) are in the phase unit; ``frame.attrs`` holds
        the channel, group, unit and sample count. Needs pandas (extra ``pandas``).
        """
        frames = []
        for r in self.results.values():
            f = r.to_pandas()
            f.insert(0, "unit", self.unit)
            f.insert(0, "group", self.group)
            f.insert(0, "channel", self.name)
            frames.append(f)
        return concat_frames(frames, attrs={"channel": self.name, "group": self.group, "unit": self.unit,
                                            "n_samples": self.n_samples})

    def plot(self, ax: Any = None, **kw: Any) -> Any:
        """Draw the channel's statistics (interval bands) and its fitted model on one log–log axes.

        Parameters
        ----------
        ax : matplotlib.axes.Axes, optional
            Axes to draw on; a new figure's when None.
        **kw
            ``statistics``: the names to draw (default all computed).

        Returns
        -------
        matplotlib.axes.Axes
        """
        return plot("channel", self, ax=ax, **kw)


@dataclass(frozen=True)
class LogAnalysis:
    """The analysis of one log (see :func:`~sigmatau.analysis.analyze_log`).

    Attributes
    ----------
    log : SensorLog
        The log analysed (the segment, when the log was split at gaps).
    channels : tuple of ChannelAnalysis
    settings : dict
        Every setting that shaped the result.
    kalibr : dict or None
        :func:`sigmatau.imu.kalibr_config` of the gyro and accel models.
    kalibr_note : str
        Why there is no Kalibr entry, when there is none.
    notes : tuple of str
        What was done to the data on the way (segment chosen …).
    warnings : tuple of str
        Warnings issued during the analysis, each once (those of the IMU model
        are in each model's ``flags``).
    version : str
        sigmatau version.
    seconds : float
        Wall time of the analysis.
    """

    log: Any
    channels: tuple[ChannelAnalysis, ...]
    settings: Mapping[str, Any]
    kalibr: Optional[dict] = None
    kalibr_note: str = ""
    notes: tuple[str, ...] = ()
    warnings: tuple[str, ...] = ()
    version: str = __version__
    seconds: float = 0.0

    def channel(self, name: str) -> ChannelAnalysis:
        """The analysis of one channel by name."""
        for ch in self.channels:
            if ch.name == name:
                return ch
        raise ParameterError(f"no channel {name!r}; channels are: {', '.join(c.name for c in self.channels)}")

    def groups(self) -> dict[str, list[ChannelAnalysis]]:
        """Channels by group, in log order."""
        out: dict[str, list[ChannelAnalysis]] = {}
        for ch in self.channels:
            out.setdefault(ch.group, []).append(ch)
        return out

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary of everything (NaN and inf as None)."""
        return json_ready({
            "tool": {"name": "sigmatau", "version": self.version},
            "input": {"path": self.log.source.path, "format": self.log.source.format,
                      "sha256": self.log.source.sha256, "size": self.log.source.size,
                      "topic": self.log.source.topic},
            "log": self.log.to_dict(),
            "settings": dict(self.settings),
            "notes": list(self.notes),
            "warnings": list(self.warnings),
            "channels": [c.to_dict() for c in self.channels],
            "kalibr": self.kalibr,
            "kalibr_note": self.kalibr_note,
            "seconds": self.seconds,
        })

    def _repr_html_(self) -> str:
        """One row per channel (statistics, and the model's N, B, K in SI), the Kalibr values and the
        notes and warnings, as HTML for notebooks."""
        log = self.log
        rows = []
        for ch in self.channels:
            terms = ["—"] * 3
            if ch.model is not None:
                terms = [format_parameter(getattr(ch.model, t).si()) for t in ("N", "B", "K")]
            rows.append([ch.name, ch.group, ch.unit or "?", ", ".join(ch.results) or "none", *terms])
        notes = [f"note: {n}" for n in self.notes]
        if self.kalibr is not None:
            k = self.kalibr
            notes.append(f"Kalibr ({k['axis_rule']}): " + ", ".join(
                f"{key} {k[key]:.4g}" for key in ("gyroscope_noise_density", "gyroscope_random_walk",
                                                  "accelerometer_noise_density", "accelerometer_random_walk")))
        elif self.kalibr_note:
            notes.append(f"no Kalibr entry: {self.kalibr_note}")
        notes += [f"warning: {w}" for w in self.warnings]
        caption = (f"sigmatau {self.version}: {log.source.path} ({log.source.format}), {len(log.channels)} channel(s)"
                   f" × {len(log):,} samples at {log.rate:.6g} Hz")
        return html_table(["channel", "group", "unit", "statistics", "N (SI)", "B (SI)", "K (SI)"], rows,
                          caption=caption, notes=notes)

    def to_pandas(self, what: str = "statistics") -> Any:
        """The analysis as one tidy DataFrame: ``"statistics"`` (every channel's
        :meth:`ChannelAnalysis.to_pandas`, stacked) or ``"model"`` (every IMU model's
        :meth:`~sigmatau.imu.NoiseModel.to_pandas` with a ``channel`` column).

        ``frame.attrs`` holds the input path, its SHA-256, the rate and the sigmatau version.
        Needs pandas (extra ``pandas``).
        """
        if what not in ("statistics", "model"):
            raise ParameterError(f"what={what!r} must be 'statistics' or 'model'")
        frames = []
        for ch in self.channels:
            if what == "statistics":
                frames.append(ch.to_pandas())
            elif ch.model is not None:
                f = ch.model.to_pandas()
                f.insert(0, "group", ch.group)
                f.insert(0, "channel", ch.name)
                frames.append(f)
        return concat_frames(frames, attrs={"input": self.log.source.path, "sha256": self.log.source.sha256,
                                            "rate_hz": self.log.rate, "version": self.version})

    def plot(self, ax: Any = None, **kw: Any) -> Any:
        """Draw one statistic of every channel of a group on one log–log axes (matplotlib).

        Parameters
        ----------
        ax : matplotlib.axes.Axes, optional
            Axes to draw on; a new figure's when None.
        **kw
            ``group`` (default the first group with results), ``statistic`` (default the
            first computed, OADEV by default), ``model`` (draw each channel's fitted model,
            default True).

        Returns
        -------
        matplotlib.axes.Axes
        """
        return plot("log", self, ax=ax, **kw)

    def summary(self) -> str:
        """Terminal summary: data checks, then per channel the model (SI and customary units) and flags."""
        log = self.log
        from ..imu.model import format_duration

        lines = [f"sigmatau {self.version}: {log.source.path} ({log.source.format}), {len(log.channels)} channel(s)"
                 f" × {len(log)} samples at {log.rate:.6g} Hz ({format_duration(len(log) / log.rate)})"]
        lines.append("timing: " + log.timing.summary().replace("\n", "\n  "))
        lines += [f"note: {n}" for n in self.notes]
        for ch in self.channels:
            lines.append("")
            got = ", ".join(ch.results) or "none"
            lines.append(f"[{ch.name}] {ch.group}, unit {ch.unit or '?'}: statistics {got}")
            for stat, why in ch.skipped.items():
                lines.append(f"  {stat}: not computed — {why}")
            if ch.model is not None:
                lines.append(_model_lines(ch.model))
            elif ch.model_note:
                lines.append(f"  no IMU model: {ch.model_note}")
            if ch.dynamic is not None:
                lines.append(f"  dynamic {ch.dynamic.statistic}: {ch.dynamic.stationarity.finding}")
            elif ch.dynamic_note:
                lines.append(f"  dynamic stability not computed: {ch.dynamic_note}")
            for row in ch.datasheet:
                verdict = "covers" if row["covers"] else "does not cover"
                lines.append(f"  datasheet {row['term']} = {row['reference_given']}: interval {verdict} it"
                             + (f" (ratio {row['ratio']:.3g})" if row.get("ratio") else ""))
        if self.kalibr is not None:
            k = self.kalibr
            lines.append("")
            lines.append(f"Kalibr imu.yaml ({k['axis_rule']}): gyroscope_noise_density"
                         f" {k['gyroscope_noise_density']:.4g}, gyroscope_random_walk {k['gyroscope_random_walk']:.4g},"
                         f" accelerometer_noise_density {k['accelerometer_noise_density']:.4g},"
                         f" accelerometer_random_walk {k['accelerometer_random_walk']:.4g}")
            if k["bounds_used"]:
                lines.append("  upper bounds used (not resolved): " + ", ".join(k["bounds_used"]))
            if k.get("axes_note"):
                lines.append(f"  fewer than three axes: {k['axes_note']}")
        elif self.kalibr_note:
            lines.append("")
            lines.append(f"no Kalibr imu.yaml: {self.kalibr_note}")
        if self.warnings:
            lines.append("")
            lines.append("warnings:")
            lines += [f"  - {w}" for w in self.warnings]
        return "\n".join(lines)


def _model_lines(model: Any) -> str:
    """The model as indented lines: each term in SI and customary units, then the flags."""
    out = []
    for t in TERMS:
        p = getattr(model, t)
        si = p.si()
        cust = "; ".join(format_parameter(c) for c in p.customary())
        out.append(f"  {t} {_TERM_NAMES[model.kind][t]:<26} {format_parameter(si):<44} {cust}")
    gm = getattr(model, "gauss_markov", None)
    if gm is not None:
        out.append(f"  GM (Gauss–Markov)            σ {format_parameter(gm.sigma)}, correlation time"
                   f" {format_parameter(gm.tau_c)} ({gm.criterion} prefers it by {gm.delta_bic:.3g}; not in the"
                   " Kalibr entry)")
    for f in model.flags:
        out.append(f"  ! [{f.code}{' ' + f.term if f.term else ''}] {f.message}")
    return "\n".join(out)


_TERM_NAMES = {
    "gyro": {"Q": "(angle quantisation)", "N": "(angle random walk)", "B": "(bias instability)",
             "K": "(rate random walk)", "R": "(rate ramp)"},
    "accel": {"Q": "(velocity quantisation)", "N": "(velocity random walk)", "B": "(bias instability)",
              "K": "(acceleration random walk)", "R": "(acceleration ramp)"},
}


def format_parameter(p: Any) -> str:
    """``value [low, high] unit``, ``< bound unit`` when not resolved (terminal and report)."""
    from ..imu.units import pretty

    if not p.resolved:
        return f"< {p.high:.3g} {pretty(p.unit)}" if math.isfinite(p.high) else "not resolved"
    return f"{p.value:.4g} [{p.low:.4g}, {p.high:.4g}] {pretty(p.unit)}"


