"""The main job on a log larger than memory: ``sigmatau analyze`` out of core, chosen automatically.

:func:`memory_plan` estimates, before reading, the peak of the in-memory analysis
(:func:`sigmatau.analysis.memory_needed`: samples × columns × 8 bytes × the measured factor) and
compares it with the memory available (:func:`sigmatau.io.memory_budget`, or a limit given);
:func:`analyze_file` then runs :func:`~sigmatau.analysis.analyze_log` on the log read whole, or
:func:`analyze_disk_log` on the log opened by :func:`sigmatau.io.open_log`, whose channels are read
in chunks by the statistics of :mod:`sigmatau.chunked`.

Out of core, per channel: OADEV, MDEV, OHDEV, TOTDEV (and ADEV, HDEV) streamed, TDEV from MDEV,
each with the noise type, EDF and interval of the in-memory run (≤ 1e-12 relative,
``tests/test_out_of_core.py``), and the IMU model fitted to that OADEV
(:func:`sigmatau.imu.analyze` takes the curve), so the model, the Kalibr entry and the exports are
the in-memory ones. What needs the record in memory is skipped, each with a note saying why and how
to get it: the statistics without a chunked kernel (TheoH, Theo1, MTOT …), the data checks of the
samples behind the model, the warm-up search (its fit reads the whole record; a warm-up given in
seconds and ``part`` are cut exactly), the temperature compensation, outliers, drift removal,
averaging, the dynamic stability, and the signal figures (report layer). Memory: each worker holds
a few dozen arrays of one chunk, whatever the length of the record.
"""

from __future__ import annotations

import dataclasses
import math
import os
import re
import time
import warnings
from concurrent.futures import ThreadPoolExecutor
from typing import Any, Callable, Literal, Mapping, Optional, Sequence, Union

import numpy as np

from ..errors import DataError, ParameterError, SigmaTauError
from ..uncertainty.confidence import ONE_SIGMA
from ..pipeline.analysis import (DEFAULT_STATISTICS, distinct_warnings, STEP_COST, StepEvent, check_statistics, datasheet_reference,
                                 kalibr_entry, memory_needed, tdev_from_mdev)
from ..pipeline.prepare import Preparation
from ..pipeline.results import IMU_GROUPS, ChannelAnalysis, LogAnalysis
from .chunked import DEFAULT_CHUNK, STATISTICS as CHUNKED_STATISTICS, ChunkedSeries, compute

__all__ = ["MEMORY_MODES", "MemoryPlan", "memory_plan", "parse_size", "analyze_file", "analyze_disk_log"]

#: ``memory=``: decide from the estimate (``auto``), or force the log in memory or out of core.
MEMORY_MODES = ("auto", "in", "chunked")

_UNITS = {"": 1, "b": 1, "k": 1e3, "kb": 1e3, "m": 1e6, "mb": 1e6, "g": 1e9, "gb": 1e9, "t": 1e12, "tb": 1e12,
          "kib": 1 << 10, "mib": 1 << 20, "gib": 1 << 30, "tib": 1 << 40}


def parse_size(text: Union[str, int, float]) -> int:
    """Bytes from ``"1GiB"``, ``"512MiB"``, ``"2G"`` (10⁹), ``"1.5e9"`` or a number.

    >>> parse_size("1GiB"), parse_size("500M"), parse_size(4096)
    (1073741824, 500000000, 4096)
    """
    if isinstance(text, bool):
        raise ParameterError(f"memory_limit={text!r} must be a size such as '1GiB', '512MiB' or '2e9'")
    if isinstance(text, (int, float)):
        value = float(text)
    else:
        m = re.fullmatch(r"\s*([0-9]*\.?[0-9]+(?:[eE][+-]?[0-9]+)?)\s*([A-Za-z]*)\s*", str(text))
        if m is None or m.group(2).lower() not in _UNITS:
            raise ParameterError(f"memory_limit={text!r} must be a size such as '1GiB', '512MiB', '2G' or '2e9'"
                                 " (bytes)")
        value = float(m.group(1)) * _UNITS[m.group(2).lower()]
    if not (math.isfinite(value) and value > 0):
        raise ParameterError(f"memory_limit={text!r} must be a positive size")
    return int(value)


