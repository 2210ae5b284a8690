"""The main job: every statistic, the noise types and the IMU model of every channel of a log.

:func:`analyze_log` takes a :class:`~sigmatau.io.SensorLog` (from
:func:`sigmatau.io.read` or built in memory) and returns a :class:`LogAnalysis`:
per channel the chosen statistics with noise type, EDF and interval at every τ,
and — for gyroscope and accelerometer channels with a known unit — the IMU noise
model (:func:`sigmatau.imu.analyze`), a comparison with datasheet figures, and
the Kalibr entry of the whole IMU. :mod:`sigmatau.outputs` writes it to a
directory; the ``sigmatau analyze`` command does both.

It only calls the public API; nothing here computes a statistic of its own.

Examples
--------
>>> import numpy as np
>>> from sigmatau.analysis import analyze_log, log_from_arrays
>>> from sigmatau.imu import simulate
>>> gx = simulate("euroc-gyro", duration=600.0, rng=1)
>>> log = log_from_arrays({"gyro_x": gx}, rate=200.0, units={"gyro_x": "rad/s"})
>>> a = analyze_log(log, statistics=("oadev", "mdev"))
>>> ch = a.channel("gyro_x")
>>> sorted(ch.results), ch.model.N.resolved
(['mdev', 'oadev'], True)
"""

from __future__ import annotations

import dataclasses
import hashlib
import math
import os
import time
import warnings
from concurrent.futures import ThreadPoolExecutor
from typing import Any, Callable, Mapping, Optional, Sequence, Union

import numpy as np

from ..uncertainty.confidence import ONE_SIGMA
from ..errors import DataError, ParameterError, SigmaTauError, SigmaTauWarning, caller_stacklevel
from ..core.result import StabilityResult
from ..core.shared import shared_record
from ..stats import FUNCTIONS
from ..uncertainty.attach import attach
from .prepare import Preparation, prepare_log
from .results import ChannelAnalysis, IMU_GROUPS, LogAnalysis, SI_TERM_UNITS, TERMS, json_ready

__all__ = [
    "DEFAULT_STATISTICS",
    "STATISTICS",
    "STEP_COST",
    "ChannelAnalysis",
    "StepEvent",
    "LogAnalysis",
    "Preparation",
    "analyze_log",
    "log_from_arrays",
    "datasheet_reference",
    "json_ready",
    "IN_MEMORY_PEAK",
    "memory_needed",
    "check_statistics",
    "kalibr_entry",
    "tdev_from_mdev",
]

#: Statistics computed by default (the issue's choice: the overlapping and
#: modified Allan deviations, the time deviation, the overlapping Hadamard
#: deviation, the total deviation and TheoH, each where the record allows).
DEFAULT_STATISTICS = ("oadev", "mdev", "tdev", "ohdev", "totdev", "theoh")

#: Statistics :func:`analyze_log` can compute: every one of :data:`sigmatau.stats.FUNCTIONS`.
STATISTICS = tuple(FUNCTIONS)


Reference = Mapping[str, Mapping[str, "tuple[float, str]"]]

#: Relative cost of each step of a channel, for the time left of a progress display: seconds per
#: step on one 21.6-million-sample channel of bench/main_job.py (the IMU model includes its OADEV
#: and data checks; TDEV is derived from MDEV; OADEV alone, about the model less its checks). A
#: statistic not listed counts as 2.
STEP_COST = {"model": 3.7, "oadev": 2.0, "mdev": 2.6, "tdev": 0.05, "ohdev": 1.7, "totdev": 1.5, "theoh": 1.8}


@dataclasses.dataclass(frozen=True)
class StepEvent:
    """One step of :func:`analyze_log` starting or ending, for a progress display.

    Attributes
    ----------
    channel : str
        The channel.
    step : str
        ``"model"`` (the IMU noise model) or a statistic name.
    done : bool
        False when the step starts, True when it has ended (computed or skipped).
    weight : float
        The step's estimated share of the job (:data:`STEP_COST`).
    total : float
        The sum of the weights of every step of the job.
    """

    channel: str
    step: str
    done: bool
    weight: float
    total: float


# ----------------------------------------------------------------------- helpers


