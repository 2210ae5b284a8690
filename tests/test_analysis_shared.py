"""The main job shares work between statistics of one channel without changing a digit."""

import numpy as np
import pytest

import sigmatau
from sigmatau.analysis import analyze_log, log_from_arrays
from sigmatau.pipeline.analysis import _tdev_from_mdev

FIELDS = ("var", "dev", "alpha", "alpha_estimate", "edf", "ci_low", "ci_high", "n", "m", "taus")


def _assert_same(a, b):
    for f in FIELDS:
        np.testing.assert_array_equal(getattr(a, f), getattr(b, f), err_msg=f)
    assert a.ci_reason == b.ci_reason and a.confidence == b.confidence
    assert (a.statistic, a.bias, a.rate, a.data_type, a.n_points) == (b.statistic, b.bias, b.rate, b.data_type,
                                                                        b.n_points)


@pytest.mark.parametrize("alpha", [2, 1, 0, -1, -2])
@pytest.mark.parametrize("data_type", ["freq", "phase"])
def test_tdev_from_mdev_is_tdev_bit_for_bit(alpha, data_type, rng):
    y = sigmatau.power_law_noise(6000, alpha=alpha, rng=rng) * 1e-3 + 5.0
    for rate, confidence in ((1.0, sigmatau.ONE_SIGMA), (200.0, 0.95)):
        m = sigmatau.mdev(y, rate=rate, data_type=data_type, confidence=confidence)
        _assert_same(_tdev_from_mdev(m), sigmatau.tdev(y, rate=rate, data_type=data_type, confidence=confidence))


def test_tdev_from_mdev_declines_what_tdev_would_say_differently():
    y = sigmatau.power_law_noise(2000, alpha=0, rng=4)
    assert _tdev_from_mdev(sigmatau.mdev(y, ci=None)) is None
    assert _tdev_from_mdev(sigmatau.mdev(y, alpha=0)) is not None  # forced α: edf from α, as tdev(alpha=0)
    _assert_same(_tdev_from_mdev(sigmatau.mdev(y, alpha=0)), sigmatau.tdev(y, alpha=0))
    constant = sigmatau.mdev(np.ones(100))  # noise type not identified: tdev gives its own reason
    assert np.isnan(constant.alpha).all() and _tdev_from_mdev(constant) is None


def test_the_main_job_reports_the_tdev_of_tdev(rng):
    y = np.column_stack([sigmatau.power_law_noise(20_000, alpha=a, rng=rng) for a in (0, -1)])
    log = log_from_arrays({"gyro_x": y[:, 0], "gyro_y": y[:, 1]}, rate=100.0, units={"gyro": "rad/s"})
    analysis = analyze_log(log, statistics=("mdev", "tdev"), model=False, workers=1)
    for ch, col in zip(analysis.channels, (0, 1)):
        _assert_same(ch.results["tdev"], sigmatau.tdev(y[:, col], rate=100.0))
    alone = analyze_log(log, statistics=("tdev",), model=False, workers=1)  # no MDEV to share: computed
    _assert_same(alone.channels[0].results["tdev"], sigmatau.tdev(y[:, 0], rate=100.0))


def test_the_main_job_uses_fast_theobr_and_says_so():
    y = sigmatau.power_law_noise(200_000, alpha=-1, rng=7)
    log = log_from_arrays({"gyro_x": y}, rate=1000.0, units={"gyro": "rad/s"})
    fast = analyze_log(log, statistics=("theoh",), model=False, workers=1)
    exact = analyze_log(log, statistics=("theoh",), model=False, workers=1, theoh="exact")
    assert fast.settings["theoh"] == "fast" and exact.settings["theoh"] == "exact"
    _assert_same(fast.channels[0].results["theoh"], sigmatau.theoh(y, rate=1000.0, method="fast"))
    _assert_same(exact.channels[0].results["theoh"], sigmatau.theoh(y, rate=1000.0))
    assert "fast theobr on blocks of 4 points" in fast.channels[0].results["theoh"].bias
    with pytest.raises(sigmatau.ParameterError, match="theoh='quick'"):
        analyze_log(log, statistics=("theoh",), model=False, theoh="quick")


def test_cli_theoh_option(tmp_path, capsys):
    from helpers import run_cli

    y = sigmatau.power_law_noise(3000, alpha=0, rng=9)
    log = tmp_path / "clock.txt"
    log.write_text("\n".join(f"{v:.12g}" for v in y) + "\n")
    code, out, err = run_cli(["stats", str(log), "--data-type", "freq", "--rate", "1", "--stat", "theoh",
                              "--csv", str(tmp_path / "t.csv")], capsys)
    assert code == 0, err
    code, out, err = run_cli(["stats", str(log), "--data-type", "freq", "--rate", "1", "--stat", "theoh",
                              "--theoh", "quick"], capsys)
    assert code == 2 and "--theoh" in err