@dataclasses.dataclass(frozen=True)
class MemoryPlan:
    """How a log will be analysed: in memory or out of core, and why.

    Attributes
    ----------
    mode : {"in", "chunked"}
    requested : {"auto", "in", "chunked"}
    needed : int or None
        Estimated peak of the in-memory analysis, bytes (None: the size is not known before reading).
    budget : int or None
        Bytes available (the limit given, else :func:`sigmatau.io.memory_budget`).
    limited : bool
        Whether ``budget`` is a limit given by the caller.
    rows, columns : int or None
        The log's size as estimated (columns: channels and time column).
    """

    mode: Literal["in", "chunked"]
    requested: str
    needed: Optional[int] = None
    budget: Optional[int] = None
    limited: bool = False
    rows: Optional[int] = None
    columns: Optional[int] = None

    def describe(self, chunk_size: Optional[int] = None) -> str:
        """One line: where the analysis runs and why (with the chunk size when given)."""
        from ..io import fmt_bytes

        where = "in memory" if self.mode == "in" else (
            "out of core, read in chunks" + (f" of {chunk_size:,} samples" if chunk_size else ""))
        if self.requested != "auto":
            return f"analysed {where} (memory='{self.requested}', --memory {self.requested})"
        if self.needed is None:
            return f"analysed {where} (the size of this log is not known before reading it)"
        budget = fmt_bytes(self.budget or 0)
        room = (f"the limit of {budget} given (memory_limit, --memory-limit)" if self.limited
                else f"the {budget} available")
        if self.mode == "in":
            return f"analysed {where}: about {fmt_bytes(self.needed)} needed, " + (
                "no limit known" if self.budget is None else f"within {room}")
        return (f"analysed {where}: the in-memory analysis would need about {fmt_bytes(self.needed)}, more than"
                f" {room}")

    def to_dict(self) -> dict[str, Any]:
        return {**dataclasses.asdict(self), "reason": self.describe()}


def memory_plan(path: Union[str, "os.PathLike[str]"], *, memory: str = "auto",
                memory_limit: Union[None, str, int, float] = None, **read_options: Any) -> MemoryPlan:
    """Whether :func:`analyze_file` would analyse ``path`` in memory or out of core.

    Parameters
    ----------
    path : str or path-like
    memory : {"auto", "in", "chunked"}
        ``auto``: out of core when the in-memory peak (:func:`sigmatau.analysis.memory_needed` of the
        log's rows and columns, :func:`sigmatau.io.log_size`) exceeds the budget; ``in`` or
        ``chunked`` force it.
    memory_limit : str or int, optional
        The budget in bytes (``"1GiB"`` …, :func:`parse_size`) instead of the memory available.
    **read_options
        Options of :func:`sigmatau.io.read`.
    """
    from ..io import log_size, memory_budget

    if memory not in MEMORY_MODES:
        raise ParameterError(f"memory={memory!r} must be one of {', '.join(MEMORY_MODES)}")
    limit = None if memory_limit is None else parse_size(memory_limit)
    if memory == "in":
        return MemoryPlan("in", "in", budget=limit, limited=limit is not None)
    try:
        size = log_size(path, **read_options)
    except (SigmaTauError, OSError):
        if memory == "chunked":
            raise
        size = None  # the in-memory reader says what is wrong with the file, in its own words
    rows = None if size is None else size.rows
    columns = None if size is None else size.channels + int(size.time)
    needed = None if size is None else memory_needed(size.rows, columns)  # type: ignore[arg-type]
    budget = limit if limit is not None else memory_budget()
    if memory == "chunked":
        mode = "chunked"
    else:
        mode = "chunked" if needed is not None and budget is not None and needed > budget else "in"
    return MemoryPlan(mode, memory, needed, budget, limit is not None, rows, columns)  # type: ignore[arg-type]


