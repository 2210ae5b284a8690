"""Readers registered by format name, format detection, and what a reader hands back."""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Mapping, Sequence

import numpy as np

from ..errors import ParameterError
from ._errors import FormatError

__all__ = ["Options", "Table", "ReaderSpec", "register", "formats", "get", "detect", "file_sha256"]


@dataclass(frozen=True)
class Options:
    """The validated keyword arguments of :func:`sigmatau.io.read`."""

    format: str | None = None
    columns: object = None
    time_column: object = None
    time_unit: str | None = None
    rate: float | None = None
    data_type: str | None = None
    units: Mapping[str, str] | None = None
    topic: str | None = None
    dataset: str | None = None
    stamps: str | None = None
    gaps: str = "refuse"
    gap_threshold: float = 1.5
    unsorted: str = "sort"
    duplicates: str = "drop"
    allow_nan: bool = False
    delimiter: str | None = None


@dataclass
class Table:
    """What a reader found: the chosen columns as float64 and what the file says about them.

    Keys of ``data``, ``units`` and ``groups`` are the file's column names.
    """

    format: str
    columns: tuple[str, ...]
    data: dict[str, np.ndarray]
    rows: int
    sha256: str
    size: int
    time: np.ndarray | None = None
    time_name: str | None = None
    time_unit: str | None = None
    time_unit_reason: str = ""
    units: dict[str, str] = field(default_factory=dict)
    unit_origin: str = "file"
    groups: dict[str, str] = field(default_factory=dict)
    rename: dict[str, str] = field(default_factory=dict)
    rate: float | None = None
    data_type: str | None = None
    detail: str = ""
    topic: str | None = None
    warnings: list[str] = field(default_factory=list)
    unused: tuple[tuple[str, str], ...] = ()  # (column, why) left out by the automatic choice


Reader = Callable[..., Table]


@dataclass(frozen=True)
class ReaderSpec:
    name: str
    func: Reader
    extensions: tuple[str, ...]
    description: str
    options: frozenset[str]  # format-specific options the reader accepts


_READERS: dict[str, ReaderSpec] = {}


def register(
    name: str, *, extensions: Sequence[str] = (), description: str = "", options: Sequence[str] = ()
) -> Callable[[Reader], Reader]:
    """Register a reader function under a format name."""

    def deco(func: Reader) -> Reader:
        _READERS[name] = ReaderSpec(name, func, tuple(extensions), description, frozenset(options))
        return func

    return deco


_ORDER = ("csv", "stable32", "npy", "npz", "rosbag1", "rosbag2", "hdf5", "parquet")


def _names() -> list[str]:
    return sorted(_READERS, key=lambda n: (_ORDER.index(n) if n in _ORDER else len(_ORDER), n))


def formats() -> dict[str, str]:
    """Format names and what each reads."""
    return {name: _READERS[name].description for name in _names()}


def get(name: object) -> ReaderSpec:
    if not isinstance(name, str) or name not in _READERS:
        raise ParameterError(f"format={name!r} is not a known format; formats are: {', '.join(_names())}")
    return _READERS[name]


_MAGIC = (
    (b"\x93NUMPY", "npy"),
    (b"#ROSBAG V2.0", "rosbag1"),
    (b"SQLite format 3\x00", "rosbag2"),
    (b"\x89MCAP", "rosbag2"),
    (b"\x89HDF\r\n\x1a\n", "hdf5"),
    (b"PAR1", "parquet"),
)
_COMPRESSED = (b"\x1f\x8b", b"BZh", b"\xfd7zXZ\x00")
_TEXT_EXT = (".csv", ".tsv", ".txt", ".dat", ".log", ".tab", ".asc")


def _suffix(path: Path) -> str:
    suffixes = [s.lower() for s in path.suffixes]
    if suffixes and suffixes[-1] in (".gz", ".bz2", ".xz"):
        suffixes = suffixes[:-1]
    return suffixes[-1] if suffixes else ""


def detect(path: Path, display: str, head: bytes | None = None) -> tuple[str, bool]:
    """Format name of an existing path, and whether a text file's flavour is still open.

    Content (magic bytes) decides first, then the extension; other files are
    read as text unless they hold binary bytes. ``head``: the first bytes when
    the caller has read them already (a pipe cannot be opened twice).
    """
    if path.is_dir():
        if (path / "metadata.yaml").is_file():
            return "rosbag2", False
        raise FormatError(f"{display}: is a directory, not a ROS 2 bag (no metadata.yaml in it)")
    if head is None:
        with path.open("rb") as fh:
            head = fh.read(8192)
    for magic, name in _MAGIC:
        if head.startswith(magic):
            return name, False
    if head.startswith(b"PK\x03\x04") or head.startswith(b"PK\x05\x06"):
        return "npz", False
    ext = _suffix(path)
    for spec in (_READERS[n] for n in _names()):
        if ext and ext in spec.extensions:
            return spec.name, spec.name == "csv"
    if head.startswith(_COMPRESSED) or ext in _TEXT_EXT:
        return "csv", True
    if b"\x00" in head or _binary_fraction(head) > 0.1:
        raise FormatError(
            f"{display}: unrecognised format (binary content, extension {ext or 'none'!r});"
            f" formats are: {', '.join(_names())}"
        )
    return "csv", True


def _binary_fraction(head: bytes) -> float:
    if not head:
        return 0.0
    text_bytes = bytes(range(32, 127)) + b"\t\r\n\f\b"
    control = head.translate(None, text_bytes + bytes(range(128, 256)))
    return len(control) / len(head)


def file_sha256(path: Path) -> tuple[str, int]:
    """SHA-256 and size of a file, or of a directory's files (names and hashes, sorted)."""
    if path.is_dir():
        outer = hashlib.sha256()
        size = 0
        for p in sorted(q for q in path.rglob("*") if q.is_file()):
            digest, n = file_sha256(p)
            size += n
            outer.update(f"{p.relative_to(path).as_posix()}\0{digest}\n".encode())
        return outer.hexdigest(), size
    h = hashlib.sha256()
    size = 0
    with path.open("rb") as fh:
        while block := fh.read(1 << 20):
            h.update(block)
            size += len(block)
    return h.hexdigest(), size