def log_from_arrays(channels: Mapping[str, Any], *, rate: float, units: Optional[Mapping[str, str]] = None,
                    groups: Optional[Mapping[str, Sequence[str]]] = None, data_type: str = "freq",
                    name: str = "<memory>") -> Any:
    """A :class:`~sigmatau.io.SensorLog` from arrays already in memory (simulations, notebooks).

    Parameters
    ----------
    channels : mapping of str to array_like
        Samples per channel, all of the same length. Channels named ``gyro_*``
        and ``accel_*`` are grouped as gyro and accel unless ``groups`` says
        otherwise.
    rate : float
        Sample rate in Hz.
    units : mapping of str to str, optional
        Unit per channel.
    groups : mapping, optional
        Group → channel names.
    data_type : {"freq", "phase"}
    name : str
        Shown as the log's source path.
    """
    from ..core.validate import check_rate
    from ..io import Source, SensorLog, TimingReport

    rate_f = check_rate(rate)
    if not channels:
        raise DataError("no channels given")
    arrays = {str(k): np.asarray(v, dtype=np.float64) for k, v in channels.items()}
    sizes = {a.shape for a in arrays.values()}
    if len(sizes) != 1 or len(next(iter(sizes))) != 1:
        raise DataError(f"every channel must be one-dimensional and of the same length, got shapes {sorted(sizes)}")
    if groups is None:
        grp: dict[str, list[str]] = {}
        for k in arrays:
            g = k.split("_")[0] if k.split("_")[0] in IMU_GROUPS else ("other" if data_type == "freq" else "phase")
            grp.setdefault(g, []).append(k)
        groups = grp
    n = next(iter(arrays.values())).size
    digest = hashlib.sha256()
    for a in arrays.values():
        digest.update(np.ascontiguousarray(a).tobytes())
    units = dict(units or {})
    return SensorLog(
        channels=arrays, rate=rate_f, timestamps=None,
        groups={g: tuple(v) for g, v in groups.items()},
        units={k: units.get(k, "") for k in arrays},
        data_type=data_type,  # type: ignore[arg-type]
        source=Source(path=name, format="memory", sha256=digest.hexdigest(), size=int(n * 8 * len(arrays)),
                      detail="arrays in memory", columns=tuple(arrays)),
        timing=TimingReport(samples=n, rows=n, rate=rate_f, rate_source="declared"),
        unit_origin={k: ("declared" if units.get(k) else "") for k in arrays},
    )


def datasheet_reference(spec: Union[str, Mapping[str, Any], None]) -> dict[str, dict[str, tuple[float, str]]]:
    """Datasheet figures by group: ``{"gyro": {"N": (value, unit)}, "accel": {...}}``.

    Parameters
    ----------
    spec : str or mapping or None
        A part with presets in :data:`sigmatau.imu.PRESETS` (``"lsm6dsl"``,
        ``"lsm6dsm"``, ``"adis16448"``, ``"euroc"``) — the preset's non-zero
        terms in SI — or a mapping group → term → ``(value, unit)`` or a
        string ``"value unit"``.
    """
    from ..imu.model import PRESETS

    if spec is None:
        return {}
    if isinstance(spec, str):
        key = spec.strip().lower()
        found = {g: PRESETS[f"{key}-{g}"] for g in IMU_GROUPS if f"{key}-{g}" in PRESETS}
        if not found:
            parts = sorted({k.rsplit("-", 1)[0] for k in PRESETS})
            raise ParameterError(f"unknown datasheet {spec!r}; known parts: {', '.join(parts)}")
        return {g: {t: (float(getattr(p, t)), SI_TERM_UNITS[g][t]) for t in TERMS if getattr(p, t) > 0}
                for g, p in found.items()}
    out: dict[str, dict[str, tuple[float, str]]] = {}
    for group, terms in spec.items():
        if group not in IMU_GROUPS:
            raise ParameterError(f"datasheet group {group!r} must be 'gyro' or 'accel'")
        out[group] = {}
        for term, value in terms.items():
            if term not in TERMS:
                raise ParameterError(f"datasheet term {term!r} must be one of {', '.join(TERMS)}")
            out[group][term] = _value_unit(value, f"{group}.{term}")
    return out


