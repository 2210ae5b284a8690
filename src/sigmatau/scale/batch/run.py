"""``analyze_many``: a batch run from its arguments to the fleet summary, as a sequence of named steps."""

from __future__ import annotations

import contextlib
import hashlib
import os
import time
import uuid
import warnings
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Callable, Mapping, Optional, Sequence, Union

from ..._version import __version__
from ...errors import SigmaTauWarning, caller_stacklevel
from ...pipeline.analysis import DEFAULT_STATISTICS, json_ready
from ...report.estimators import parse_exports
from ...uncertainty.confidence import ONE_SIGMA
from .cluster import (_connect, _distributed, _probe_scheduler, check_scheduler_address, local_worker_count,
                      usable_cores)
from .common import LIMIT_MARGIN, LOGS_DIR, OUTLIER_Z, ClusterError, PathLike, _stem
from .inputs import (_analysis_kwargs, _check_cluster_choice, _check_outlier_z, _check_out, _check_settings,
                     _figure_formats, _read_kwargs, expand_patterns)
from .journal import _done_before, _Journal, _remove_if_ours_and_empty, _remove_leftovers, _stat
from .limits import load_limits
from .lock import _Lock
from .progress import _Progress
from .report import _build_fleet
from .summary import FleetSummary, _tally
from .task import _analyse_one, _error_record


