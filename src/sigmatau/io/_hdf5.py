"""HDF5 files via ``h5py`` (optional extra ``hdf5``).

The ``dataset`` option names a dataset or a group. A 2-D dataset (samples ×
columns) gives ``col0`` … (or the names in its ``columns``/``names`` attribute);
a compound dataset one column per field; a group one column per 1-D member
(2-D members: ``key_x/y/z`` or ``key_0`` …). Without ``dataset``: the only
member of the file, else the members at the root, else the only group.
Attributes ``units``/``unit`` give units and ``rate``/``sample_rate``/``fs`` the rate.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Optional

import numpy as np

from ..errors import DataError, ParameterError
from ._columns import select
from ._errors import FormatError, require_optional, option_hint
from ._limits import check_allocation
from ._numpy import RATE_KEYS, split_2d
from ._progress import Progress
from ._registry import Options, Table, file_sha256, register

__all__ = ["read_hdf5"]

_BLOCK = 1 << 18


def _text(value: Any) -> str | None:
    if isinstance(value, bytes):
        return value.decode(errors="replace")
    if isinstance(value, str):
        return value
    if isinstance(value, np.ndarray) and value.shape == () and value.dtype.kind in "SUO":
        return _text(value.item())
    return None


def _texts(value: Any, k: int) -> list[str] | None:
    if isinstance(value, (list, tuple, np.ndarray)) and len(value) == k:
        out = [_text(v) for v in value]
        if all(v is not None for v in out):
            return out  # type: ignore[return-value]
    return None


def _listing(f: Any) -> str:
    found: list[str] = []

    def visit(name: str, obj: Any) -> None:
        if hasattr(obj, "shape"):
            found.append(f"/{name} {tuple(obj.shape)}")

    f.visititems(visit)
    return ", ".join(found[:40]) + (f", … {len(found) - 40} more" if len(found) > 40 else "") or "none"


def _auto(f: Any, display: str) -> Any:
    node = f
    while True:
        members = list(node.values())
        datasets = [m for m in members if hasattr(m, "shape")]
        groups = [m for m in members if not hasattr(m, "shape")]
        if len(members) == 1 and datasets:
            return datasets[0]
        if datasets:
            return node
        if len(groups) == 1:
            node = groups[0]
            continue
        raise FormatError(
            f"{display}: cannot tell which dataset to read; choose one with"
            f" {option_hint('--dataset PATH', 'dataset=')} (datasets: {_listing(f)})"
        )


def _unit_attr(obj: Any) -> Any:
    for key in ("units", "unit"):
        if key in obj.attrs:
            return obj.attrs[key]
    return None


@register("hdf5", extensions=(".h5", ".hdf5", ".hdf", ".he5"),
          description="HDF5 dataset or group (needs extra 'hdf5')", options=("dataset",))
def read_hdf5(path: Path, display: str, opts: Options, progress: Progress) -> Table:
    h5py = require_optional("h5py", extra="hdf5", package="h5py", what="HDF5 files")
    try:
        f = h5py.File(path, "r")
    except (OSError, ValueError) as exc:
        raise FormatError(f"{display}: not a readable HDF5 file ({' '.join(str(exc).split())})") from None
    with f:
        if opts.dataset is not None:
            if opts.dataset not in f:
                raise ParameterError(f"{display}: no dataset or group {opts.dataset!r}; datasets are: {_listing(f)}")
            target = f[opts.dataset]
        else:
            target = _auto(f, display)
        cols = _columns_of(f, target, display)
        names = list(cols.specs)
        numeric = [_kind(cols.specs[nm]) in "biuf" for nm in names]
        sel = select(names, numeric, columns=opts.columns, time_column=opts.time_column, path=display)
        rate = _rate_attribute(target, f)
        out = _read_columns(cols, names, sel, display, progress)
        where = target.name  # read while the file is open (h5py gives None once it is closed)
    data = {names[j]: out[j] for j in sel.channels}
    digest, size = file_sha256(path)
    n = cols.rows
    return Table(
        format="hdf5", columns=tuple(names), data=data, rows=n, sha256=digest, size=size,
        time=None if sel.time is None else out[sel.time],
        time_name=None if sel.time is None else names[sel.time], time_unit=sel.time_unit,
        time_unit_reason=f"from the name {names[sel.time]!r}" if sel.time is not None and sel.time_unit else "",
        units={k: v for k, v in cols.units.items() if k in data}, rate=rate,
        detail=f"{'dataset' if cols.single else 'group'} {where}, {n} rows",
        unused=sel.unused + (tuple(cols.left_out) if opts.columns is None else ()),
    )


@dataclass
class _H5Columns:
    """The columns a dataset or group offers: name -> (dataset, column index, field name or None)."""

    specs: dict[str, tuple[Any, Any]]
    units: dict[str, str]
    rows: int
    single: bool
    left_out: list[tuple[str, str]]


def _kind(spec: tuple[Any, Any]) -> str:
    ds, sub = spec
    return ds.dtype[sub].kind if isinstance(sub, str) else ds.dtype.kind


def _columns_of(f: Any, target: Any, display: str) -> _H5Columns:
    """Every column of ``target`` (a dataset, or a group's datasets of the common length), with units."""
    specs: dict[str, tuple[Any, Any]] = {}
    units: dict[str, str] = {}
    if hasattr(target, "shape"):
        members = [(target.name.rsplit("/", 1)[-1] or "data", target)]
        single = True
    else:
        members = [(k, v) for k, v in target.items() if hasattr(v, "shape")]
        single = False
    lengths = [m.shape[0] for _, m in members if m.ndim in (1, 2) and m.shape[0] > 0]
    if not lengths:
        raise DataError(f"{display}: no numeric data in {target.name} (datasets: {_listing(f)})")
    n = max(set(lengths), key=lengths.count)
    left_out: list[tuple[str, str]] = []
    for key, ds in members:
        if ds.ndim not in (1, 2) or ds.shape[0] != n:
            left_out.append((f"{key} {tuple(ds.shape)}", f"not of the common length {n}"))
            continue
        unit = _unit_attr(ds)
        if ds.dtype.names:
            for field in ds.dtype.names:
                specs[field] = (ds, field)
        elif ds.ndim == 1:
            specs["col0" if single else key] = (ds, None)
            if _text(unit):
                units["col0" if single else key] = _text(unit)  # type: ignore[assignment]
        else:
            k = ds.shape[1]
            attr_names = next((_texts(ds.attrs[a], k) for a in ("columns", "column_names", "names", "fields")
                               if a in ds.attrs and _texts(ds.attrs[a], k)), None)
            names = attr_names or ([f"col{j}" for j in range(k)] if single else split_2d(key, k))
            per_col = _texts(unit, k) if unit is not None else None
            for j, name in enumerate(names):
                specs[name] = (ds, j)
                u = per_col[j] if per_col else _text(unit)
                if u:
                    units[name] = u
    return _H5Columns(specs, units, n, single, left_out)


def _rate_attribute(target: Any, f: Any) -> Optional[float]:
    """The sample rate from an attribute of the dataset/group, else of the file (first readable key)."""
    for obj in (target, f):
        for key in RATE_KEYS:
            if key in obj.attrs:
                try:
                    return float(obj.attrs[key])
                except (TypeError, ValueError):
                    continue
    return None


def _read_columns(cols: _H5Columns, names: list[str], sel: Any, display: str,
                  progress: Progress) -> dict[int, np.ndarray]:
    """The selected columns read in blocks of _BLOCK rows (int64 time tags kept as integers)."""
    n = cols.rows
    progress.set_total(n, unit="rows")
    wanted = ([sel.time] if sel.time is not None else []) + list(sel.channels)
    # the row count is declared: a chunked dataset of 10^11 rows may occupy a few bytes on disk
    check_allocation(display, 8 * n * len(wanted), f"{len(wanted)} column(s) of {n:,} rows")
    out: dict[int, np.ndarray] = {}
    for j in wanted:
        is_int_time = j == sel.time and _kind(cols.specs[names[j]]) in "iu"
        out[j] = np.empty(n, dtype=np.int64 if is_int_time else np.float64)
    try:
        for lo in range(0, n, _BLOCK):
            hi = min(lo + _BLOCK, n)
            cache: dict[int, np.ndarray] = {}
            for j in wanted:
                ds, sub = cols.specs[names[j]]
                block = cache.get(id(ds))
                if block is None:
                    block = cache[id(ds)] = ds[lo:hi]
                out[j][lo:hi] = block[sub] if isinstance(sub, str) else block if sub is None else block[:, sub]
            progress.update(hi)
    except (OSError, ValueError, KeyError) as exc:
        raise FormatError(f"{display}: cannot read the data ({' '.join(str(exc).split())})") from None
    return out