def _value_unit(value: Any, what: str) -> tuple[float, str]:
    from ..imu.units import convert

    if isinstance(value, str):
        text = value.strip()
        num, _, unit = text.partition(" ")
        try:
            v = float(num)
        except ValueError:
            raise ParameterError(f"datasheet {what}={value!r} must be 'value unit', e.g. '4 mdps/sqrt(Hz)'") from None
        value = (v, unit.strip())
    try:
        v, unit = float(value[0]), str(value[1])
    except (TypeError, ValueError, IndexError):
        raise ParameterError(f"datasheet {what}={value!r} must be (value, unit)") from None
    if not math.isfinite(v) or v <= 0:
        raise ParameterError(f"datasheet {what}={value!r}: the value must be positive")
    try:
        convert(1.0, unit, unit)
    except SigmaTauError:
        raise ParameterError(f"datasheet {what}: unknown unit {unit!r}") from None
    return v, unit


# ----------------------------------------------------------------------- analysis


def check_statistics(statistics: Sequence[str]) -> tuple[str, ...]:
    """``statistics`` (names, or one comma-separated string) checked against :data:`STATISTICS`, in
    order, each once; a ParameterError naming the unknown one."""
    if isinstance(statistics, str):
        statistics = [s for s in statistics.replace(" ", "").split(",") if s]
    out = []
    for s in statistics:
        name = str(s).strip().lower()
        if name not in STATISTICS:
            raise ParameterError(f"unknown statistic {s!r}; choose from {', '.join(STATISTICS)}")
        if name not in out:
            out.append(name)
    if not out:
        raise ParameterError("no statistic chosen")
    return tuple(out)


def _no_step(step: str, done: bool) -> None:
    """The step callback when nobody watches."""


def _channel(log: Any, name: str, statistics: tuple[str, ...], taus: Any, confidence: float,
             reference: Mapping[str, Mapping[str, tuple[float, str]]], model_wanted: bool,
             options: Optional[Mapping[str, Mapping[str, Any]]] = None, step: Callable[[str, bool], None] = _no_step,
             dynamic_spec: Optional[tuple[float, float]] = None, gauss_markov: str = "auto") -> ChannelAnalysis:
    from ..imu import model as imu
    from ..imu.units import sensor_unit

    t0 = time.perf_counter()
    x = log[name]
    group = log.group_of(name)
    unit = log.units.get(name, "")
    model = None
    note = ""
    if model_wanted and group in IMU_GROUPS:
        step("model", False)
        try:
            su = sensor_unit(unit)
        except SigmaTauError:
            su = None
        if su is None or su.kind != group:
            note = f"unit {unit!r} is not a known {group} unit; declare it (--{group}-unit)"
        elif log.data_type != "freq":
            note = "the IMU model needs rate/specific-force samples, not phase data"
        else:
            try:
                model = imu.analyze(x, rate=log.rate, unit=su.name, taus=taus, confidence=confidence,
                                    gauss_markov=gauss_markov)
            except DataError as exc:
                note = str(exc)
            except (ArithmeticError, np.linalg.LinAlgError) as exc:
                # The fit's linear algebra fails on data far from unit scale (an SVD that does
                # not converge at 1e-100): the statistics stand, the model is skipped with why.
                note = f"IMU model not fitted: numerical failure in the fit ({type(exc).__name__}: {exc})"
        step("model", True)
    elif model_wanted:
        note = f"{group} channel: the IMU model applies to gyro and accel channels"
    results: dict[str, StabilityResult] = {}
    skipped: dict[str, str] = {}
    for stat in statistics:
        step(stat, False)
        _statistic(stat, x, log, taus, confidence, (options or {}).get(stat, {}), model, results, skipped)
        step(stat, True)
    rows: tuple[dict, ...] = ()
    if model is not None and reference.get(group):
        rows = tuple(model.compare(reference[group]))
    dyn, dyn_note = None, ""
    if dynamic_spec is not None:
        step("dynamic", False)
        dyn, dyn_note = _dynamic(x, log, dynamic_spec, confidence)
        step("dynamic", True)
    return ChannelAnalysis(name=name, group=group, unit=unit, n_samples=int(x.size), results=results,
                           skipped=skipped, model=model, model_note=note, datasheet=rows,
                           seconds=time.perf_counter() - t0, dynamic=dyn, dynamic_note=dyn_note)


