"""Reading sensor logs: CSV/TSV/whitespace text, Stable32 data files, NumPy, ROS bags, HDF5, Parquet.

:func:`read` turns a file into a :class:`SensorLog` — float64 channels grouped
as gyro/accel/…, their units, the sample rate, the timestamps and a
:class:`TimingReport` of jitter, gaps, duplicated and out-of-order samples and
what was done about them. :func:`list_topics` lists the topics of a ROS bag.
:func:`open_log` opens a log larger than memory as a :class:`DiskLog` (the same checks, the
channels read in pieces; ``.npy``, stored ``.npz``, HDF5 and text) and :func:`log_size` tells a
log's size from its headers before anything is read.

Formats (see :func:`formats`): ``csv``, ``stable32``, ``npy``, ``npz`` with
NumPy only; ``rosbag1`` and ``rosbag2`` (sqlite3 and MCAP) need the extra
``ros`` (package ``rosbags``), ``hdf5`` the extra ``hdf5`` (``h5py``),
``parquet`` the extra ``parquet`` (``pyarrow``); each is imported only when
such a file is read.

Layer: beside :mod:`sigmatau.imu`, above the statistics. It may import
:mod:`sigmatau.core` and :mod:`sigmatau.errors` only (it has its own unit
tables), never the statistics, reports, the scale-out layer or the CLI.

Errors are one line naming the file and the problem, from sigmatau's hierarchy:
:class:`InputNotFoundError` (also a FileNotFoundError), :class:`FormatError`
and the other :class:`~sigmatau.errors.DataError` cases, a
:class:`~sigmatau.errors.ParameterError` for a bad argument or a column, topic or
dataset that does not exist (listing those that do), and
:class:`MissingDependencyError` naming the extra to install. The input is only
ever read, and read once: a pipe, FIFO or ``/dev/stdin`` works for text logs.

Limits against hostile files: a gyro or accel unit the file states but sigmatau
does not know is refused (declare the unit to override it); lines longer than
:data:`MAX_LINE_CHARS` and more than :data:`MAX_CHANNELS` channels at once are
refused; sizes declared by ``.npy``/``.npz`` headers, zip directories, HDF5 and
Parquet are checked against the memory available before anything is allocated.
Columns the automatic choice leaves out are named in an :class:`InputWarning`
and in ``Source.unused_columns``.

Examples
--------
>>> import tempfile, pathlib, numpy as np
>>> from sigmatau import io
>>> folder = pathlib.Path(tempfile.mkdtemp())
>>> t = 1_403_636_579_758_555_392 + 5_000_000 * np.arange(400)
>>> rows = "\\n".join(f"{ti},0.001,-0.002,0.003,9.81,0.1,-0.2" for ti in t)
>>> header = "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],"
>>> header += "a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]"
>>> _ = (folder / "data.csv").write_text(header + "\\n" + rows + "\\n")
>>> log = io.read(folder / "data.csv")
>>> log.names, log.rate, log.units["gyro_x"], log.timing.time_unit
(('gyro_x', 'gyro_y', 'gyro_z', 'accel_x', 'accel_y', 'accel_z'), 200.0, 'rad/s', 'ns')
"""

from __future__ import annotations

from ._disk import DiskChannel, DiskLog, LogSize, OUT_OF_CORE_FORMATS, log_size, open_log
from ._errors import FormatError, InputNotFoundError, InputWarning, MissingDependencyError, TimingWarning
from ._limits import MAX_CHANNELS, MAX_LINE_CHARS, memory_budget
from ._model import Gap, SensorLog, Source, TimingReport, TopicInfo
from ._read import MIN_SAMPLES, detect_format, list_topics, read
from ._registry import formats
from ._units import DEFAULT_UNITS, GROUP_UNITS, SI_UNITS, TIME_UNITS
# For the layers above (batch, chunked), outside __all__ so that ``from sigmatau.io import *``
# gives what it gave before: read options checked without reading, a file's SHA-256, an
# optional backend imported or named in one line, a size in bytes in a short form.
from ._errors import require_optional  # noqa: F401
from ._read import check_read_options  # noqa: F401
from ._registry import file_sha256  # noqa: F401
from ._limits import fmt_bytes  # noqa: F401

__all__ = [
    "read",
    "open_log",
    "log_size",
    "list_topics",
    "formats",
    "detect_format",
    "SensorLog",
    "DiskLog",
    "DiskChannel",
    "LogSize",
    "OUT_OF_CORE_FORMATS",
    "TimingReport",
    "Gap",
    "Source",
    "TopicInfo",
    "FormatError",
    "InputNotFoundError",
    "MissingDependencyError",
    "InputWarning",
    "TimingWarning",
    "DEFAULT_UNITS",
    "GROUP_UNITS",
    "SI_UNITS",
    "TIME_UNITS",
    "MIN_SAMPLES",
    "MAX_CHANNELS",
    "MAX_LINE_CHARS",
]
