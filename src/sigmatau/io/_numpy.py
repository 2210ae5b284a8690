"""NumPy ``.npy`` and ``.npz`` files (never unpickled).

* ``.npy``: samples along the first axis. A 1-D array is one channel
  (``col0``), a 2-D array one channel per column (``col0`` …), a structured array
  one channel per field (named, so the time column is found by name).
* ``.npz``: every 1-D array of the common length is a column named by its key; a
  2-D array ``key`` of that length gives ``key_x/y/z`` (3 columns) or
  ``key_0`` …; a scalar ``rate`` (or ``fs``, ``sample_rate``, ``sampling_rate``)
  gives the rate.
"""

from __future__ import annotations

import zipfile
from collections import Counter
from pathlib import Path

import numpy as np

from ..errors import DataError
from ._columns import select
from ._errors import FormatError
from ._progress import Progress
from ._registry import Options, Table, file_sha256, register

__all__ = ["read_npy", "read_npz", "split_2d"]

RATE_KEYS = ("rate", "sample_rate", "sampling_rate", "fs")


def split_2d(key: str, k: int) -> list[str]:
    """Column names for a (n, k) member named ``key``."""
    return [f"{key}_{a}" for a in "xyz"] if k == 3 else [f"{key}_{j}" for j in range(k)]


def _numeric_kind(a: np.ndarray) -> bool:
    return a.dtype.kind in "biuf"


def _table_from_columns(
    cols: dict[str, np.ndarray], *, fmt: str, display: str, opts: Options, detail: str,
    rate: float | None = None, units: dict[str, str] | None = None,
) -> Table:
    names = list(cols)
    numeric = [_numeric_kind(cols[n]) for n in names]
    first_bad = [None if numeric[j] else str(cols[n][:1].tolist()[:1] or "")[:40] for j, n in enumerate(names)]
    sel = select(names, numeric, columns=opts.columns, time_column=opts.time_column, path=display,
                 first_bad=first_bad)
    data = {names[j]: np.asarray(cols[names[j]], dtype=np.float64) for j in sel.channels}
    time = None
    if sel.time is not None:
        t = np.asarray(cols[names[sel.time]])
        time = t.astype(np.int64) if t.dtype.kind in "iu" else t.astype(np.float64)
    rows = next(iter(data.values())).size
    if rows == 0:
        raise DataError(f"{display}: no numeric data (0 samples)")
    return Table(
        format=fmt, columns=tuple(names), data=data, rows=rows, sha256="", size=0, time=time,
        time_name=None if sel.time is None else names[sel.time], time_unit=sel.time_unit,
        time_unit_reason=f"from the name {names[sel.time]!r}" if sel.time is not None and sel.time_unit
        else "", rate=rate, units={k: v for k, v in (units or {}).items() if k in data}, detail=detail,
    )


@register("npy", extensions=(".npy",), description="NumPy .npy array: samples along the first axis")
def read_npy(path: Path, display: str, opts: Options, progress: Progress) -> Table:
    try:
        arr = np.load(path, mmap_mode="r", allow_pickle=False)
    except ValueError as exc:
        text = " ".join(str(exc).split())
        if "pickle" in text.lower():
            raise FormatError(f"{display}: holds Python objects (pickled), which are never loaded") from None
        raise FormatError(f"{display}: not a valid .npy file ({text})") from None
    except (OSError, EOFError) as exc:
        raise FormatError(f"{display}: not a valid .npy file ({' '.join(str(exc).split())})") from None
    if arr.dtype.names:
        if arr.ndim != 1:
            raise FormatError(f"{display}: a structured array must be 1-D, got shape {arr.shape}")
        cols = {name: arr[name] for name in arr.dtype.names}
        bad = [n for n, c in cols.items() if c.ndim != 1]
        if bad:
            raise FormatError(f"{display}: fields {bad} are not scalar per sample")
    elif arr.ndim == 1:
        cols = {"col0": arr}
    elif arr.ndim == 2:
        cols = {f"col{j}": arr[:, j] for j in range(arr.shape[1])}
    else:
        raise DataError(
            f"{display}: array of shape {arr.shape}; expected 1-D (one channel) or 2-D (samples × channels)"
        )
    if arr.shape[0] == 0:
        raise DataError(f"{display}: no numeric data (0 samples)")
    if not any(_numeric_kind(c) for c in cols.values()):
        raise DataError(f"{display}: no numeric data (dtype {arr.dtype})")
    table = _table_from_columns(cols, fmt="npy", display=display, opts=opts,
                                detail=f"array {arr.dtype} of shape {arr.shape}")
    table.sha256, table.size = file_sha256(path)
    return table


@register("npz", extensions=(".npz",), description="NumPy .npz archive: one array per column, optional rate")
def read_npz(path: Path, display: str, opts: Options, progress: Progress) -> Table:
    # The file is opened here, not by np.load: numpy leaves its own handle open when the
    # archive turns out to be corrupt.
    with open(path, "rb") as fh:
        try:
            archive = np.load(fh, allow_pickle=False)
        except (ValueError, OSError, EOFError, zipfile.BadZipFile) as exc:
            raise FormatError(f"{display}: not a valid .npz file ({' '.join(str(exc).split())})") from None
        if not isinstance(archive, np.lib.npyio.NpzFile):
            raise FormatError(f"{display}: not an .npz archive")
        with archive:
            arrays: dict[str, np.ndarray] = {}
            for key in archive.files:
                try:
                    arrays[key] = archive[key]
                except ValueError as exc:
                    if "pickle" in str(exc).lower():
                        raise FormatError(
                            f"{display}: array {key!r} holds Python objects, which are never loaded"
                        ) from None
                    raise FormatError(f"{display}: array {key!r} is corrupt ({' '.join(str(exc).split())})") from None
                except (OSError, EOFError, zipfile.BadZipFile) as exc:
                    raise FormatError(f"{display}: array {key!r} is corrupt ({' '.join(str(exc).split())})") from None
    rate = None
    for key in RATE_KEYS:
        if key in arrays and arrays[key].ndim == 0 and _numeric_kind(arrays[key]):
            rate = float(arrays[key])
            break
    lengths = Counter(a.shape[0] for a in arrays.values() if a.ndim in (1, 2) and a.shape[0] > 0)
    if not lengths:
        shapes = ", ".join(f"{k} {a.shape}" for k, a in arrays.items())
        raise DataError(f"{display}: no numeric data (arrays: {shapes})")
    n = lengths.most_common(1)[0][0]
    cols: dict[str, np.ndarray] = {}
    ignored = []
    for key, a in arrays.items():
        if a.ndim == 1 and a.shape[0] == n:
            cols[key] = a
        elif a.ndim == 2 and a.shape[0] == n:
            for j, name in enumerate(split_2d(key, a.shape[1])):
                cols[name] = a[:, j]
        elif key not in RATE_KEYS:
            ignored.append(f"{key} {a.shape}")
    detail = f"{len(arrays)} arrays, {n} samples"
    if ignored:
        detail += f"; not of that length, left out: {', '.join(ignored)}"
    table = _table_from_columns(cols, fmt="npz", display=display, opts=opts, detail=detail, rate=rate)
    table.sha256, table.size = file_sha256(path)
    return table