def _with_raw(ch: ChannelAnalysis, raw: Mapping[str, np.ndarray], log: Any, taus: Any,
              confidence: float) -> ChannelAnalysis:
    """The channel with ``oadev_raw``, the OADEV of its samples before the temperature compensation
    (drawn beside the compensated curve), when it was compensated."""
    if ch.name not in raw or "oadev" not in ch.results:
        return ch
    from ..stats.allan import oadev

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SigmaTauWarning)
        before = oadev(raw[ch.name], rate=log.rate, data_type=log.data_type, taus=taus, confidence=confidence)
    return dataclasses.replace(ch, results={**ch.results, "oadev_raw": before})


def _dynamic(x: np.ndarray, log: Any, spec: tuple[float, float], confidence: float) -> tuple[Any, str]:
    """OADEV over sliding windows of ``spec = (window, step)`` seconds, or None and why not."""
    from ..stats.dynamic import dynamic

    window, step_s = spec
    try:
        return dynamic(x, rate=log.rate, window=window, step=step_s, window_unit="seconds",
                       data_type=log.data_type, confidence=confidence), ""
    except (DataError, ParameterError) as exc:
        return None, str(exc)


def _statistic(stat: str, x: np.ndarray, log: Any, taus: Any, confidence: float, extra: Mapping[str, Any],
               model: Any, results: dict[str, StabilityResult], skipped: dict[str, str]) -> None:
    """Compute one statistic of a channel into ``results`` (or its reason into ``skipped``), with
    ``extra`` keywords for its function (TheoH's ``method``, Theo1's ``bias``)."""
    if stat == "oadev" and model is not None:
        results[stat] = model.result  # the very curve the model was fitted on
        return
    if stat == "tdev" and "mdev" in results:
        derived = tdev_from_mdev(results["mdev"])  # TVAR = τ²/3·MVAR: no second pass over the record
        if derived is not None:
            results[stat] = derived
            return
    try:
        results[stat] = FUNCTIONS[stat](x, rate=log.rate, data_type=log.data_type, taus=taus,
                                        confidence=confidence, **extra)
    except DataError as exc:
        skipped[stat] = str(exc)


def _plan(log: Any, names: Sequence[str], stats: tuple[str, ...], model: bool) -> dict[tuple[str, str], float]:
    """Every (channel, step) of the job with its estimated cost (:data:`STEP_COST`)."""
    plan: dict[tuple[str, str], float] = {}
    for name in names:
        with_model = model and log.group_of(name) in IMU_GROUPS
        if with_model:
            plan[(name, "model")] = STEP_COST["model"]
        for stat in stats:
            cost = STEP_COST.get(stat, 2.0)
            if (stat == "oadev" and with_model) or (stat == "tdev" and "mdev" in stats[:stats.index(stat)]):
                cost = 0.05  # taken from the model's curve / derived from MDEV
            plan[(name, stat)] = cost
    return plan


def tdev_from_mdev(mdev_result: StabilityResult) -> Optional[StabilityResult]:
    """TDEV of a record from its MDEV result, without computing MVAR again.

    .. math:: σ_x^2(τ) = \\frac{τ^2}{3}\\,\\mathrm{Mod}\\,σ_y^2(τ),\\quad τ = mτ_0

    (W. J. Riley, NIST SP 1065 (2008) §5.2.6). The variance is the one
    :func:`sigmatau.tdev` computes, bit for bit: the kernel forms the same product in the
    same order on data scaled by a power of two, and that scaling is exact. The
    noise type of each row is MDEV's (both are identified with the rules of the
    modified family at the same factors and term counts), and the EDF and interval
    are attached from it by the same step as :func:`tdev`.

    ``mdev_result`` must come from :func:`sigmatau.mdev` with ``ci="chi2"`` (as
    every statistic of the main job does). Returns None when it cannot stand for
    :func:`sigmatau.tdev`'s result: no noise type identified (``ci=None`` or a
    forced ``alpha``), a row whose noise type was not identified (the reason is
    tdev's own), or a variance float64 cannot hold. The caller computes TDEV then.
    """
    if mdev_result.statistic != "mdev" or mdev_result.alpha is None or mdev_result.alpha_estimate is None:
        return None
    if mdev_result.confidence is None or not np.all(np.isfinite(mdev_result.alpha)):
        return None
    tau0 = 1.0 / mdev_result.rate
    with np.errstate(over="ignore"):
        var = mdev_result.var * (mdev_result.m * tau0) ** 2 / 3.0
    if not np.all(np.isfinite(var)):
        return None
    raw = dataclasses.replace(
        mdev_result, statistic="tdev", var=var, dev=np.sqrt(var), alpha=None, alpha_estimate=None, edf=None,
        ci_low=None, ci_high=None, confidence=None, ci_reason=None,
    )
    return attach(raw, np.empty(0), mdev_result.data_type, alpha=None, confidence=mdev_result.confidence,
                  ci="chi2", identified=(mdev_result.alpha, mdev_result.alpha_estimate))


