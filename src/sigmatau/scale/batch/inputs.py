"""What a batch is given: the logs named by patterns, and the read and analysis settings checked.

Everything here runs on the client before anything is submitted, so a bad
argument is a :class:`~sigmatau.errors.ParameterError` and not a failure of
every log.
"""

from __future__ import annotations

import glob
import hashlib
import json
import os
from pathlib import Path
from typing import Any, Mapping, Optional, Sequence

from ...errors import ParameterError
from .common import _SETTINGS, PathLike, _write_json


def _is_bag_dir(p: Path) -> bool:
    """Whether ``p`` is a ROS 2 bag directory (it holds ``metadata.yaml``)."""
    return p.is_dir() and (p / "metadata.yaml").is_file()


def expand_patterns(patterns: Sequence[PathLike], *, exclude: Optional[PathLike] = None) -> list[str]:
    """Absolute paths of the logs named by files, directories and glob patterns.

    Patterns are expanded by Python (``*``, ``?``, ``[…]`` and ``**`` for any
    depth), so they work the same on every shell, also when quoted. A ROS 2 bag
    directory (one holding ``metadata.yaml``) is one log; other directories a
    pattern matches are passed over, and a directory named literally is an error.
    Paths inside ``exclude`` (the output directory) are left out; duplicates
    are removed, the order is sorted.

    Raises
    ------
    ParameterError
        A pattern matches no log.
    """
    if isinstance(patterns, (str, os.PathLike)):
        patterns = [patterns]
    skip = Path(exclude).resolve() if exclude is not None else None
    found: dict[str, None] = {}
    for pat in patterns:
        text = os.fspath(pat)
        literal = not glob.has_magic(text)
        if literal:
            p = Path(text)
            if p.is_dir() and not _is_bag_dir(p):
                raise ParameterError(f"{text!r} is a directory, not a log (nor a ROS 2 bag); give files or a pattern"
                                     f" such as {os.path.join(text, '*.csv')!r}")
            # A missing literal path is kept: its task reports it like any unreadable log.
            matches = [text]
        else:
            matches = [m for m in sorted(glob.glob(text, recursive=True))
                       if Path(m).is_file() or _is_bag_dir(Path(m))]
            if not matches:
                raise ParameterError(f"pattern {text!r} matches no log")
        for m in matches:
            a = Path(os.path.abspath(m))
            if skip is not None and (a.resolve() == skip or skip in a.resolve().parents):
                continue
            found[str(a)] = None
    if not found:
        raise ParameterError("no log to analyse")
    return sorted(found)


def _read_kwargs(read: Optional[Mapping[str, Any]]) -> dict[str, Any]:
    """``read`` checked against :func:`sigmatau.io.read` before anything is submitted."""
    from ... import io

    kw = dict(read or {})
    for bad in ("path", "progress"):
        if bad in kw:
            raise ParameterError(f"read option {bad!r} is set by the batch itself")
    io.check_read_options(**kw)  # raises ParameterError naming an unknown option or a bad value
    return kw


def _analysis_kwargs(statistics: Any, taus: Any, confidence: float, model: bool, axis_rule: str, inflate: float,
                     rostopic: str, datasheet: Any, warmup: Any = "auto", temperature: Any = "auto") -> dict[str, Any]:
    """The keyword arguments of :func:`sigmatau.analysis.analyze_log`, checked and JSON-ready.

    They enter the settings token, so they are normalised here (floats, lists).
    """
    from ...pipeline.analysis import check_statistics, datasheet_reference
    from ...pipeline.prepare import Preparation

    Preparation(warmup=warmup, temperature=temperature)  # checks them

    if axis_rule not in ("max", "rms", "mean"):
        raise ParameterError(f"axis_rule={axis_rule!r} must be 'max', 'rms' or 'mean'")
    if isinstance(confidence, bool) or not isinstance(confidence, (int, float)) or not 0 < confidence < 1:
        raise ParameterError(f"confidence={confidence!r} must be a number between 0 and 1")
    if not isinstance(taus, str):
        import numpy as np

        taus = [float(t) for t in np.asarray(taus, dtype=float).ravel()]
    return {"statistics": list(check_statistics(statistics)), "taus": taus, "confidence": float(confidence),
            "model": bool(model), "axis_rule": axis_rule, "inflate": float(inflate), "rostopic": str(rostopic),
            "datasheet": {g: {t: list(v) for t, v in terms.items()}
                          for g, terms in datasheet_reference(datasheet).items()} or None,
            "warmup": warmup if isinstance(warmup, str) or warmup is None else float(warmup),
            "temperature": temperature}


def _check_settings(out: Path, settings: dict[str, Any], force: bool) -> str:
    """Record the settings in ``OUT/batch.json``; refuse to mix results of other settings."""
    token = hashlib.sha256(json.dumps(settings, sort_keys=True).encode()).hexdigest()[:16]
    path = out / _SETTINGS
    if path.is_file() and not force:
        try:
            old = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            old = {}
        if old.get("token") != token:
            was, now = old.get("settings", {}), settings
            diff = [k for k in sorted(set(was) | set(now)) if was.get(k) != now.get(k)]
            raise ParameterError(f"{str(out)!r} holds results of other settings (differing: {', '.join(diff)});"
                                 " use --force-rerun to recompute them all, or another --out")
    _write_json(path, {"token": token, "settings": settings})
    return token


def _check_cluster_choice(client: Any, scheduler: Optional[str], workers: Any) -> None:
    """Refuse contradictory cluster arguments of :func:`~sigmatau.scale.batch.analyze_many`.

    Raises
    ------
    ParameterError
        ``client`` and ``scheduler`` both given, ``workers`` with either of them,
        or ``workers`` not a positive integer.
    """
    if client is not None and scheduler is not None:
        raise ParameterError("give client or scheduler, not both")
    if (client is not None or scheduler is not None) and workers is not None:
        raise ParameterError("workers= starts a local cluster; it cannot be combined with client or scheduler")
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int) or workers < 1):
        raise ParameterError(f"workers={workers!r} must be a positive integer")


def _figure_formats(figures: Optional[Sequence[str]]) -> list[str]:
    """The per-log figure formats, lower case, each checked against ``FIGURE_FORMATS``."""
    from ...report.outputs import FIGURE_FORMATS

    fmts = [str(f).lower() for f in (figures or ())]
    for f in fmts:
        if f not in FIGURE_FORMATS:
            raise ParameterError(f"figure format {f!r} must be one of {', '.join(FIGURE_FORMATS)}")
    return fmts


def _check_outlier_z(outlier_z: Any) -> None:
    """Refuse an ``outlier_z`` that is not a positive number."""
    if isinstance(outlier_z, bool) or not isinstance(outlier_z, (int, float)) or not outlier_z > 0:
        raise ParameterError(f"outlier_z={outlier_z!r} must be a positive number")


def _check_out(out_p: Path) -> None:
    """Refuse an output directory that cannot be one of a batch (checked before it is created).

    Raises
    ------
    ParameterError
        ``out_p`` is a file, its parent does not exist, or it is a non-empty
        directory without ``batch.json`` (not made by sigmatau batch).
    """
    if out_p.exists() and not out_p.is_dir():
        raise ParameterError(f"out {str(out_p)!r} exists and is not a directory")
    if not out_p.resolve().parent.is_dir():
        raise ParameterError(f"out {str(out_p)!r}: the parent directory does not exist")
    if out_p.is_dir() and any(out_p.iterdir()) and not (out_p / "batch.json").is_file():
        raise ParameterError(f"out {str(out_p)!r} exists, is not empty and is not a sigmatau batch directory"
                             " (no batch.json); choose another --out")
