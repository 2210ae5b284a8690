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


def ocxo_normalised() -> np.ndarray:
    """OCXO frequency as the Stable32 octave runs (``ocxo/*_octave.txt``) read it: f/1e7 ≈ 1.

    Their headers say "Average = 1.000000e+00" where the all-τ runs of y = f/1e7 − 1
    say "Average = 1.881550e-13".
    """
    return _column(DATA / "ocxo" / "ocxo_frequency.txt") / 1e7


def stable32_float_freq_dev(statistic: str, u: np.ndarray, ms, alpha=None) -> np.ndarray:
    """Deviations of frequency data ``u`` (τ0 = 1) by the plain sums, in float64, in the
    order a program that does not remove the mean frequency first would use.

    This reproduces the round-off of Stable32's octave runs on f/1e7 = 1 + y: the
    non-overlapped ADEV/HDEV from averages of ``u`` summed sequentially over each block,
    every other statistic from the phase ``x = [0, cumsum(u)]`` (about 2·10⁴ s for the
    OCXO, so each point carries a rounding error of up to ulp/2 ≈ 1.8e-12 s against
    7.6e-11 s phase steps: an added white-PM-like noise). Applied to y itself it gives
    the exact statistic. ``alpha`` (one per m) applies the TOTVAR bias 1 − aτ/T of
    SP1065 (a = 0, 1/(3 ln 2), 0.75 for α = 0, −1, −2; T = M τ0), as Stable32 does.
    A test oracle: plain loops over numpy slices, no sigmatau code.
    """
    u = np.asarray(u, dtype=np.float64)
    x = np.concatenate(([0.0], np.cumsum(u)))
    out = []
    for k, m in enumerate(int(v) for v in np.atleast_1d(ms)):
        if statistic in ("adev", "hdev"):
            blocks = u[: (u.size // m) * m].reshape(-1, m)
            avg = np.cumsum(blocks, axis=1)[:, -1] / m
            d = np.diff(avg, 1 if statistic == "adev" else 2)
            var = np.mean(d**2) / (2.0 if statistic == "adev" else 6.0)
        elif statistic in ("oadev", "mdev", "tdev"):
            d2 = x[2 * m:] - 2 * x[m:-m] + x[: -2 * m]
            if statistic == "oadev":
                var = np.mean(d2**2) / (2.0 * m * m)
            else:
                c = np.concatenate(([0.0], np.cumsum(d2)))
                var = np.mean((c[m:] - c[:-m]) ** 2) / (2.0 * m**4)
                if statistic == "tdev":
                    var *= m * m / 3.0
        elif statistic == "ohdev":
            d3 = x[3 * m:] - 3 * x[2 * m: -m] + 3 * x[m: -2 * m] - x[: -3 * m]
            var = np.mean(d3**2) / (6.0 * m * m)
        elif statistic == "totdev":
            n = x.size
            ext = np.concatenate((2 * x[0] - x[n - 2:0:-1], x, 2 * x[-1] - x[-2:0:-1]))
            i = np.arange(1, n - 1) + (n - 2)
            d2 = ext[i - m] - 2 * ext[i] + ext[i + m]
            var = np.sum(d2**2) / (2.0 * m * m * (n - 2))
            a = {0: 0.0, -1: 1.0 / (3.0 * np.log(2.0)), -2: 0.75}
            if alpha is not None:
                var /= 1.0 - a.get(int(np.atleast_1d(alpha)[k]), 0.0) * m / u.size
        else:
            raise KeyError(statistic)
        out.append(np.sqrt(var))
    return np.array(out)


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