def _nothing_computed(n_samples: int, channel: ChannelAnalysis) -> str:
    """One line saying why no statistic could be computed, each distinct reason once."""
    by_reason: dict[str, list[str]] = {}
    for stat, reason in channel.skipped.items():
        # The statistics' own messages often start with their name: group on the rest.
        tail = reason[len(stat) + 2:] if reason.startswith(f"{stat}: ") else reason
        by_reason.setdefault(tail, []).append(stat)
    why = "; ".join(f"{', '.join(stats)}: {tail}" for tail, stats in by_reason.items())
    if all("at least" in r for r in channel.skipped.values()):
        return f"too few samples for any statistic ({n_samples} samples; {why})"
    return f"no statistic could be computed for channel {channel.name!r} ({n_samples} samples): {why}"


def analyze_log(
    log: Any,
    *,
    statistics: Union[str, Sequence[str]] = DEFAULT_STATISTICS,
    channels: Optional[Sequence[str]] = None,
    taus: Any = "octave",
    confidence: float = ONE_SIGMA,
    model: bool = True,
    axis_rule: str = "max",
    inflate: float = 1.0,
    rostopic: str = "/imu0",
    datasheet: Union[str, Mapping[str, Any], None] = None,
    workers: Optional[int] = None,
    progress: Optional[Callable[[str], None]] = None,
    theoh: str = "fast",
    on_step: Optional[Callable[[StepEvent], None]] = None,
    prep: Optional[Preparation] = None,
    dynamic: Optional[tuple[float, float]] = None,
    gauss_markov: str = "auto",
    theo1_bias: str = "none",
) -> LogAnalysis:
    """Compute the statistics, noise types and IMU model of every channel of a log.

    Parameters
    ----------
    log : SensorLog
        From :func:`sigmatau.io.read` or :func:`log_from_arrays`. A log read
        with ``gaps="split"`` is analysed on its longest gap-free segment (the
        statistics need evenly spaced samples); a note says which.
    statistics : sequence of str or str
        Names from :data:`STATISTICS` (comma-separated string accepted);
        default :data:`DEFAULT_STATISTICS`. A statistic the record is too
        short for is skipped with the reason.
    channels : sequence of str, optional
        Channels to analyse (default all).
    taus : str or array_like
        τ grid of every statistic (default octave).
    confidence : float
        Two-sided coverage of every interval (default ±1σ, 0.683).
    model : bool
        Fit the IMU model to gyro and accel channels.
    axis_rule : {"max", "rms", "mean"}
        How the three axes combine into the Kalibr values (default the largest).
    inflate : float
        Inflation factor of the Kalibr values (recorded).
    rostopic : str
        ``rostopic`` of the Kalibr entry.
    datasheet : str or mapping, optional
        Figures to compare with (:func:`datasheet_reference`).
    workers : int, optional
        Channels analysed at once (threads). Default: the usable cores, fewer
        when the memory available would not hold them (each needs about
        :data:`WORKER_MEMORY` times its channel's size).
    progress : callable, optional
        Called with a line of text as each channel finishes.
    on_step : callable, optional
        Called with a :class:`StepEvent` as each step of each channel (the IMU
        model, each statistic) starts and ends, from the worker threads; for
        a progress display with the time left (``sigmatau analyze`` draws one
        on a terminal). It must return quickly.
    theoh : {"fast", "exact"}
        How TheoH's TheoBR rows are computed (:func:`sigmatau.theoh` ``method``):
        ``"fast"`` (default) uses Fast TheoBR on block averages above 65,536
        phase points, unless κ indicates phase noise; ``"exact"`` the definition.
        docs/theoh-fast.md gives the difference.
    theo1_bias : {"none", "published"}
        Theo1 raw (default, as Stable32 prints it with Alpha forced to 0) or divided by
        Howe & Tasset's AVAR/Theo1 bias of the noise type identified at each τ
        (:func:`sigmatau.theo1` ``bias``).
    prep : Preparation, optional
        Steps applied to every channel first, in the order part → outliers → drift →
        average (:mod:`sigmatau.pipeline.prepare`); each channel's records of them are in
        :attr:`ChannelAnalysis.prep`. Missing samples (NaN) are gaps throughout.
    dynamic : (window, step) in seconds, optional
        Also compute OADEV over sliding windows of every channel and its stationarity
        check (:func:`sigmatau.dynamic`, Stable32's Dynamic Stability), in
        :attr:`ChannelAnalysis.dynamic`; a window or step that does not fit is a note.
    gauss_markov : {"auto", "never", "always"}
        The first-order Gauss–Markov term of the IMU model (:func:`sigmatau.imu.analyze`):
        fitted and kept when BIC prefers it (default), never, or always.

    Returns
    -------
    LogAnalysis

    Notes
    -----
    Each statistic is the public function of that name (``sigmatau.oadev`` …)
    with ``ci="chi2"``: noise type identified per τ, Greenhall/SP1065 EDF and
    χ² interval (numerics.md §5, §7). The model is :func:`sigmatau.imu.analyze`
    and its OADEV curve is the one reported as ``oadev``.
    """
    t0 = time.perf_counter()
    stats = check_statistics(statistics)
    if axis_rule not in ("max", "rms", "mean"):
        raise ParameterError(f"axis_rule={axis_rule!r} must be 'max', 'rms' or 'mean'")
    if not isinstance(confidence, (int, float)) or isinstance(confidence, bool) or not 0 < confidence < 1:
        raise ParameterError(f"confidence={confidence!r} must be a number between 0 and 1")
    if theoh not in ("fast", "exact"):
        raise ParameterError(f"theoh={theoh!r} must be 'fast' or 'exact'")
    if theo1_bias not in ("none", "published"):
        raise ParameterError(f"theo1_bias={theo1_bias!r} must be 'none' or 'published'")
    if gauss_markov not in ("auto", "never", "always"):
        raise ParameterError(f"gauss_markov={gauss_markov!r} must be 'auto', 'never' or 'always'")
    reference = datasheet_reference(datasheet)
    log, notes = _longest_segment(log)
    prepared = prepare_log(log, prep)
    log = prepared.log
    if prep and prep.describe():
        notes.append(f"prepared every channel: {prep.describe()}")
    notes.extend(prepared.notes)
    names = _channel_names(log, channels)
    workers = _worker_count(workers, len(names), max((log[n].nbytes for n in names), default=0))
    options = {"theoh": {"method": theoh}, "theo1": {"bias": theo1_bias}}
    done, seen = _analyse_channels(log, names, stats, taus, float(confidence), reference, model, workers, progress,
                                   options, on_step, dynamic, gauss_markov)
    done = [_with_raw(dataclasses.replace(c, prep=prepared.records.get(c.name, ())), prepared.raw, log, taus,
                      float(confidence)) for c in done]
    kalibr, kalibr_note = kalibr_entry(done, model, axis_rule, inflate, rostopic)
    settings = {"statistics": list(stats), "channels": names, "taus": taus if isinstance(taus, str) else
                list(np.asarray(taus, dtype=float)), "confidence": float(confidence), "ci": "chi2",
                "model": bool(model), "axis_rule": axis_rule, "inflate": float(inflate), "rostopic": rostopic,
                "datasheet": {g: {t: list(v) for t, v in terms.items()} for g, terms in reference.items()},
                "workers": workers, "theoh": theoh, "theo1_bias": theo1_bias,
                "prep": {k: v for k, v in dataclasses.asdict(prep).items() if v is not None} if prep else {},
                "dynamic": None if dynamic is None else [float(v) for v in dynamic], "gauss_markov": gauss_markov}
    return LogAnalysis(log=log, channels=tuple(done), settings=settings, kalibr=kalibr, kalibr_note=kalibr_note,
                       notes=tuple(notes), warnings=tuple(seen),
                       seconds=time.perf_counter() - t0)


