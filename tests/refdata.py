"""Readers for the Stable32 reference tables and data sets in tests/data/allantools.

Provenance and licence of the files: tests/data/allantools/README.md.
"""

from __future__ import annotations

import functools
import gzip
from dataclasses import dataclass
from pathlib import Path

import numpy as np

DATA = Path(__file__).parent / "data" / "allantools"


@dataclass(frozen=True)
class Table:
    """A Stable32 output table. ``commented`` marks rows that upstream commented out."""

    path: Path
    af: np.ndarray
    tau: np.ndarray
    n: np.ndarray
    alpha: np.ndarray | None
    min_sigma: np.ndarray | None
    sigma: np.ndarray
    max_sigma: np.ndarray | None
    commented: np.ndarray


def _numeric_row(text: str) -> list[float] | None:
    parts = text.split()
    if len(parts) not in (4, 7):
        return None
    try:
        return [float(p) for p in parts]
    except ValueError:
        return None


def load_table(relpath: str, *, include_commented: bool = True) -> Table:
    """Read a table; rows commented out with '#' are kept when they are numeric rows."""
    path = DATA / relpath
    rows, commented = [], []
    for line in path.read_text(encoding="utf-8").splitlines():
        line = line.strip()
        is_comment = line.startswith("#")
        row = _numeric_row(line.lstrip("#")) if is_comment else _numeric_row(line)
        if row is None or (is_comment and not include_commented):
            continue
        rows.append(row)
        commented.append(is_comment)
    arr = np.array(rows)
    if arr.shape[1] == 4:
        return Table(path, arr[:, 0].astype(int), arr[:, 1], arr[:, 2].astype(int), None, None,
                     arr[:, 3], None, np.array(commented))
    return Table(path, arr[:, 0].astype(int), arr[:, 1], arr[:, 2].astype(int), arr[:, 3].astype(int),
                 arr[:, 4], arr[:, 5], arr[:, 6], np.array(commented))


def _column(path: Path, skip_nonnumeric: bool = True) -> np.ndarray:
    opener = gzip.open if path.suffix == ".gz" else open
    with opener(path, "rt", encoding="utf-8") as fh:
        return np.array([float(l.split()[0]) for l in fh if l.strip() and not l.lstrip().startswith("#")])


def phase_dat() -> np.ndarray:
    """PHASE.DAT (Stable32): 1001 phase points, τ0 = 1 s."""
    return _column(DATA / "phasedat" / "PHASE.DAT")


def gps_phase() -> np.ndarray:
    """GPS 1PPS vs H-maser phase in seconds, τ0 = 1 s (241218 points)."""
    return _column(DATA / "gps" / "gps_1pps_phase_data.txt.gz")


def ocxo_frequency() -> np.ndarray:
    """OCXO fractional frequency, τ0 = 1 s (normalised with the nominal 10 MHz, as upstream)."""
    f = _column(DATA / "ocxo" / "ocxo_frequency.txt")
    return f / 1e7 - 1.0


def tic_phase() -> np.ndarray:
    """Keysight 53230A time-interval noise floor, phase in seconds (first 55688 points)."""
    return _column(DATA / "Keysight53230A_ti_noise_floor" / "tic_phase.txt")[:55688]


def pink_frequency() -> np.ndarray:
    """Simulated pink-FM fractional frequency, 10000 points, τ0 = 42 s."""
    return _column(DATA / "pink_frequency" / "pink_frequency.txt")


PINK_RATE = 1.0 / 42.0


@functools.lru_cache(maxsize=None)
def dataset(name: str) -> tuple[np.ndarray, float, str]:
    """(data, rate, data_type) of a reference data set, as the Stable32 runs read it."""
    if name == "phasedat":
        return phase_dat(), 1.0, "phase"
    if name == "gps":
        return gps_phase(), 1.0, "phase"
    if name == "ocxo":
        return ocxo_frequency(), 1.0, "freq"
    if name == "tic":
        return tic_phase(), 1.0, "phase"
    if name == "pink":
        return pink_frequency(), PINK_RATE, "freq"
    raise KeyError(name)
