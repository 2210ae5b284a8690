"""Helpers shared by the test modules (import as ``from helpers import ...``).

- :func:`half_unit` and :func:`assert_printed`: compare with a published number to the digits
  printed in the source, the tolerance every reference-table test uses.
- :func:`assert_one_line_error`: what the CLI promises for bad input — a non-zero exit, one line
  on stderr that names what is wrong, no traceback.
"""

from __future__ import annotations

import re
import subprocess
from decimal import Decimal

import numpy as np


def half_unit(printed: str) -> float:
    """Half a unit in the last digit of a printed number (trailing zeros count).

    >>> half_unit("2.922319e-01")
    5e-08
    >>> half_unit("0.0100")
    5e-05
    """
    return 0.5 * 10.0 ** Decimal(printed.strip()).as_tuple().exponent


def assert_printed(value: float, printed: str) -> None:
    """``value`` rounds to ``printed`` at the digits shown there (half a unit in the last one)."""
    ref = float(printed)
    np.testing.assert_allclose(value, ref, rtol=half_unit(printed) / abs(ref), atol=0.0)


def assert_one_line_error(result: subprocess.CompletedProcess | tuple[int, str], *,
                          code: int | None = None, match: str | None = None) -> str:
    """A failed CLI run: non-zero exit (``code`` if given), one stderr line, no traceback.

    ``result`` is a finished subprocess or ``(exit_code, stderr)`` from calling ``main`` in
    process. ``match`` is a regular expression the line must contain. Returns the line.
    """
    rc, err = (result.returncode, result.stderr) if hasattr(result, "returncode") else result
    assert rc != 0, "expected a failure"
    if code is not None:
        assert rc == code, f"exit {rc}, expected {code}: {err!r}"
    assert "Traceback" not in err, err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1, f"expected one line on stderr, got {len(lines)}: {err!r}"
    if match is not None:
        assert re.search(match, lines[0]), f"{match!r} not in {lines[0]!r}"
    return lines[0]


def run_cli(argv, capsys) -> tuple[int, str, str]:
    """``sigmatau.cli.main`` on ``argv`` (items made strings) in process: (exit code, stdout, stderr)."""
    from sigmatau.cli import main

    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def cli_error_line(err: str, *patterns: str) -> str:
    """The one error line of a CLI run's stderr (warning lines aside), containing every pattern."""
    lines = [ln for ln in err.splitlines() if ln.strip() and not ln.startswith("sigmatau: warning:")]
    assert len(lines) == 1, err
    assert "Traceback" not in err
    for p in patterns:
        assert p in lines[0], (p, lines[0])
    return lines[0]


def assert_same_result(got, ref, rtol: float = 1e-12) -> None:
    """Two StabilityResults are the same result: τ grid, counts, gaps and flags exactly, the
    variance and deviation to ``rtol``, the noise type, EDF and interval to 1e-9 (the chunked and
    in-memory paths, for instance)."""
    assert got.statistic == ref.statistic and got.data_type == ref.data_type
    assert got.n_points == ref.n_points and got.rate == ref.rate
    np.testing.assert_array_equal(got.m, ref.m)
    np.testing.assert_array_equal(got.taus, ref.taus)
    np.testing.assert_array_equal(got.n, ref.n)
    assert got.n_missing == ref.n_missing
    assert (got.n_effective is None) == (ref.n_effective is None)
    if ref.n_effective is not None:
        np.testing.assert_array_equal(got.n_effective, ref.n_effective)
    np.testing.assert_allclose(got.var, ref.var, rtol=rtol, atol=0)
    np.testing.assert_allclose(got.dev, ref.dev, rtol=rtol, atol=0)
    assert got.bias == ref.bias
    for name in ("alpha", "edf", "ci_low", "ci_high", "bias_factor"):
        a, b = getattr(got, name), getattr(ref, name)
        assert (a is None) == (b is None), name
        if a is not None:
            np.testing.assert_allclose(a, b, rtol=1e-9, atol=0, equal_nan=True, err_msg=name)
    if ref.alpha_estimate is not None:
        np.testing.assert_allclose(got.alpha_estimate, ref.alpha_estimate, rtol=0, atol=1e-9, equal_nan=True)
    assert got.ci_reason == ref.ci_reason
    assert got.confidence == ref.confidence


def simulated_imu_log(seed: int = 11, duration: float = 120.0, rate: float = 50.0):
    """A 6-axis simulated LSM6DSL-like log in memory (gyro_x … accel_z, rad/s and m/s²), one seed
    stream per axis: the small IMU log the output tests analyse."""
    from sigmatau.analysis import log_from_arrays
    from sigmatau.imu import simulate

    streams = np.random.SeedSequence(seed).spawn(6)
    axes = [(g, a) for g in ("gyro", "accel") for a in "xyz"]
    chans = {f"{g}_{a}": simulate(f"lsm6dsl-{g}", duration=duration, rate=rate, rng=np.random.default_rng(s))
             for (g, a), s in zip(axes, streams)}
    units = {k: "rad/s" if k.startswith("gyro") else "m/s^2" for k in chans}
    return log_from_arrays(chans, rate=rate, units=units, name="sim")


def headless_chromium():
    """A headless Chromium driven by selenium, its console and DevTools network events logged.

    Needs Debian's ``chromium`` and ``chromium-driver`` (installed by ``.ci/run``) and
    ``selenium`` (test extra). Skips the test when one is missing, unless the environment
    variable ``SIGMATAU_REQUIRE_BROWSER`` is set (``.ci/run`` sets it): then it fails, so
    their absence cannot hide the check.
    """
    import os
    import shutil

    import pytest

    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    driver_path = shutil.which("chromedriver")
    try:
        from selenium import webdriver
        from selenium.webdriver.chrome.options import Options
        from selenium.webdriver.chrome.service import Service
    except ImportError:
        webdriver = None
    missing = [name for name, ok in (("chromium", chromium), ("chromedriver", driver_path), ("selenium", webdriver))
               if not ok]
    if missing:
        if os.environ.get("SIGMATAU_REQUIRE_BROWSER"):
            pytest.fail(f"browser test required but missing: {', '.join(missing)}")
        pytest.skip(f"missing {', '.join(missing)}")
    opts = Options()
    opts.binary_location = chromium
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                "--disable-background-networking", "--window-size=1300,1000"):
        opts.add_argument(arg)
    # "performance" records the DevTools network events: every request the page makes.
    opts.set_capability("goog:loggingPrefs", {"browser": "ALL", "performance": "ALL"})
    return webdriver.Chrome(service=Service(driver_path), options=opts)