def _longest_segment(log: Any) -> tuple[Any, list[str]]:
    """The log to analyse and a note: a log read with ``gaps="split"`` gives its longest gap-free segment."""
    if not (log.timing.gaps and log.timing.gaps_policy == "split"):
        return log, []
    segments = log.segments(min_samples=2)
    if not segments:
        raise DataError("no gap-free segment of at least 2 samples")
    best = max(range(len(segments)), key=lambda i: len(segments[i]))
    seg = segments[best]
    note = (f"split at {len(log.timing.gaps)} gap(s) into {len(segments)} segments; analysed the"
            f" longest, segment {best + 1} ({len(seg)} of {len(log)} samples)")
    return seg, [note]


def _channel_names(log: Any, channels: Optional[Sequence[str]]) -> list[str]:
    """The channels asked for (default all), each checked to exist."""
    names = list(log.names) if channels is None else [str(c) for c in channels]
    for n in names:
        log[n]  # one-line error naming the channels that exist
    if not names:
        raise DataError("the log has no channels")
    return names


#: Peak memory of one worker thread, in sizes of the channel it analyses (float64): the validated
#: samples, their mean-removed copy and MVAR's double window sums, measured on a 21.6-million-sample
#: channel (4.2), with a margin.
WORKER_MEMORY = 4.5


