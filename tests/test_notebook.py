"""Results in a notebook: ``_repr_html_`` (escaped), ``to_pandas()`` (the same numbers) and ``plot()``.

Every value in a frame is compared with the result's own fields; every plotted line with the
curve it draws; every name from a user's file must reach the HTML escaped.
"""

from __future__ import annotations

import html
import sys

import numpy as np
import pytest

pd = pytest.importorskip("pandas")
pytest.importorskip("matplotlib")

import sigmatau  # noqa: E402
from sigmatau import ParameterError  # noqa: E402
from sigmatau.errors import MissingDependencyError  # noqa: E402

HOSTILE = "<script>alert('x')</script>&\"gyro\""


@pytest.fixture(scope="module")
def analysis():
    """A 6-axis simulated log (2 min at 50 Hz, seed 11), one accel channel with a hostile name."""
    from sigmatau.analysis import analyze_log, log_from_arrays
    from sigmatau.imu import simulate

    streams = np.random.SeedSequence(11).spawn(6)
    names = ["gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", HOSTILE]
    groups = ["gyro"] * 3 + ["accel"] * 3
    chans = {n: simulate(f"lsm6dsl-{g}", duration=120, rate=50, rng=np.random.default_rng(s))
             for n, g, s in zip(names, groups, streams)}
    units = {n: "rad/s" if g == "gyro" else "m/s^2" for n, g in zip(names, groups)}
    log = log_from_arrays(chans, rate=50, units=units, groups={"gyro": names[:3], "accel": names[3:]},
                          name="run<1>.csv")
    return analyze_log(log, statistics="oadev,mdev", workers=1)


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    import matplotlib.pyplot as plt

    plt.close("all")


def _result(rng):
    return sigmatau.oadev(rng.standard_normal(4000), rate=10.0, m=[1, 2, 4, 8, 16, 64])


def test_result_frame_holds_the_result(rng):
    r = _result(rng)
    f = r.to_pandas()
    assert list(f.columns) == ["statistic", "tau_s", "m", "n", "alpha", "noise", "dev", "dev_low", "dev_high",
                               "edf", "var"]
    assert len(f) == len(r) and set(f["statistic"]) == {"oadev"}
    for col, field in (("tau_s", "taus"), ("m", "m"), ("n", "n"), ("alpha", "alpha"), ("dev", "dev"),
                       ("dev_low", "ci_low"), ("dev_high", "ci_high"), ("edf", "edf"), ("var", "var")):
        np.testing.assert_array_equal(f[col].to_numpy(dtype=float), np.asarray(getattr(r, field), dtype=float))
    assert set(f["noise"]) <= {"WPM", "FPM", "WFM", "FFM", "RWFM"} and "WFM" in set(f["noise"])
    assert f.attrs == {"rate_hz": 10.0, "data_type": "freq", "n_points": r.n_points, "n_missing": 0,
                       "bias": "none", "confidence": r.confidence}


def test_bare_result_frame_has_nan_intervals(rng):
    r = sigmatau.oadev(rng.standard_normal(500), ci=None)
    f = r.to_pandas()
    assert f["dev_low"].isna().all() and f["alpha"].isna().all() and (f["noise"] == "").all()


def test_result_html_table(rng):
    r = _result(rng)
    text = r._repr_html_()
    assert text.count("<tr>") == len(r) + 1
    assert html.escape(r._title()) in text
    for v in r.dev:
        assert f"{v:.4g}" in text


def test_result_plot_draws_the_curve(rng):
    import matplotlib.pyplot as plt

    r = _result(rng)
    ax = r.plot()
    line = ax.get_lines()[0]
    np.testing.assert_array_equal(line.get_xdata(), r.taus)
    np.testing.assert_array_equal(line.get_ydata(), r.dev)
    assert ax.get_xscale() == "log" and ax.get_yscale() == "log"
    assert len(ax.collections) == 1  # the interval band
    _, given = plt.subplots()
    assert r.plot(ax=given, label="mine", band=False) is given
    assert given.get_lines()[0].get_label() == "mine" and not given.collections


def test_noise_model_frame_and_html(analysis):
    model = analysis.channel("gyro_x").model
    f = model.to_pandas()
    assert list(f["term"]) == ["Q", "N", "B", "K", "R"]
    for _, row in f.iterrows():
        p = getattr(model, row["term"])
        si = p.si()
        np.testing.assert_equal([row["value"], row["low"], row["high"], row["value_si"], row["high_si"]],
                                [p.value, p.low, p.high, si.value, si.high])  # NaN equals NaN here
        assert (row["unit"], row["unit_si"], row["resolved"], row["method"]) == (p.unit, si.unit, p.resolved, p.method)
    assert f.attrs["kind"] == "gyro" and f.attrs["rate_hz"] == 50.0
    text = model._repr_html_()
    assert text.count("<tr>") == 6 and "IMU noise model: gyroscope" in text


def test_noise_model_plot(analysis):
    model = analysis.channel("gyro_x").model
    ax = model.plot()
    labels = [line.get_label() for line in ax.get_lines()]
    assert "model" in labels
    curve = ax.get_lines()[labels.index("model")]
    np.testing.assert_allclose(curve.get_ydata(), model.deviation(curve.get_xdata()), rtol=1e-12)


def test_channel_and_log_frames(analysis):
    ch = analysis.channel(HOSTILE)
    f = ch.to_pandas()
    assert len(f) == sum(len(r) for r in ch.results.values())
    assert set(f["channel"]) == {HOSTILE} and set(f["statistic"]) == {"oadev", "mdev"}
    np.testing.assert_array_equal(f.loc[f["statistic"] == "mdev", "dev"].to_numpy(), ch.results["mdev"].dev)
    whole = analysis.to_pandas()
    assert len(whole) == sum(len(r) for c in analysis.channels for r in c.results.values())
    assert whole.attrs["input"] == "run<1>.csv"
    models = analysis.to_pandas("model")
    assert len(models) == 5 * sum(c.model is not None for c in analysis.channels)
    with pytest.raises(ParameterError, match="'statistics' or 'model'"):
        analysis.to_pandas("everything")


def test_html_escapes_every_name(analysis):
    for text in (analysis._repr_html_(), analysis.channel(HOSTILE)._repr_html_()):
        assert "<script>" not in text
        assert html.escape(HOSTILE) in text or html.escape(HOSTILE, quote=False) in text
    assert "run&lt;1&gt;.csv" in analysis._repr_html_()


def test_channel_and_log_plots(analysis):
    ax = analysis.plot(group="accel", statistic="mdev")
    drawn = [line.get_label() for line in ax.get_lines() if not line.get_label().startswith("_")]
    assert drawn == ["accel_x mdev", "accel_y mdev", f"{HOSTILE} mdev"]
    ax = analysis.channel("gyro_y").plot(statistics=["oadev"])
    assert [line.get_label() for line in ax.get_lines()][:2] == ["gyro_y oadev", "gyro_y model"]
    with pytest.raises(ParameterError, match="were not computed"):
        analysis.channel("gyro_y").plot(statistics=["totdev"])
    with pytest.raises(ParameterError, match="no statistics; groups"):
        analysis.plot(group="clock")


def test_to_pandas_without_pandas_names_the_extra(rng, monkeypatch):
    monkeypatch.setitem(sys.modules, "pandas", None)
    with pytest.raises(MissingDependencyError, match=r"sigmatau\[pandas\]"):
        _result(rng).to_pandas()