def analyze_file(path: Union[str, "os.PathLike[str]"], *, memory: str = "auto",
                 memory_limit: Union[None, str, int, float] = None, chunk_size: Optional[int] = None,
                 workdir: Optional[Union[str, "os.PathLike[str]"]] = None,
                 read_options: Optional[Mapping[str, Any]] = None, **analysis: Any) -> LogAnalysis:
    """The main job on a log file, in memory or — when it would not fit — out of core.

    Parameters
    ----------
    path : str or path-like
        The log (any format :func:`sigmatau.io.read` reads; out of core: ``.npy``, ``.npz`` of
        stored arrays, HDF5 and text).
    memory, memory_limit
        As for :func:`memory_plan`.
    chunk_size : int, optional
        Samples per read out of core (default :data:`sigmatau.chunked.DEFAULT_CHUNK`).
    workdir : path, optional
        Where a text log's temporary files go out of core (:func:`sigmatau.io.open_log`).
    read_options : mapping, optional
        Options of :func:`sigmatau.io.read`.
    **analysis
        Options of :func:`sigmatau.analysis.analyze_log`.

    Returns
    -------
    LogAnalysis
        Out of core, ``settings["memory"]`` says why and the first note says so in one line.

    Examples
    --------
    >>> import tempfile, pathlib, numpy as np
    >>> from sigmatau.chunked import analyze_file
    >>> f = pathlib.Path(tempfile.mkdtemp()) / "clock.npz"
    >>> np.savez(f, y=np.random.default_rng(0).standard_normal(5000), rate=np.array(1.0))
    >>> a = analyze_file(f, memory="chunked", statistics="oadev,theoh")
    >>> a.notes[0].startswith("analysed out of core"), sorted(a.channel("y").skipped)
    (True, ['theoh'])
    """
    from ..io import open_log, read
    from ..pipeline.analysis import analyze_log

    opts = dict(read_options or {})
    plan = memory_plan(path, memory=memory, memory_limit=memory_limit, **opts)
    if plan.mode == "in":
        return analyze_log(read(path, **opts), **analysis)
    with open_log(path, workdir=workdir, **opts) as log:
        return analyze_disk_log(log, chunk_size=chunk_size, plan=plan, **analysis)


_NO_KERNEL = ("no chunked kernel, so not computed out of core (chunked: {chunked}); to get it, analyse the log"
              " in memory (memory='in', --memory in) where it fits, or a shorter record cut from it")


def _check(statistics: Union[str, Sequence[str]], axis_rule: str, confidence: float, gauss_markov: str,
           theoh: str, theo1_bias: str, chunk_size: Optional[int]) -> tuple[tuple[str, ...], int]:
    """The options of :func:`analyze_disk_log`, checked as :func:`analyze_log` checks them."""
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
    chunk = DEFAULT_CHUNK if chunk_size is None else chunk_size
    if isinstance(chunk, bool) or not isinstance(chunk, int) or chunk < 16:
        raise ParameterError(f"chunk_size={chunk_size!r} must be an integer of at least 16 samples")
    return stats, chunk


def _prep_notes(log: Any, prep: Optional[Preparation], dynamic: Optional[tuple[float, float]]) -> list[str]:
    """One note per preparation step asked for and not done out of core, with why and what to do."""
    if not prep and dynamic is None:
        return []
    notes = []
    sensors = any(log.group_of(n) in IMU_GROUPS for n in log.names)
    in_memory = "analyse the log in memory (--memory in) where it fits"
    if prep is not None and prep.warmup == "auto" and sensors:
        notes.append("warm-up: not looked for out of core (its fit reads the whole record at once), so every sample"
                     " is analysed; to have it found, " + in_memory + "; --warmup keep skips the search and this note")
    skipped = []
    if prep is not None:
        if prep.part is not None:
            skipped.append("part")
        if prep.warmup not in (None, "auto"):
            skipped.append(f"warm-up of {prep.warmup:g} s")
        if prep.temperature is not None and any(log.group_of(n) == "temperature" for n in log.names) and sensors:
            skipped.append("temperature compensation")
        if prep.outliers is not None:
            skipped.append("outliers")
        if prep.drift is not None:
            skipped.append("drift removal")
        if prep.average is not None:
            skipped.append("averaging")
    if dynamic is not None:
        skipped.append("dynamic stability (--dynamic)")
    if skipped:
        notes.append(f"not done out of core (each needs the record in memory): {', '.join(skipped)}; the statistics"
                     f" are those of the channels as recorded; {in_memory}")
    return notes


