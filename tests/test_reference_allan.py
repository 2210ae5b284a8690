"""Validation of the Allan and Hadamard families against published numbers.

Sources (see /work/shared/reference/numerics.md §7 and tests/data/allantools/README.md):

* NBS 1000-point set: SP1065 Table 31 / Riley's test-suite Table III, as transcribed
  in numerics.md §7.1–7.2. Tolerance: half a unit in the last printed digit.
* NBS 9-point set (NBS Monograph 140): SP1065 Table 30, numerics.md §7.3, same tolerance.
* Stable32 v1.53/1.60 output tables copied from allantools. Stable32 prints five
  significant digits, so a deviation is held to a relative 1e-4 (a rounded 5-digit
  mantissa is off by at most 5e-5 of itself) and the number of terms exactly.
"""

from __future__ import annotations

import functools
import warnings

import numpy as np
import pytest

import refdata
from helpers import assert_printed
import sigmatau
from sigmatau.datasets import nbs1000, nbs9

STABLE32_RTOL = 1e-4


def compute(statistic: str, data, *, rate: float, data_type: str, m) -> sigmatau.StabilityResult:
    """Run ``statistic`` at explicit averaging factors.

    The reference tables go past our default limit ⌊N/stop⌋ (all-τ runs, Stable32's own
    grids for some statistics), for which the driver issues a RangeWarning by design;
    here those factors are requested on purpose.
    """
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", sigmatau.RangeWarning)
        return getattr(sigmatau, statistic)(data, rate=rate, data_type=data_type, m=m)


# --- NBS 1000-point set (numerics.md §7.1) ---------------------------------------------

# i -> (n_i, y_i) of the Park–Miller sequence.
LCG_TABLE = {
    0: (1234567890, "0.5748904732"),
    1: (395529916, "0.1841829699"),
    2: (1209410747, "0.5631757656"),
    3: (633705974, "0.2950923398"),
    4: (1324899545, "0.6169544280"),
    5: (328717072, "0.1530708150"),
    999: (1560135652, "0.7264947764"),
}


@pytest.mark.parametrize("i", sorted(LCG_TABLE))
def test_nbs1000_generator_values(i):
    y = nbs1000()
    n_i, y_i = LCG_TABLE[i]
    # y_i = n_i / (2^31 - 1) exactly in float64, so the integer state is recoverable.
    assert round(y[i] * 2147483647) == n_i
    assert_printed(y[i], y_i)


def test_nbs1000_summary():
    y = nbs1000()
    assert y.shape == (1000,)
    assert y.dtype == np.float64
    assert_printed(np.std(y, ddof=1), "2.884664e-01")
    assert_printed(np.std(y, ddof=0), "2.883221e-01")
    assert_printed(np.mean(y), "4.897745e-01")
    assert_printed(np.median(y), "4.798849e-01")
    assert_printed(y.min(), "1.371760e-03")
    assert_printed(y.max(), "9.957453e-01")
    x = sigmatau.frequency_to_phase(y)
    assert x.size == 1001
    assert x[0] == 0.0
    assert_printed(x[-1], "489.774463")


def test_phase_dat_is_nbs1000_phase():
    # Stable32's PHASE.DAT is the NBS set integrated after removing its mean (README).
    y = nbs1000()
    x = sigmatau.frequency_to_phase(y - y.mean())
    np.testing.assert_allclose(refdata.phase_dat(), x, rtol=0, atol=1e-12)


# (statistic, m) -> printed deviation, numerics.md §7.2.
NBS1000_DEV = {
    ("adev", 1): "2.922319e-01", ("adev", 10): "9.965736e-02", ("adev", 100): "3.897804e-02",
    ("oadev", 1): "2.922319e-01", ("oadev", 10): "9.159953e-02", ("oadev", 100): "3.241343e-02",
    ("mdev", 1): "2.922319e-01", ("mdev", 10): "6.172376e-02", ("mdev", 100): "2.170921e-02",
    ("tdev", 1): "1.687202e-01", ("tdev", 10): "3.563623e-01", ("tdev", 100): "1.253382e+00",
    # Non-overlapped HDEV at m = 100 is printed 3.910860e-02 in Riley's Table III, a
    # truncation of 3.9108606e-02 (numerics.md §7.2 gives the full value): test that one.
    ("hdev", 1): "2.943883e-01", ("hdev", 10): "1.052754e-01", ("hdev", 100): "3.9108606e-02",
    # Listed as "HDEV" in the SP1065 T31 transcription; it is the overlapped form.
    ("ohdev", 1): "2.943883e-01", ("ohdev", 10): "9.581083e-02", ("ohdev", 100): "3.237638e-02",
    ("stdev", 1): "2.884664e-01", ("stdev", 10): "9.296352e-02", ("stdev", 100): "3.206656e-02",
    # Overlapped averages: computed independently only (no published counterpart).
    ("ostdev", 1): "2.884664e-01", ("ostdev", 10): "8.763251e-02", ("ostdev", 100): "2.724726e-02",
}