def analyze_many(
    paths: Union[PathLike, Sequence[PathLike]],
    out: PathLike,
    *,
    client: Any = None,
    scheduler: Optional[str] = None,
    workers: Optional[int] = None,
    read: Optional[Mapping[str, Any]] = None,
    statistics: Union[str, Sequence[str]] = DEFAULT_STATISTICS,
    taus: Any = "octave",
    confidence: float = ONE_SIGMA,
    model: bool = True,
    axis_rule: str = "max",
    inflate: float = 1.0,
    rostopic: str = "/imu0",
    datasheet: Union[str, Mapping[str, Any], None] = None,
    figures: Optional[Sequence[str]] = ("png",),
    report: bool = True,
    exports: Union[str, Sequence[str]] = ("kalibr",),
    limits: Any = None,
    limit_margin: float = LIMIT_MARGIN,
    outlier_z: float = OUTLIER_Z,
    fleet_figures: bool = True,
    force: bool = False,
    progress: Any = None,
    warmup: Any = "auto",
    temperature: Any = "auto",
) -> FleetSummary:
    """Analyse many logs on a Dask cluster, one task per log, and summarise the fleet.

    Parameters
    ----------
    paths : path, pattern or sequence of them
        Logs: files, ROS 2 bag directories or glob patterns
        (:func:`expand_patterns`). With a remote cluster, the workers must see
        the same paths (a shared file system) and write to ``out``.
    out : path
        Output directory (created; its parent must exist). Reused by a rerun,
        which skips the logs already done.
    client : distributed.Client, optional
        A client of the cluster to use (left open).
    scheduler : str, optional
        Address of an existing scheduler (``"tcp://host:8786"``) to connect to;
        checked by :func:`check_scheduler_address` and reached within
        :data:`~sigmatau.scale.batch.common.CONNECT_TIMEOUT` seconds before ``out`` is created.
    workers : int, optional
        Without ``client`` and ``scheduler``: a ``LocalCluster`` of this many
        single-threaded worker processes (default: the usable cores), at most
        the usable cores and the logs to analyse (a ``SigmaTauWarning`` says
        so when a request is capped).
    read : mapping, optional
        Keyword arguments of :func:`sigmatau.io.read` (``columns``,
        ``time_unit``, ``rate``, ``units``, ``topic``, ``gaps`` …), the same
        for every log.
    statistics, taus, confidence, model, axis_rule, inflate, rostopic, datasheet
        As :func:`sigmatau.analysis.analyze_log`.
    warmup, temperature
        As ``sigmatau analyze --warmup/--temperature`` (:class:`sigmatau.analysis.Preparation`):
        by default the warm-up is detected and left out, and the gyro and accel channels are
        compensated for temperature when a log has a temperature channel.
    figures : sequence of {"png", "svg", "pdf"} or None
        Per-log figure formats (default PNG only; None: no figures, fastest).
    report : bool
        Write each log's ``report.html``.
    exports : sequence of str or str
        Estimator parameter files written for each log with gyro and accel models
        (:func:`sigmatau.outputs.write_outputs`; default Kalibr's ``imu.yaml``).
    limits : str, path or mapping, optional
        Pass/fail limits (:func:`load_limits`): a datasheet part, a file or a mapping.
    limit_margin : float
        Factor on a datasheet part's typical values (default 1.5).
    outlier_z : float
        Robust z beyond which a term is an outlier of its fleet (default 3.5).
    fleet_figures : bool
        Draw the fleet histograms and strip plot (needs matplotlib).
    force : bool
        Recompute every log, replacing its directory (also when the settings changed).
    progress : None, bool, "bar", "lines", "none" or callable
        None: a bar on stderr when it is a terminal. A callable is called as
        ``progress(record, done, total)`` after each log (raising
        KeyboardInterrupt from it stops the run like Ctrl-C).

    Returns
    -------
    FleetSummary

    Raises
    ------
    ParameterError
        A bad argument, pattern or limits file; ``out`` of other settings; or
        ``out`` locked by a run that is still alive (a lock left by a run that
        died, or whose PID now belongs to another process, is taken over).
    ClusterError
        The scheduler cannot be reached or the local cluster cannot start;
        an ``out`` created by this call is then removed again.

    Notes
    -----
    Each log is one task ``(hash, read, analyze_log, write_outputs, record)``
    that returns a small record and never raises: a corrupt or unreadable log
    becomes an error record with the exception's class and a one-line reason.
    The per-log directory ``out/logs/<stem>-<sha256[:12]>`` is written under a
    hidden name and renamed into place, its ``record.json`` included, so it
    exists only complete; a task finding the directory of its content already
    there returns that record. The client appends every finished record to
    ``out/index.jsonl`` (fsync) as it arrives — once per path, content hash
    and outcome, so a log failing on every rerun stays one line — and a rerun
    skips paths whose
    size and mtime match a journal entry whose directory exists, without
    submitting them; the others are hashed on the workers and skipped there.
    The fleet summary counts each content once. A worker that dies has its
    tasks rerun elsewhere by Dask; after ``distributed.scheduler.allowed-failures``
    deaths the log is reported as failed (``KilledWorker``).
    """
    t0 = time.perf_counter()
    out_p = Path(out)
    files = expand_patterns([paths] if isinstance(paths, (str, os.PathLike)) else list(paths), exclude=out_p)
    _check_cluster_choice(client, scheduler, workers)
    if scheduler is not None:
        check_scheduler_address(scheduler)
    fmts = _figure_formats(figures)
    targets = list(parse_exports(exports))
    _check_outlier_z(outlier_z)
    read_kw = _read_kwargs(read)
    analysis_kw = _analysis_kwargs(statistics, taus, confidence, model, axis_rule, inflate, rostopic, datasheet,
                                   warmup, temperature)
    lim = load_limits(limits, margin=limit_margin)
    _check_out(out_p)
    if scheduler is not None:
        _probe_scheduler(scheduler)
    created = not out_p.exists()
    out_p.mkdir(exist_ok=True)
    try:
        return _run_batch(out_p, files, created=created, client=client, scheduler=scheduler, workers=workers,
                          read_kw=read_kw, analysis_kw=analysis_kw, fmts=fmts, report=report, exports=targets,
                          lim=lim, outlier_z=outlier_z, fleet_figures=fleet_figures, force=force, progress=progress,
                          t0=t0)
    except ClusterError:
        if created:  # nothing was analysed: leave no trace of the attempt
            _remove_if_ours_and_empty(out_p)
        raise