#: Peak memory of :func:`analyze_log` on a log it reads whole, in sizes of its samples as float64
#: (every channel and the time column): measured on the 24 h 1 kHz six-channel log of
#: bench/main_job.py (7.24 GB for 4.15 GB of samples) with the compiled kernels, 1.75; with the
#: numpy kernels (no numba, or SIGMATAU_NUMBA=0) their record-sized temporaries make it about 2.6.
IN_MEMORY_PEAK = {"compiled": 1.75, "numpy": 2.6}


def memory_needed(rows: int, columns: int) -> int:
    """Bytes the in-memory analysis of a log of ``rows`` × ``columns`` float64 values peaks at.

    ``columns`` counts the channels and the time column. The factor is :data:`IN_MEMORY_PEAK`'s for
    the kernels that would run: the compiled twins when numba imports and ``SIGMATAU_NUMBA`` is not
    ``0`` on a record of at least :data:`sigmatau.core.accel.FUSED_MIN_POINTS` points.

    >>> memory_needed(1000, 2) in (28000, 41600)
    True
    """
    from ..core.accel import fused_for

    kind = "compiled" if fused_for(rows) is not None else "numpy"
    return int(math.ceil(8 * rows * columns * IN_MEMORY_PEAK[kind]))


def _worker_count(workers: Optional[int], n_channels: int, channel_bytes: int = 0) -> int:
    """Threads to analyse the channels with: the request, else the usable cores as far as memory allows.

    The default never starts more workers than the memory available holds
    (:data:`WORKER_MEMORY` channel sizes each): on a small machine a long log is
    analysed one channel at a time rather than swapped. When even one does not
    fit, a :class:`~sigmatau.errors.SigmaTauWarning` says so and how much is needed.
    """
    if workers is None:
        workers = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
        need = WORKER_MEMORY * channel_bytes
        avail = available_memory()
        if need > 0 and avail is not None:
            fits = int(avail // need)
            if fits < 1:
                warnings.warn(
                    f"the analysis needs about {need / 2**30:.1f} GiB beyond the loaded log and"
                    f" {avail / 2**30:.1f} GiB are available: it may swap; `sigmatau analyze --memory chunked`"
                    " (sigmatau.chunked.analyze_file) analyses the log without loading it",
                    SigmaTauWarning, stacklevel=caller_stacklevel())
            workers = max(1, min(workers, fits))
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise ParameterError(f"workers={workers!r} must be a positive integer")
    return min(workers, n_channels)


def available_memory() -> Optional[float]:
    """Bytes that new allocations may use: :func:`sigmatau.io.memory_budget` (the least of
    ``MemAvailable``, the cgroup limit and ``ulimit -v``), or None when none is known."""
    from ..io import memory_budget

    return memory_budget()


def _analyse_channels(log: Any, names: list[str], stats: tuple[str, ...], taus: Any, confidence: float,
                      reference: Mapping[str, Mapping[str, tuple[float, str]]], model: bool, workers: int,
                      progress: Optional[Callable[[str], None]],
                      options: Optional[Mapping[str, Mapping[str, Any]]] = None,
                      on_step: Optional[Callable[[StepEvent], None]] = None,
                      dynamic: Optional[tuple[float, float]] = None, gauss_markov: str = "auto",
                      ) -> tuple[list[ChannelAnalysis], list[str]]:
    """Every channel analysed (in threads), and the distinct warnings they raised."""
    plan = _plan(log, names, stats, model) if on_step is not None else {}
    total = sum(plan.values())

    def one(name: str) -> ChannelAnalysis:
        def step(what: str, finished: bool) -> None:
            if on_step is not None:
                on_step(StepEvent(name, what, finished, plan.get((name, what), 0.0), total))

        # The statistics and the model of a channel share its validated samples, phase and
        # noise identification (computed once instead of once per statistic).
        with shared_record(log[name], statistics=stats):
            ch = _channel(log, name, stats, taus, confidence, reference, model, options, step, dynamic, gauss_markov)
        if progress is not None:
            progress(f"{name}: {', '.join(ch.results) or 'no statistic'} in {ch.seconds:.1f} s")
        return ch

    # Warnings from the worker threads reach this (process-wide) recorder too.
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        if workers == 1:
            done = [one(n) for n in names]
        else:
            with ThreadPoolExecutor(max_workers=workers, thread_name_prefix="sigmatau") as pool:
                done = list(pool.map(one, names))
    if not any(c.results for c in done):
        raise DataError(_nothing_computed(len(log), done[0]))
    return done, distinct_warnings(caught)


def distinct_warnings(caught: Sequence[Any]) -> list[str]:
    """The distinct warnings recorded while channels were analysed, as ``"Category: message"``,
    in order; IMU warnings are left out (already in the model's flags, with their channel)."""
    from ..imu.model import ImuWarning

    seen: list[str] = []
    for w in caught:
        if issubclass(w.category, ImuWarning):
            continue
        text = f"{w.category.__name__}: {w.message}"
        if text not in seen:
            seen.append(text)
    return seen


def kalibr_entry(done: Sequence[ChannelAnalysis], model: bool, axis_rule: str, inflate: float,
                  rostopic: str) -> tuple[Optional[dict[str, Any]], str]:
    """The Kalibr values from the gyro and accel models (or None) and a note when there are none."""
    from ..imu.model import kalibr_config

    gyro = [c.model for c in done if c.group == "gyro" and c.model is not None]
    accel = [c.model for c in done if c.group == "accel" and c.model is not None]
    if gyro and accel:
        kalibr = kalibr_config(gyro=gyro, accel=accel, rule=axis_rule, inflate=inflate,  # type: ignore[arg-type]
                               rostopic=rostopic)
        kalibr["axes"] = {"gyroscope": [c.name for c in done if c.group == "gyro" and c.model is not None],
                          "accelerometer": [c.name for c in done if c.group == "accel" and c.model is not None]}
        # Kalibr's values stand for all three axes: say when fewer went into them.
        short = [f"{sensor} from {len(axes)} of 3 axes ({', '.join(axes)})"
                 for sensor, axes in kalibr["axes"].items() if len(axes) < 3]
        kalibr["axes_note"] = "; ".join(short)
        return kalibr, ""
    if model:
        missing = [g for g, ms in (("gyroscope", gyro), ("accelerometer", accel)) if not ms]
        return None, f"Kalibr needs both sensors; no {' and no '.join(missing)} model"
    return None, ""