# Number of terms at m = 1, 10, 100 (numerics.md §7.2 "Number of terms"; TVAR shares MVAR's
# sum). stdev/ostdev are not listed there: their n is the number of averages, ⌊M/m⌋ and
# M - m + 1 by definition (§1.1).
NBS1000_TERMS = {
    "adev": [999, 99, 9],
    "oadev": [999, 981, 801],
    "mdev": [999, 972, 702],
    "tdev": [999, 972, 702],
    "hdev": [998, 98, 8],
    "ohdev": [998, 971, 701],
    "stdev": [1000, 100, 10],
    "ostdev": [1000, 991, 901],
}


@pytest.mark.parametrize(("statistic", "m"), sorted(NBS1000_DEV), ids=lambda v: str(v))
def test_nbs1000_deviation(statistic, m):
    result = getattr(sigmatau, statistic)(nbs1000(), m=m)
    assert result.m.tolist() == [m]
    assert result.taus.tolist() == [float(m)]
    assert_printed(result.dev[0], NBS1000_DEV[statistic, m])


@pytest.mark.parametrize("statistic", sorted(NBS1000_TERMS))
def test_nbs1000_terms(statistic):
    result = getattr(sigmatau, statistic)(nbs1000(), m=[1, 10, 100])
    assert result.n.tolist() == NBS1000_TERMS[statistic]
    assert result.n_points == 1001


# --- NBS 9-point set (numerics.md §7.3) -------------------------------------------------

NBS9_DEV = {
    "adev": ("91.22945", "115.8082"),
    "oadev": ("91.22945", "85.95287"),
    "mdev": ("91.22945", "74.78849"),
    "tdev": ("52.67135", "86.35831"),
    "ohdev": ("70.80607", "85.61487"),  # "HDEV" of the SP1065 table (overlapped)
    "hdev": ("70.80607", "116.7980"),  # non-overlapped, as in Riley's older paper
}


def test_nbs9_data():
    y = nbs9()
    assert y.tolist() == [892, 809, 823, 798, 671, 644, 883, 903, 677]
    assert sigmatau.frequency_to_phase(y).tolist() == [
        0, 892, 1701, 2524, 3322, 3993, 4637, 5520, 6423, 7100,
    ]
    assert_printed(np.mean(y), "788.889")
    assert_printed(np.std(y, ddof=1), "100.977")
    assert_printed(sigmatau.stdev(y, m=1).dev[0], "100.977")


@pytest.mark.parametrize("statistic", sorted(NBS9_DEV))
def test_nbs9_deviation(statistic):
    result = getattr(sigmatau, statistic)(nbs9(), m=[1, 2])
    assert result.m.tolist() == [1, 2]
    for value, printed in zip(result.dev, NBS9_DEV[statistic]):
        assert_printed(value, printed)


# --- Stable32 tables (tests/data/allantools) ---------------------------------------------


dataset = refdata.dataset


_STATS = ("adev", "oadev", "mdev", "tdev", "hdev", "ohdev")

# Stable32 ran the ocxo *_octave.txt tables on f/1e7 ≈ 1 (their header: "Average =
# 1.000000e+00"), not on y = f/1e7 - 1 as the all-τ tables ("Average = 1.881550e-13").
# Integrating 1 + y to a phase of ~2e4 s in float64 adds rounding noise of ~1e-12 s to
# phase steps of 7.6e-11 s: the overlapped tables are up to 1.8e-3 above the exact value
# (their OADEV at m = 1 is 7.6143e-11 against 7.6106e-11 for their own ADEV at m = 1, the
# same quantity), the non-overlapped ones (block sums of 1 + y) up to 1.5e-4 at m = 2048.
# These tables are therefore compared twice (test_stable32_ocxo_octave_*): the plain sums
# on the data as Stable32 saw it reproduce the printed values, and sigmatau's exact value
# differs from the printed one by no more than that round-off artefact.
_OCXO_OCTAVE = {f"ocxo/{s}_octave.txt" for s in ("adev", "oadev", "mdev", "tdev", "hdev", "ohdev")}

# τ0 of a Stable32 run when it differs from the rate of the data set: this table was run
# with τ0 = 1 s (its Tau column equals AF); a deviation of frequency data does not
# depend on τ0.
_TABLE_TAU0 = {"pink_frequency/s32_oadev_octave.txt": 1.0}


def _tables():
    out = []
    for s in _STATS:
        out += [
            ("phasedat", f"phasedat/phase_dat_{s}.txt", s, None),
            ("phasedat", f"phasedat/phase_dat_{s}_octave.txt", s, "octave"),
            ("gps", f"gps/stable32_{'ADEV_decade' if s == 'adev' else s.upper() + '_octave'}.txt",
             s, "decade" if s == "adev" else "octave"),
            ("ocxo", f"ocxo/{s}_octave.txt", s, "octave"),
            ("ocxo", f"ocxo/stable32_{s}_alltau.txt", s, None),
            # tic_adev.txt is a dense (all-τ) run; the others are octave runs.
            ("tic", f"Keysight53230A_ti_noise_floor/tic_{s}.txt", s, None if s == "adev" else "octave"),
            ("pink", f"pink_frequency/{s}.txt", s, None),
        ]
    out.append(("pink", "pink_frequency/s32_oadev_octave.txt", "oadev", "octave"))
    return out


