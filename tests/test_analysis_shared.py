"""The main job shares work between statistics of one channel without changing a digit."""

import numpy as np
import pytest

import sigmatau
from sigmatau.analysis import analyze_log, log_from_arrays
from sigmatau.core.shared import shared_record
from sigmatau.pipeline.analysis import tdev_from_mdev

FIELDS = ("var", "dev", "alpha", "alpha_estimate", "edf", "ci_low", "ci_high", "n", "m", "taus")


def _assert_same(a, b):
    for f in FIELDS:
        np.testing.assert_array_equal(getattr(a, f), getattr(b, f), err_msg=f)
    assert a.ci_reason == b.ci_reason and a.confidence == b.confidence
    assert (a.statistic, a.bias, a.rate, a.data_type, a.n_points) == (b.statistic, b.bias, b.rate, b.data_type,
                                                                        b.n_points)


@pytest.mark.parametrize("alpha", [2, 1, 0, -1, -2])
@pytest.mark.parametrize("data_type", ["freq", "phase"])
def testtdev_from_mdev_is_tdev_bit_for_bit(alpha, data_type, rng):
    y = sigmatau.power_law_noise(6000, alpha=alpha, rng=rng) * 1e-3 + 5.0
    for rate, confidence in ((1.0, sigmatau.ONE_SIGMA), (200.0, 0.95)):
        m = sigmatau.mdev(y, rate=rate, data_type=data_type, confidence=confidence)
        _assert_same(tdev_from_mdev(m), sigmatau.tdev(y, rate=rate, data_type=data_type, confidence=confidence))


def testtdev_from_mdev_declines_what_tdev_would_say_differently():
    y = sigmatau.power_law_noise(2000, alpha=0, rng=4)
    assert tdev_from_mdev(sigmatau.mdev(y, ci=None)) is None
    assert tdev_from_mdev(sigmatau.mdev(y, alpha=0)) is not None  # forced α: edf from α, as tdev(alpha=0)
    _assert_same(tdev_from_mdev(sigmatau.mdev(y, alpha=0)), sigmatau.tdev(y, alpha=0))
    constant = sigmatau.mdev(np.ones(100))  # noise type not identified: tdev gives its own reason
    assert np.isnan(constant.alpha).all() and tdev_from_mdev(constant) is None


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


# --- sigmatau.core.shared: one channel's validation, phase and noise identification, once


def _every_statistic(y, data_type, rate):
    """Every public statistic of y (the main job's path: identified noise type, χ² interval)."""
    return {name: sigmatau.stats.FUNCTIONS[name](y, rate=rate, data_type=data_type, taus="octave")
            for name in sigmatau.stats.FUNCTIONS}


@pytest.mark.slow
@pytest.mark.parametrize("data_type", ["freq", "phase"])
@pytest.mark.parametrize("alpha", [2, 0, -2])
def test_statistics_in_a_shared_scope_are_bit_for_bit_those_outside(alpha, data_type):
    y = sigmatau.power_law_noise(3000, alpha=alpha, rng=alpha + 10) * 3e-3 + 0.25
    alone = _every_statistic(y, data_type, 50.0)
    with shared_record(y):
        together = _every_statistic(y, data_type, 50.0)
        again = _every_statistic(y, data_type, 50.0)  # from the scope's memo
    for name in alone:
        _assert_same(together[name], alone[name])
        _assert_same(again[name], alone[name])


def test_integer_data_beyond_2_53_keep_their_two_forms_apart():
    # remove_offset=True takes these exactly relative to the first value; False rounds each: both
    # forms live in the scope under their own keys.
    y = (np.arange(2000, dtype=np.int64) * 7 + (1 << 60)) + np.random.default_rng(3).integers(-50, 50, 2000)
    alone = {n: sigmatau.stats.FUNCTIONS[n](y, data_type="phase") for n in ("oadev", "mdev", "theoh", "totdev")}
    with shared_record(y):
        for n, res in alone.items():
            _assert_same(sigmatau.stats.FUNCTIONS[n](y, data_type="phase"), res)


