"""The preparation steps of the main job, applied to every channel of a log before its statistics.

The order is fixed and documented (docs/prep.md): **part → warm-up → temperature → outliers →
drift → average**. A part first, so that every later estimate reads only the samples analysed;
the warm-up cut before the temperature fit, which would otherwise read the settling transient as
temperature dependence (docs/warmup-temperature.md); outliers before the drift, so that a spike
cannot tilt the drift fit; the drift before averaging, so that it is estimated at the full
resolution. Each step is the :mod:`sigmatau.prep` function of that name; its record (parameters,
estimates with standard errors, samples affected) goes with the channel into results.json and
the report.

The warm-up is cut from every channel at once (the latest end found on the gyro and accel
channels), so that the channels stay aligned. The temperature dependence is fitted per gyro and
accel channel against the log's temperature channel; the channel's samples before the
compensation are kept (:attr:`Prepared.raw`) for the σ–τ curve the figure shows beside the
compensated one.
"""

from __future__ import annotations

import warnings
from concurrent.futures import ThreadPoolExecutor
from dataclasses import asdict, dataclass, field, replace
from typing import Any, Callable, Optional, Union

import numpy as np

from ..errors import DataError, ParameterError, SigmaTauWarning
from ..prep import DRIFT_MODELS, average, drift, drop_warmup, outliers, part, temperature_fit, warmup

__all__ = ["Preparation", "Prepared", "prepare_log", "parse_part"]

#: Groups whose channels carry the sensor noise that the warm-up and temperature steps model.
_SENSOR_GROUPS = ("gyro", "accel")
#: False-alarm probability of the warm-up search over all the gyro and accel channels of a log.
WARMUP_ALPHA = 0.01
#: Customary units of a temperature coefficient, per group (per kelvin, i.e. per °C).
_TEMPCO_UNITS = {"gyro": "deg/h", "accel": "mg"}

#: Channel groups that hold no sensor noise: only the steps that keep the channels aligned
#: (part, average) apply to them.
_AUXILIARY = ("temperature",)


@dataclass(frozen=True)
class Preparation:
    """What to do to every channel before the statistics, in the order of the fields.

    Attributes
    ----------
    part : (start, stop) in seconds, optional
        Keep ``[start, stop)``, seconds from the first sample (either may be None).
    warmup : "auto", seconds, or None
        ``"auto"``: detect the settling of the bias after power-on on the gyro and accel
        channels (:func:`sigmatau.prep.warmup`) and analyse every channel from the latest end
        found; a number: leave out that many seconds; None (or ``"keep"``): keep everything.
    temperature : "auto" or None
        ``"auto"``: when the log has a temperature channel, fit each gyro and accel channel's
        bias against it (:func:`sigmatau.prep.temperature_fit`) and analyse the compensated
        residual; None (or ``"off"``): no compensation.
    outliers : float, optional
        Replace by gaps the samples farther than ``k`` robust standard deviations from the
        median (:func:`sigmatau.prep.outliers` with ``action="gap"``).
    drift : str, optional
        Remove the drift with this model (:data:`sigmatau.prep.DRIFT_MODELS`).
    average : int, optional
        Average m consecutive samples (the rate becomes rate/m).
    """

    part: Optional[tuple[Optional[float], Optional[float]]] = None
    warmup: Union[None, str, float] = None
    temperature: Optional[str] = None
    outliers: Optional[float] = None
    drift: Optional[str] = None
    average: Optional[int] = None

    def __post_init__(self) -> None:
        if self.warmup == "keep":
            object.__setattr__(self, "warmup", None)
        if self.temperature == "off":
            object.__setattr__(self, "temperature", None)
        w = self.warmup
        if w is not None and w != "auto" and (isinstance(w, (bool, str)) or not isinstance(w, (int, float))
                                              or not np.isfinite(w) or w < 0):
            raise ParameterError(f"warmup={w!r} must be 'auto', 'keep' or a non-negative number of seconds")
        if self.temperature not in (None, "auto"):
            raise ParameterError(f"temperature={self.temperature!r} must be 'auto' or 'off'")

    def __bool__(self) -> bool:
        return any(v is not None for v in asdict(self).values())

    def describe(self) -> str:
        """One line: the steps given explicitly, in order, e.g. ``"part 10–600 s, outliers k=5 (gaps), drift
        linear"`` (the warm-up and temperature steps say what they found in notes of their own)."""
        done = []
        if self.part is not None:
            a, b = self.part
            done.append(f"part {'start' if a is None else f'{a:g}'}–{'end' if b is None else f'{b:g}'} s")
        if self.outliers is not None:
            done.append(f"outliers k={self.outliers:g} (gaps)")
        if self.drift is not None:
            done.append(f"drift {self.drift}")
        if self.average is not None:
            done.append(f"average {self.average}")
        return ", ".join(done)