def _run_batch(out_p: Path, files: list[str], *, created: bool, client: Any, scheduler: Optional[str],
               workers: Optional[int], read_kw: dict[str, Any], analysis_kw: dict[str, Any], fmts: list[str],
               report: bool, exports: list[str], lim: Mapping[str, Any], outlier_z: float, fleet_figures: bool,
               force: bool, progress: Any, t0: float) -> FleetSummary:
    """The body of :func:`analyze_many` once its arguments are checked and ``out_p`` exists.

    Under the lock of ``out_p``: record the settings, take the logs done before
    from the journal, analyse the others on the cluster, then summarise the fleet.

    Parameters
    ----------
    out_p : Path
        The output directory (it exists).
    files : list of str
        The logs, as :func:`expand_patterns` gives them.
    created : bool
        Whether this call created ``out_p``.
    client, scheduler, workers, force, progress
        As :func:`analyze_many`.
    read_kw, analysis_kw : dict
        Checked keyword arguments of :func:`sigmatau.io.read` and :func:`sigmatau.analysis.analyze_log`.
    fmts : list of str
        Per-log figure formats.
    report : bool
        Write each log's ``report.html``.
    exports : list of str
        Estimator parameter files per log (:func:`sigmatau.outputs.parse_exports`).
    lim : mapping
        The limits (:func:`load_limits`).
    outlier_z : float
        Robust z beyond which a term is an outlier.
    fleet_figures : bool
        Draw the fleet figures.
    t0 : float
        ``time.perf_counter()`` at the start of the call.

    Returns
    -------
    FleetSummary
    """
    logs_dir = out_p / LOGS_DIR
    logs_dir.mkdir(exist_ok=True)
    settings = json_ready({"version": __version__, "read": read_kw, "analysis": analysis_kw, "figures": fmts,
                           "report": bool(report), "exports": list(exports)})

    with _Lock(out_p):
        token = _check_settings(out_p, settings, force)
        stats = {p: _stat(p) for p in files}
        results = _done_before(out_p, files, stats, token, force)
        todo = [p for p in files if p not in results]
        bar = _Progress(len(files), progress)
        for rec in results.values():
            bar.update(rec)
        job = _Job(logs_dir=logs_dir, token=token, read_kw=read_kw, analysis_kw=analysis_kw, fmts=fmts,
                   report=report, force=force, exports=tuple(exports))
        _analyse_pending(job, todo, stats, client=client, scheduler=scheduler, workers=workers, results=results,
                         journal=_Journal(out_p), bar=bar)
        ok, errors, computed, reused = _tally(files, results)
        fleet = _build_fleet(out_p, ok, errors, limits=lim, outlier_z=float(outlier_z),
                             computed=computed, reused=reused, seconds=time.perf_counter() - t0,
                             figures=fleet_figures)
    return replace(fleet, seconds=time.perf_counter() - t0)


@dataclass(frozen=True)
class _Job:
    """What every task of a run is given besides its log: where to write and with which settings.

    Attributes
    ----------
    logs_dir : Path
        ``OUT/logs``.
    token : str
        The settings token (:func:`_check_settings`).
    read_kw, analysis_kw : dict
        Keyword arguments of :func:`sigmatau.io.read` and :func:`sigmatau.analysis.analyze_log`.
    fmts : list of str
        Per-log figure formats.
    report, force : bool
        Write each log's ``report.html``; recompute logs already done.
    exports : tuple of str
        Estimator parameter files per log.
    """

    logs_dir: Path
    token: str
    read_kw: dict[str, Any]
    analysis_kw: dict[str, Any]
    fmts: list[str]
    report: bool
    force: bool
    exports: tuple[str, ...] = ("kalibr",)


def _analyse_pending(job: _Job, todo: list[str], stats: Mapping[str, Optional[tuple[int, int]]], *, client: Any,
                     scheduler: Optional[str], workers: Optional[int], results: dict[str, dict[str, Any]],
                     journal: _Journal, bar: _Progress) -> None:
    """Analyse the logs ``todo`` on the cluster, adding their records to ``results`` as they finish.

    Whatever happens (an interruption included), the bar and the journal are
    closed, the tasks still pending cancelled, the cluster opened here closed and
    the leftovers of unfinished tasks removed (:func:`_wind_down`).

    Parameters
    ----------
    job : _Job
        Settings of every task.
    todo : list of str
        The logs to analyse (none: no cluster is started).
    stats : mapping
        Size and modification time of every log (:func:`_stat`), for the journal.
    client, scheduler, workers
        As :func:`analyze_many`.
    results : dict
        Path → record; filled in place.
    journal : _Journal
        ``OUT/index.jsonl``, appended to as records arrive; closed here.
    bar : _Progress
        Updated as records arrive; closed here.
    """
    closer: Callable[[], None] = lambda: None
    futures: list[Any] = []
    cl: Any = None
    local = client is None and scheduler is None
    try:
        if todo:
            distributed = _distributed()
            cl, closer = _open_client(client, scheduler, workers, len(todo), local)
            futures = _submit(cl, job, todo, stats)
            _collect(distributed, cl, futures, todo, stats, results=results, journal=journal, bar=bar)
    finally:
        bar.close()
        journal.close()
        _wind_down(cl, futures, closer, job.logs_dir, local)