def test_the_scope_shares_the_lag1_autocorrelations(monkeypatch):
    from sigmatau.uncertainty import lag1

    calls = []
    real = lag1._lag1_r1
    monkeypatch.setattr(lag1, "_lag1_r1", lambda z, acf="standard", gaps=False: calls.append(z.size) or real(z, acf, gaps))
    y = sigmatau.power_law_noise(20_000, alpha=0, rng=5)
    sigmatau.oadev(y)
    once = len(calls)
    assert once > 0
    calls.clear()
    with shared_record(y):
        for name in ("oadev", "mdev", "totdev", "ohdev"):
            sigmatau.stats.FUNCTIONS[name](y)
    # White FM stops at d = 0 at every factor: the four statistics ask at the same octave factors,
    # so the scope computes each r1 once (without it: four times as many).
    assert len(calls) == once
    calls.clear()
    for name in ("oadev", "mdev", "totdev", "ohdev"):
        sigmatau.stats.FUNCTIONS[name](y)
    assert len(calls) >= 4 * once - 4


def test_the_scope_leaves_the_callers_array_alone_and_hands_out_read_only_copies():
    from sigmatau.core.driver import validated_samples

    y = sigmatau.power_law_noise(1000, alpha=0, rng=2) * 1e-2
    before = y.copy()
    with shared_record(y):
        series, k = validated_samples(y, remove_offset=False)
        assert series is validated_samples(y, remove_offset=True)[0]  # float data: one copy for both
        assert not series.flags.writeable and y.flags.writeable
        with pytest.warns(sigmatau.imu.ImuWarning, match="not resolved"):  # 10 s of white noise: no K
            sigmatau.imu.analyze(y, rate=100.0, unit="rad/s")
        sigmatau.theoh(y, rate=100.0)
    np.testing.assert_array_equal(y, before)
    assert y.flags.writeable
    other, _ = validated_samples(y, remove_offset=False)  # scope closed: a fresh, writeable copy
    assert other is not series and other.flags.writeable


def test_scopes_belong_to_their_thread():
    import threading

    from sigmatau.core.driver import validated_samples

    y = np.linspace(0.0, 1.0, 100)
    seen = {}
    with shared_record(y):
        mine = validated_samples(y, remove_offset=False)[0]
        t = threading.Thread(target=lambda: seen.setdefault("other", validated_samples(y, remove_offset=False)[0]))
        t.start()
        t.join()
        assert validated_samples(y, remove_offset=False)[0] is mine
    assert seen["other"] is not mine and seen["other"].flags.writeable


def test_the_main_job_equals_each_statistic_called_alone():
    from sigmatau.imu import simulate

    gx = simulate("euroc-gyro", duration=300.0, rng=11)
    log = log_from_arrays({"gyro_x": gx}, rate=200.0, units={"gyro_x": "rad/s"})
    ch = analyze_log(log, workers=1).channel("gyro_x")
    model = sigmatau.imu.analyze(gx, rate=200.0, unit="rad/s")
    assert set(ch.results) == {"oadev", "mdev", "tdev", "ohdev", "totdev", "theoh"}
    for name, res in ch.results.items():
        extra = {"method": "fast"} if name == "theoh" else {}
        _assert_same(res, sigmatau.stats.FUNCTIONS[name](gx, rate=200.0, taus="octave", **extra))
    for term in ("N", "B", "K"):
        assert getattr(ch.model, term) == getattr(model, term)


def test_the_scope_never_locks_memory_of_an_array_like_source():
    # An array-like whose __array__ returns its own buffer (a pandas Series does): validation of
    # all-zero float64 data hands that very buffer on; it must stay the caller's, writeable.
    class Channel:
        def __init__(self, a):
            self.a = a

        def __array__(self, dtype=None, copy=None):
            return self.a

    buf = np.zeros(200)
    ch = Channel(buf)
    with shared_record(ch):
        for name in ("oadev", "totdev", "theo1", "hdev"):
            sigmatau.stats.FUNCTIONS[name](ch)
    assert buf.flags.writeable
    buf[0] = 1.0