def parse_part(text: str) -> tuple[Optional[float], Optional[float]]:
    """``"START:END"`` in seconds (either side may be empty) as ``(start, stop)``.

    >>> parse_part("10:600"), parse_part(":60"), parse_part("5:")
    ((10.0, 600.0), (None, 60.0), (5.0, None))
    """
    if not isinstance(text, str) or text.count(":") != 1:
        raise ParameterError(f"part={text!r} must be START:END in seconds (either may be empty), e.g. 10:600")
    a, b = (s.strip() for s in text.split(":"))
    try:
        return (float(a) if a else None, float(b) if b else None)
    except ValueError:
        raise ParameterError(f"part={text!r} must be START:END in seconds (either may be empty), e.g. 10:600") from None


@dataclass(frozen=True)
class Prepared:
    """What :func:`prepare_log` returns.

    Attributes
    ----------
    log : SensorLog
        The prepared log (a new one; the input is not modified).
    records : dict of str to tuple of dict
        Each channel's step records, in order (:meth:`sigmatau.prep.PrepResult.to_dict`).
    raw : dict of str to numpy.ndarray
        The channels compensated for temperature, as they were before the compensation
        (averaged as the channel is, so that the two σ–τ curves compare).
    notes : list of str
        What was done to the log as a whole (the warm-up cut, a temperature fit that failed).
    """

    log: Any
    records: dict = field(default_factory=dict)
    raw: dict = field(default_factory=dict)
    notes: list = field(default_factory=list)


def prepare_log(log: Any, prep: Optional[Preparation]) -> Prepared:
    """The log with every channel prepared, each channel's records of the steps, and notes.

    Timestamps follow the part, the warm-up cut and the averaging (each average keeps the time of
    its first sample); the rate becomes rate/m.
    """
    if not prep:
        return Prepared(log)
    if prep.drift is not None and prep.drift not in DRIFT_MODELS.get(log.data_type, ()):
        models = ", ".join(DRIFT_MODELS.get(log.data_type, ()))
        raise ParameterError(f"drift={prep.drift!r} is not a model for {log.data_type} data; use one of: {models}")
    channels = dict(log.channels)
    t = log.timestamps
    records: dict[str, list[dict]] = {name: [] for name in channels}
    notes: list[str] = []
    if prep.part is not None:
        for name, x in channels.items():
            r = part(x, start=prep.part[0], stop=prep.part[1], rate=log.rate, unit="seconds")
            channels[name] = r.data
            records[name].append(r.to_dict())
            kept = r.details["range"]
        t = None if t is None else t[kept[0]:kept[1]]
    if prep.warmup is not None:
        looked_at = channels
        if prep.warmup == "auto" and prep.temperature is not None:
            looked_at = _without_temperature_dependence(log, channels)
        cut = _warmup_cut(log, channels, prep.warmup, records, notes, looked_at)
        if cut:
            channels = {k: v[cut:] for k, v in channels.items()}
            t = None if t is None else t[cut:]
    raw: dict[str, np.ndarray] = {}
    if prep.temperature is not None:
        _compensate(log, channels, records, raw, notes)
    for name in list(channels):
        aux = log.group_of(name) in _AUXILIARY
        x = channels[name]
        if prep.outliers is not None and not aux:
            r = outliers(x, k=prep.outliers, action="gap", data_type=log.data_type)
            x = r.data
            records[name].append(r.to_dict())
        if prep.drift is not None and not aux:
            r = drift(x, data_type=log.data_type, rate=log.rate, model=prep.drift)
            x = r.data
            records[name].append(r.to_dict())
        if prep.average is not None:
            r = average(x, factor=prep.average, data_type=log.data_type)
            x = r.data
            records[name].append(r.to_dict())
            if name in raw:
                raw[name] = average(raw[name], factor=prep.average, data_type=log.data_type).data
        channels[name] = x
    size = len(next(iter(channels.values())))
    if t is not None and prep.average:
        t = t[::prep.average][:size]  # each average (or phase point kept) at the time of its first sample
    new = replace(log, channels=channels, timestamps=None if t is None else t - t[0] if t.size else t,
                  rate=log.rate / prep.average if prep.average else log.rate)
    return Prepared(new, {k: tuple(v) for k, v in records.items()}, raw, notes)