def _open_client(client: Any, scheduler: Optional[str], workers: Optional[int], n_logs: int,
                 local: bool) -> tuple[Any, Callable[[], None]]:
    """The client to submit through and how to close what was opened (:func:`_connect`).

    A local cluster gets at most one worker per usable core and per log; a
    warning says so when the request is capped.
    """
    n_workers, note = local_worker_count(workers, n_logs, usable_cores())
    if local and note:
        # stacklevel: _open_client, _analyse_pending, _run_batch, analyze_many, then its caller.
        warnings.warn(note, SigmaTauWarning, stacklevel=caller_stacklevel())
    return _connect(client, scheduler, n_workers)


def _task_key(path: str, stat: Optional[tuple[int, int]], job: _Job, run: str) -> str:
    """The Dask key of the task of ``path``: the log and settings, plus this run.

    The run's part matters: a key of an interrupted run may still be being
    cancelled on the scheduler, and reusing it would hand back its CancelledError.
    """
    st = stat or (0, 0)
    return f"sigmatau-log-{_stem(path)}-" + hashlib.sha256(
        f"{path}\0{st[0]}\0{st[1]}\0{job.logs_dir.resolve()}\0{job.token}\0{job.force}".encode()
    ).hexdigest()[:16] + f"-{run}"


def _submit(cl: Any, job: _Job, todo: list[str], stats: Mapping[str, Optional[tuple[int, int]]]) -> list[Any]:
    """One future per log of ``todo`` (:func:`_analyse_one`), in the order of ``todo``."""
    run = uuid.uuid4().hex[:8]
    return [cl.submit(_analyse_one, p, str(job.logs_dir.resolve()), job.read_kw, job.analysis_kw, job.fmts,
                      bool(job.report), bool(job.force), job.token, exports=job.exports,
                      key=_task_key(p, stats[p], job, run), pure=False)
            for p in todo]


def _collect(distributed: Any, cl: Any, futures: list[Any], todo: list[str],
             stats: Mapping[str, Optional[tuple[int, int]]], *, results: dict[str, dict[str, Any]],
             journal: _Journal, bar: _Progress) -> None:
    """Take the records as the tasks finish: into ``results``, the journal and the bar.

    A task that raised (``KilledWorker``, ``CancelledError``) becomes an error
    record of its log; the others go on.
    """
    path_of = {f.key: p for f, p in zip(futures, todo)}
    # Through this client's own event loop: as_completed() would otherwise look for the
    # process's default client, which batch never makes (and a user need not have).
    for fut in distributed.as_completed(futures, loop=cl.loop):
        p = path_of[fut.key]
        try:
            rec = fut.result()
        except Exception as exc:  # KilledWorker, CancelledError: the log failed, the rest go on
            rec = _error_record(p, exc)
        rec = {**rec, "path": p}
        fut.release()
        results[p] = rec
        journal.append(rec, stats[p])
        bar.update(rec)


def _wind_down(cl: Any, futures: list[Any], closer: Callable[[], None], logs_dir: Path, local: bool) -> None:
    """Cancel the tasks still pending, close what :func:`_open_client` opened, remove leftovers.

    Leftovers of attempts that died or were cancelled are removed (the lock says
    no other run writes here) also after an interruption, but only once no task of
    ours can still be writing: the local cluster is closed; a cancelled task may
    still run on a cluster of the user's.
    """
    pending = [f for f in futures if not f.done()]
    if pending:
        with contextlib.suppress(Exception):  # a cluster already gone has nothing left to cancel
            cl.cancel(pending)
    closer()
    if local or not pending:
        _remove_leftovers(logs_dir)
