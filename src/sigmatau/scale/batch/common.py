"""Names every step of a batch shares: output layout, defaults, the cluster error and small writers.

Kept apart so that the steps (:mod:`.inputs`, :mod:`.task`, :mod:`.lock`,
:mod:`.journal`, :mod:`.limits`, :mod:`.summary`, :mod:`.report`, :mod:`.cluster`)
import it rather than each other (only :mod:`.report` imports :mod:`.summary`, and
:mod:`.run` imports them all), which keeps their imports acyclic.
"""

from __future__ import annotations

import json
import os
import uuid
from pathlib import Path
from typing import Any, Union

from ...errors import SigmaTauError


#: Robust z-score (``0.6745·|x − median|/MAD`` on log10 values) beyond which a term is an
#: outlier of its fleet (Iglewicz & Hoaglin's 3.5).
OUTLIER_Z = 3.5

#: Factor applied to a datasheet preset's typical value to make it a limit: datasheets
#: give typical, not maximum, noise densities, so about half of good parts exceed them.
LIMIT_MARGIN = 1.5

#: Seconds allowed to reach an existing scheduler (``--scheduler``) before giving up: a
#: scheduler that answers does so in milliseconds, and a wrong address should not hang.
CONNECT_TIMEOUT = 10.0

_RECORD = "record.json"
_INDEX = "index.jsonl"
_SETTINGS = "batch.json"
_LOCK = "batch.lock"
LOGS_DIR = "logs"
_SCHEMA = 1

PathLike = Union[str, "os.PathLike[str]"]


class ClusterError(SigmaTauError):
    """The Dask cluster could not be reached or started."""


def _stem(path: str) -> str:
    """A log's file name without suffixes, reduced to letters, digits, ``-`` and ``_`` (≤ 60).

    The start of the log's directory name under ``OUT/logs``.
    """
    name = Path(path).name.split(".")[0] or "log"
    return "".join(c if c.isalnum() or c in "-_" else "_" for c in name)[:60]


def _one_line(exc: BaseException) -> str:
    """The first line of an exception's message (an OSError's reason and file name): what a record and the CLI show."""
    if isinstance(exc, OSError) and not isinstance(exc, SigmaTauError) and exc.filename:
        text = f"{exc.strerror or exc}: {exc.filename}"
    else:
        text = str(exc) or type(exc).__name__
    return text.strip().splitlines()[0] if text.strip() else type(exc).__name__


def _write_json(path: Path, data: Any, *, fsync: bool = True) -> None:
    """Write ``data`` as JSON to ``path`` atomically: a temporary file, fsynced unless told not to, renamed."""
    tmp = path.with_name(f".{path.name}.{uuid.uuid4().hex[:8]}.tmp")
    with open(tmp, "w", encoding="utf-8", newline="") as fh:
        fh.write(json.dumps(data, indent=1, allow_nan=False, ensure_ascii=False) + "\n")
        fh.flush()
        if fsync:
            os.fsync(fh.fileno())
    os.replace(tmp, path)


def _write_text(path: Path, text: Union[str, bytes]) -> None:
    """Write text or bytes to ``path`` atomically (a temporary file renamed into place)."""
    tmp = path.with_name(f".{path.name}.{uuid.uuid4().hex[:8]}.tmp")
    tmp.write_bytes(text.encode("utf-8") if isinstance(text, str) else text)
    os.replace(tmp, path)