def _noted(step: Callable[[], Any], what: str, notes: list) -> Any:
    """``step()``, its warnings (what it chose not to do, and why) turned into notes of the analysis."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", SigmaTauWarning)
        out = step()
    notes.extend(f"{what}: {w.message}" for w in caught if issubclass(w.category, SigmaTauWarning))
    for w in caught:
        if not issubclass(w.category, SigmaTauWarning):
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    return out


def _in_threads(step: Callable[[str], Any], names: list[str]) -> dict[str, Any]:
    """``step(name)`` for every name, two at a time (numpy releases the GIL in the passes over the
    record); a DataError is returned in place of the result. What a step warns about is also in its
    record's notes, from which the caller makes the analysis's notes (which say the channel)."""
    def guarded(name: str) -> Any:
        try:
            return step(name)
        except DataError as exc:
            return exc

    # the warning filters are process-wide: one recorder around the pool, as for the channels
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        with ThreadPoolExecutor(max_workers=min(2, max(1, len(names))), thread_name_prefix="sigmatau-prep") as pool:
            out = dict(zip(names, pool.map(guarded, names)))
    for w in caught:
        if not issubclass(w.category, SigmaTauWarning):
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    return out


def _sensor_channels(log: Any, channels: dict) -> list[str]:
    return [n for n in channels if log.group_of(n) in _SENSOR_GROUPS]


_NO_SERIES = np.empty(0)


def _warmup_cut(log: Any, channels: dict, mode: Union[str, float], records: dict, notes: list,
                looked_at: Optional[dict] = None) -> int:
    """Samples to leave out at the start: the latest warm-up end found on the gyro and accel
    channels (``"auto"``, on ``looked_at``: the channels or their temperature-compensated
    forms), or the given seconds. Each channel's record is appended."""
    sensors = _sensor_channels(log, channels)
    looked_at = channels if looked_at is None else looked_at
    if mode != "auto":
        cut = int(round(float(mode) * log.rate))
        for name in channels:
            records[name].append(drop_warmup(channels[name], rate=log.rate, seconds=float(mode)).to_dict())
        notes.append(f"warm-up: the first {float(mode):g} s ({cut} samples) left out, as asked")
        return cut
    if not sensors:
        notes.append("warm-up: not looked for (no gyro or accel channel)")
        return 0
    ends = {}
    # the latest end over the channels: each tested at 1 %/channels, so that a stationary log is
    # cut by a false alarm at most 1 % of the time (not 1 % per channel)
    # Only the records are kept: each result's series (a copy of its channel) is dropped in its
    # thread, not held for every channel at once (six channel copies were the peak of the main job).
    found = _in_threads(lambda name: replace(warmup(looked_at[name], rate=log.rate,
                                                    alpha=WARMUP_ALPHA / len(sensors)), data=_NO_SERIES),
                        sensors)
    for name in sensors:
        r = found[name]
        if isinstance(r, DataError):
            notes.append(f"warm-up of {name} not estimated: {r}")
            continue
        records[name].append(r.to_dict())
        if r.details.get("detected") and r.details.get("settled") and r.details.get("end_index"):
            ends[name] = int(r.details["end_index"])
        elif r.details.get("detected"):  # a transient found but not cut: say why (its first note)
            notes.append(f"warm-up of {name}: {r.notes[0]}")
    if not ends:
        notes.append(f"warm-up: nothing to leave out on {', '.join(sensors)}; the whole record is analysed"
                     " (--warmup keep to skip the check)")
        return 0
    last = max(ends, key=lambda k: ends[k])
    cut = ends[last]
    notes.append(f"warm-up: detected on {', '.join(ends)}; every channel analysed from {cut / log.rate:.6g} s"
                 f" ({cut} samples left out, the end found on {last}; --warmup keep to keep them)")
    return cut