def _one(log: Any, name: str, stats: tuple[str, ...], taus: Any, confidence: float, reference: Mapping,
         model_wanted: bool, chunk: int, gauss_markov: str, step: Callable[[str, bool], None]) -> ChannelAnalysis:
    """One channel: its statistics streamed, TDEV from MDEV, the IMU model fitted to the OADEV."""
    from ..imu import model as imu
    from ..imu.units import sensor_unit

    t0 = time.perf_counter()
    ch = log[name]
    # One series per channel: its validating pass (finite, NaN gaps, largest value) runs once for all.
    src = ChunkedSeries(ch.read, ch.n, chunk_size=chunk, name=f"channel {name!r}")
    group, unit = log.group_of(name), log.units.get(name, "")
    kw = dict(rate=log.rate, data_type=log.data_type, taus=taus, confidence=confidence)
    model, note, curve = None, "", None
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
                curve = compute("oadev", src, **kw)
                model = imu.analyze(curve, unit=su.name, confidence=confidence, gauss_markov=gauss_markov)
            except DataError as exc:
                note = str(exc)
            except (ArithmeticError, np.linalg.LinAlgError) as exc:
                note = f"IMU model not fitted: numerical failure in the fit ({type(exc).__name__}: {exc})"
        step("model", True)
    elif model_wanted:
        note = f"{group} channel: the IMU model applies to gyro and accel channels"
    results: dict[str, Any] = {}
    skipped: dict[str, str] = {}
    for stat in stats:
        step(stat, False)
        derived = tdev_from_mdev(results["mdev"]) if stat == "tdev" and "mdev" in results else None
        if stat == "oadev" and curve is not None:
            results[stat] = curve  # the very curve the model was fitted on
        elif derived is not None:
            results[stat] = derived
        elif stat not in CHUNKED_STATISTICS:
            skipped[stat] = _NO_KERNEL.format(chunked=", ".join(CHUNKED_STATISTICS))
        else:
            try:
                results[stat] = compute(stat, src, **kw)
            except DataError as exc:
                skipped[stat] = str(exc)
        step(stat, True)
    rows: tuple[dict, ...] = ()
    if model is not None and reference.get(group):
        rows = tuple(model.compare(reference[group]))
    return ChannelAnalysis(name=name, group=group, unit=unit, n_samples=ch.n, results=results, skipped=skipped,
                           model=model, model_note=note, datasheet=rows, seconds=time.perf_counter() - t0)


def _in_threads(log: Any, names: list[str], work: Callable[[str, Callable[[str, bool], None]], ChannelAnalysis],
                workers: int, progress: Optional[Callable[[str], None]],
                on_step: Optional[Callable[[StepEvent], None]], plan: dict) -> tuple[list[ChannelAnalysis], list[str]]:
    """Every channel (in threads), the distinct warnings raised; an interruption cancels the reads."""
    total = sum(plan.values())

    def one(name: str) -> ChannelAnalysis:
        def step(what: str, finished: bool) -> None:
            if on_step is not None:
                on_step(StepEvent(name, what, finished, plan.get((name, what), 0.0), total))

        ch = work(name, step)
        if progress is not None:
            progress(f"{name}: {', '.join(ch.results) or 'no statistic'} in {ch.seconds:.1f} s (out of core)")
        return ch

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            if workers == 1:
                done = [one(n) for n in names]
            else:
                with ThreadPoolExecutor(max_workers=workers, thread_name_prefix="sigmatau-ooc") as pool:
                    try:
                        done = list(pool.map(one, names))
                    except BaseException:
                        log.cancel()  # Ctrl-C, SIGTERM: the other threads stop at their next read
                        raise
        except BaseException:
            log.cancel()
            raise
    return done, distinct_warnings(caught)


