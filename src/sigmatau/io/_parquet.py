"""Apache Parquet files via ``pyarrow`` (optional extra ``parquet``).

Numeric columns are channels; a timestamp-typed column is a time column in its
own unit. Schema metadata ``rate``/``sample_rate``/``fs`` gives the rate, field
metadata ``unit``/``units`` the unit. Read in record batches.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import DataError
from ._columns import select
from ._errors import FormatError, require_optional
from ._limits import check_allocation
from ._numpy import RATE_KEYS
from ._progress import Progress
from ._registry import Options, Table, file_sha256, register

__all__ = ["read_parquet"]

_BATCH = 1 << 16
_ARROW_UNITS = {"s": "s", "ms": "ms", "us": "us", "ns": "ns"}


def _meta(meta: dict | None, keys: tuple[str, ...]) -> str | None:
    if not meta:
        return None
    for key in keys:
        value = meta.get(key.encode())
        if value is not None:
            return value.decode(errors="replace")
    return None


@register("parquet", extensions=(".parquet", ".pq"), description="Apache Parquet table (needs extra 'parquet')")
def read_parquet(path: Path, display: str, opts: Options, progress: Progress) -> Table:
    require_optional("pyarrow", extra="parquet", package="pyarrow", what="Parquet files")
    import pyarrow as pa
    import pyarrow.parquet as pq

    try:
        pf = pq.ParquetFile(path)
        schema = pf.schema_arrow
        n = pf.metadata.num_rows
    except (pa.ArrowException, OSError) as exc:
        raise FormatError(f"{display}: not a readable Parquet file ({' '.join(str(exc).split())})") from None
    names = list(schema.names)
    types = [schema.field(nm).type for nm in names]

    def is_time(t: object) -> bool:
        return pa.types.is_timestamp(t) or pa.types.is_duration(t)

    numeric = [pa.types.is_integer(t) or pa.types.is_floating(t) or is_time(t) for t in types]
    first_bad = [None if ok else str(t) for ok, t in zip(numeric, types)]
    sel = select(names, numeric, columns=opts.columns, time_column=opts.time_column, path=display,
                 first_bad=first_bad)
    for j in sel.channels:
        if is_time(types[j]):
            raise DataError(f"{display}: column {names[j]!r} holds times ({types[j]}), not samples")
    if n == 0:
        raise DataError(f"{display}: no numeric data (0 rows)")
    time_unit = sel.time_unit
    reason = f"from the name {names[sel.time]!r}" if sel.time is not None and time_unit else ""
    if sel.time is not None and is_time(types[sel.time]):
        time_unit, reason = _ARROW_UNITS[types[sel.time].unit], f"Arrow type {types[sel.time]}"
    wanted = ([sel.time] if sel.time is not None else []) + list(sel.channels)
    check_allocation(display, 8 * n * len(wanted), f"{len(wanted)} column(s) of {n:,} rows")
    out = {}
    for j in wanted:
        int_time = j == sel.time and (pa.types.is_integer(types[j]) or is_time(types[j]))
        out[j] = np.empty(n, dtype=np.int64 if int_time else np.float64)
    progress.set_total(n, unit="rows")
    pos = 0
    try:
        for batch in pf.iter_batches(batch_size=_BATCH, columns=[names[j] for j in wanted]):
            m = batch.num_rows
            if pos + m > n:
                raise FormatError(f"{display}: more rows than its metadata says ({n})")
            for k, j in enumerate(wanted):
                col = batch.column(k)
                if is_time(col.type):
                    col = col.cast(pa.int64())
                if col.null_count:
                    values = col.to_numpy(zero_copy_only=False).astype(np.float64)
                    if out[j].dtype.kind == "i":
                        raise DataError(f"{display}: time column {names[j]!r} has missing values")
                else:
                    values = col.to_numpy(zero_copy_only=False)
                out[j][pos:pos + m] = values
            pos += m
            progress.update(pos)
    except (pa.ArrowException, OSError) as exc:
        raise FormatError(f"{display}: cannot read the data ({' '.join(str(exc).split())})") from None
    data = {names[j]: out[j][:pos] for j in sel.channels}
    units = {}
    for j in sel.channels:
        unit = _meta(schema.field(names[j]).metadata, ("unit", "units"))
        if unit:
            units[names[j]] = unit
    rate_text = _meta(schema.metadata, RATE_KEYS)
    try:
        rate = float(rate_text) if rate_text else None
    except ValueError:
        rate = None
    digest, size = file_sha256(path)
    return Table(
        format="parquet", columns=tuple(names), data=data, rows=pos, sha256=digest, size=size,
        time=None if sel.time is None else out[sel.time][:pos],
        time_name=None if sel.time is None else names[sel.time], time_unit=time_unit,
        time_unit_reason=reason, units=units, rate=rate,
        detail=f"{pf.metadata.num_row_groups} row group(s), {n} rows", unused=sel.unused,
    )