def _without_temperature_dependence(log: Any, channels: dict) -> dict:
    """The gyro and accel channels less a first estimate of their temperature dependence, for the
    warm-up search: a temperature ramp left in reads as bias wander to the warm-up's noise model
    and ends the transient early (docs/warmup-temperature.md). The dependence is fitted after a
    first warm-up cut, then removed from the whole record (each channel as it is when it fails)."""
    temps = [n for n in channels if log.group_of(n) == "temperature"]
    sensors = _sensor_channels(log, channels)
    if not temps or not sensors:
        return channels
    temp = channels[temps[0]]
    out = dict(channels)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SigmaTauWarning)  # the final passes report what matters
        for name in sensors:
            x = channels[name]
            try:
                first = warmup(x, rate=log.rate, alpha=WARMUP_ALPHA / len(sensors))
                cut = int(first.details.get("end_index") or 0) if first.details.get("detected") else 0
                fit = temperature_fit(x[cut:], temp[cut:], rate=log.rate)
            except DataError:
                continue
            out[name] = x - _temperature_part(fit, temp)
    return out


def _temperature_part(fit: Any, temp: np.ndarray) -> np.ndarray:
    """The fitted temperature-dependent bias, Σ_j c_j·(T − T_ref)^j (j ≥ 1), at every sample."""
    dt = temp - fit.details["reference_temperature"]
    out = np.zeros_like(dt)
    for j in range(1, int(fit.details["order"]) + 1):
        out += fit.estimates[f"c{j}"].value * dt ** j
    return np.where(np.isnan(out), 0.0, out)


def _compensate(log: Any, channels: dict, records: dict, raw: dict, notes: list) -> None:
    """Temperature compensation of each gyro and accel channel against the log's temperature channel."""
    from ..imu.units import convert, sensor_unit

    temps = [n for n in channels if log.group_of(n) == "temperature"]
    if not temps:
        return
    temp = channels[temps[0]]
    for name in _sensor_channels(log, channels):
        unit = log.units.get(name, "")
        try:
            r = _noted(lambda: temperature_fit(channels[name], temp, rate=log.rate, unit=unit or None),
                       f"temperature fit of {name}", notes)
        except DataError as exc:
            notes.append(f"temperature compensation of {name} not done: {exc}")
            continue
        record = r.to_dict()
        tc = r.estimates.get("tempco")
        to = _TEMPCO_UNITS.get(log.group_of(name))
        if tc is not None and to is not None and unit:
            try:
                su = sensor_unit(unit)
                factor = float(convert(1.0, su.name, to))
                record["tempco_customary"] = {"value": tc.value * factor, "stderr": tc.stderr * factor,
                                              "unit": f"{to}/degC"}
            except (ParameterError, DataError, ValueError):
                pass
        raw[name] = channels[name]
        channels[name] = r.data
        records[name].append(record)
    if raw:
        notes.append(f"temperature: the bias of {', '.join(raw)} fitted against {temps[0]} and removed; the"
                     " statistics, the model and the Kalibr values are those of the compensated channels"
                     " (--temperature off to analyse them as recorded)")