def analyze_disk_log(
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
    chunk_size: Optional[int] = None,
    plan: Optional[MemoryPlan] = None,
) -> LogAnalysis:
    """:func:`sigmatau.analysis.analyze_log` on a :class:`sigmatau.io.DiskLog`, reading it in chunks.

    Parameters
    ----------
    log : DiskLog
        From :func:`sigmatau.io.open_log`.
    statistics, channels, taus, confidence, model, axis_rule, inflate, rostopic, datasheet, workers,
    progress, theoh, on_step, prep, dynamic, gauss_markov, theo1_bias
        As for :func:`~sigmatau.analysis.analyze_log`. A statistic without a chunked kernel, and a
        preparation step or ``dynamic`` that needs the record in memory, is skipped with a note.
        ``workers`` defaults to the usable cores: each holds a few chunks, not a channel.
    chunk_size : int, optional
        Samples per read (default :data:`sigmatau.chunked.DEFAULT_CHUNK`).
    plan : MemoryPlan, optional
        Why the log is analysed out of core (:func:`memory_plan`): its line is the first note.

    Returns
    -------
    LogAnalysis
        With ``log`` the DiskLog (metadata only once it is closed) and ``settings["memory"]``.

    Notes
    -----
    Every statistic is :func:`sigmatau.chunked.compute`, equal to the in-memory function to
    ≤ 1e-12 relative with the same τ, noise types, EDF and intervals; the model is
    :func:`sigmatau.imu.analyze` of the streamed OADEV (the same curve as in memory), without the
    data checks of the samples.
    """
    t0 = time.perf_counter()
    stats, chunk = _check(statistics, axis_rule, confidence, gauss_markov, theoh, theo1_bias, chunk_size)
    reference = datasheet_reference(datasheet)
    names = list(log.names) if channels is None else [str(c) for c in channels]
    for n in names:
        log[n]
    if not names:
        raise DataError("the log has no channels")
    if workers is None:
        workers = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise ParameterError(f"workers={workers!r} must be a positive integer")
    workers = min(workers, len(names))
    plan = plan or MemoryPlan("chunked", "chunked")
    notes = [plan.describe(chunk)] + _prep_notes(log, prep, dynamic)
    cost: dict[tuple[str, str], float] = {}
    for n in names:
        with_model = model and log.group_of(n) in IMU_GROUPS
        if with_model:
            cost[(n, "model")] = STEP_COST["model"]
        for s in stats:
            cost[(n, s)] = 0.05 if (s == "oadev" and with_model) or s == "tdev" else STEP_COST.get(s, 2.0)
    done, seen = _in_threads(
        log, names, lambda n, step: _one(log, n, stats, taus, float(confidence), reference, model, chunk,
                                         gauss_markov, step), workers, progress, on_step, cost)
    if not any(c.results for c in done):
        why = "; ".join(f"{s}: {r}" for s, r in done[0].skipped.items())
        raise DataError(f"no statistic could be computed for channel {done[0].name!r} ({len(log)} samples): {why}")
    if any(c.model is not None for c in done):
        notes.append("IMU model: fitted to the OADEV computed in chunks (the in-memory curve); the data checks of"
                     " the samples (quantisation, clipping, spectrum near f/2) need them in memory and were not made")
    kalibr, kalibr_note = kalibr_entry(done, model, axis_rule, inflate, rostopic)
    settings = {"statistics": list(stats), "channels": names, "taus": taus if isinstance(taus, str) else
                list(np.asarray(taus, dtype=float)), "confidence": float(confidence), "ci": "chi2",
                "model": bool(model), "axis_rule": axis_rule, "inflate": float(inflate), "rostopic": rostopic,
                "datasheet": {g: {t: list(v) for t, v in terms.items()} for g, terms in reference.items()},
                "workers": workers, "theoh": theoh, "theo1_bias": theo1_bias,
                "prep": {k: v for k, v in dataclasses.asdict(prep).items() if v is not None} if prep else {},
                "dynamic": None if dynamic is None else [float(v) for v in dynamic], "gauss_markov": gauss_markov,
                "memory": {**plan.to_dict(), "chunk_size": chunk}}
    return LogAnalysis(log=log, channels=tuple(done), settings=settings, kalibr=kalibr, kalibr_note=kalibr_note,
                       notes=tuple(notes), warnings=tuple(seen), seconds=time.perf_counter() - t0)