TABLES = _tables()


def _params(exact_tables_only: bool):
    return [
        pytest.param(name, path, statistic, id=path)
        for name, path, statistic, grid in TABLES
        if not (exact_tables_only and path in _OCXO_OCTAVE)
    ]


@functools.lru_cache(maxsize=None)
def _run_table(name: str, path: str, statistic: str):
    table = refdata.load_table(path, include_commented=True)
    data, rate, data_type = dataset(name)
    return table, compute(statistic, data, rate=rate, data_type=data_type, m=table.af)


@pytest.mark.slow
@pytest.mark.parametrize(("name", "path", "statistic"), _params(exact_tables_only=False))
def test_stable32_terms(name, path, statistic):
    table, result = _run_table(name, path, statistic)
    np.testing.assert_array_equal(result.m, table.af)
    np.testing.assert_array_equal(result.n, table.n)
    tau0 = _TABLE_TAU0.get(path)
    expected_tau = result.taus if tau0 is None else result.m * tau0
    # The Tau column is printed with five significant digits.
    np.testing.assert_allclose(table.tau, expected_tau, rtol=5e-5, atol=0)


@pytest.mark.parametrize(("name", "path", "statistic"), _params(exact_tables_only=True))
def test_stable32_deviation(name, path, statistic):
    table, result = _run_table(name, path, statistic)
    np.testing.assert_allclose(result.dev, table.sigma, rtol=STABLE32_RTOL, atol=0)


@pytest.mark.parametrize("path", sorted(_OCXO_OCTAVE))
def test_stable32_ocxo_octave_reproduced_on_f_over_1e7(path):
    # The plain sums on f/1e7 in float64 give every printed value (measured ≤ 2.4e-5);
    # on y the same sums are 1.1e-4 … 1.8e-3 away: the tables carry Stable32's round-off.
    table = refdata.load_table(path)
    statistic = path.split("/")[1].split("_")[0]
    as_seen = refdata.stable32_float_freq_dev(statistic, refdata.ocxo_normalised(), table.af)
    np.testing.assert_allclose(as_seen, table.sigma, rtol=STABLE32_RTOL, atol=0)
    exact = refdata.stable32_float_freq_dev(statistic, refdata.ocxo_frequency(), table.af)
    assert np.abs(exact / table.sigma - 1).max() > STABLE32_RTOL


@pytest.mark.parametrize("path", sorted(_OCXO_OCTAVE))
def test_stable32_ocxo_octave_within_its_roundoff(path):
    # sigmatau on y is the exact value: row by row it differs from the printed one by at
    # most Stable32's own round-off (plain sums on f/1e7 against the same sums on y) plus
    # the printing tolerance, and it equals the exact plain sums to 1e-9.
    table, result = _run_table("ocxo", path, path.split("/")[1].split("_")[0])
    statistic = result.statistic
    exact = refdata.stable32_float_freq_dev(statistic, refdata.ocxo_frequency(), table.af)
    as_seen = refdata.stable32_float_freq_dev(statistic, refdata.ocxo_normalised(), table.af)
    np.testing.assert_allclose(result.dev, exact, rtol=1e-9, atol=0)
    artefact = np.abs(as_seen / exact - 1)
    assert np.all(np.abs(result.dev / table.sigma - 1) <= artefact + STABLE32_RTOL)


def test_stable32_tables_include_commented_rows():
    # The rows upstream commented out (pink-noise AF 2426 and 2484) are valid values and
    # are part of the comparison above.
    table = refdata.load_table("pink_frequency/oadev.txt")
    assert table.commented.sum() == 2
    assert table.af[table.commented].tolist() == [2426, 2484]


GRID_TABLES = [
    pytest.param(name, path, statistic, grid, id=path)
    for name, path, statistic, grid in TABLES
    if grid is not None
]


@pytest.mark.parametrize(("name", "path", "statistic", "grid"), GRID_TABLES)
def test_default_grid_matches_stable32(name, path, statistic, grid):
    # Stable32 stops octave/decade runs at ⌊N/stop⌋ (numerics.md §1); so do our keyword grids.
    # The ocxo ADEV/HDEV (2048, not 4096) and OADEV/OHDEV (4096) tables tell stop 5 from 4.
    table = refdata.load_table(path)
    data, rate, data_type = dataset(name)
    with warnings.catch_warnings():
        warnings.simplefilter("error", sigmatau.RangeWarning)
        result = getattr(sigmatau, statistic)(data, rate=rate, data_type=data_type, taus=grid)
    np.testing.assert_array_equal(result.m, table.af)
