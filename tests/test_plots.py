"""Figures (sigmatau.plots): built from real computed results, saved in every format, checked artist by artist."""

from __future__ import annotations

import base64
import subprocess
import sys
import warnings
import xml.etree.ElementTree as ET
from dataclasses import replace

import numpy as np
import pytest

pytest.importorskip("matplotlib")

import sigmatau
from sigmatau import imu, plots
from sigmatau.errors import DataError, ParameterError

RATE = 100.0
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def gyro():
    """Three simulated LSM6DSL-like gyro axes (20 min at 100 Hz) with B and K, their curves and models.

    K is large enough for its +½ region to appear within the record on this seed, B small enough to
    show a flat stretch first, so the figure has resolved, read-off and unresolved terms.
    """
    b = float(sigmatau.units.convert(6.0, "deg/h", "rad/s"))
    k = float(sigmatau.units.convert(150.0, "deg/h/sqrt(h)", "rad/s^2/sqrt(Hz)"))
    chans = []
    for i, axis in enumerate("xyz"):
        y = imu.simulate("lsm6dsl-gyro", duration=1200.0, rate=RATE, B=b, K=k, rng=100 + i)
        res = {s: getattr(sigmatau, s)(y, rate=RATE) for s in ("oadev", "mdev", "ohdev", "totdev", "tdev")}
        # TheoH costs O(N·m): on 10 Hz block means it stays fast and still reaches the longest τ.
        res["theoh"] = sigmatau.theoh(y.reshape(-1, 10).mean(axis=1), rate=RATE / 10)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", imu.ImuWarning)
            model = imu.analyze(res["oadev"], unit="rad/s")
        chans.append(plots.ChannelCurves(f"gyro {axis}", "rad/s", res, model))
        if i == 0:
            samples = y
    return chans, samples


@pytest.fixture(scope="module")
def group_figure(gyro):
    chans, _ = gyro
    return plots.sigma_tau_figure(chans, title="LSM6DSL gyro", datasheet=imu.PRESETS["lsm6dsl-gyro"])


def _labels(fig):
    out = []
    for leg in [*fig.legends, *(ax.get_legend() for ax in fig.axes)]:
        if leg is not None:
            out += [t.get_text() for t in leg.get_texts()]
    return out


def _gids(fig):
    return {a.get_gid() for ax in fig.axes for a in [*ax.lines, *ax.collections] if a.get_gid()}


# ------------------------------------------------------------------ σ–τ figure


def test_sigma_tau_figure_artists(gyro, group_figure):
    chans, _ = gyro
    fig = group_figure
    main = [ax for ax in fig.axes if ax.get_xscale() == "log" and ax.get_ylabel() != "x(τ) [rad/s·s]"]
    titles = sorted(ax.get_title() for ax in fig.axes if ax.get_title())
    assert titles == ["gyro x", "gyro y", "gyro z"]
    assert len({ax.get_title() for ax in main if ax.get_title()}) == 3
    labels = _labels(fig)
    assert any(lab.startswith("N (ARW)") and "°/√h" in lab for lab in labels)
    assert any(lab.startswith("datasheet N") for lab in labels)
    for stat in ("OADEV", "MDEV", "OHDEV", "TOTDEV", "TheoH", "TDEV (right axis)"):
        assert stat in labels
    gids = _gids(fig)
    for ch in chans:
        assert f"band-oadev-{ch.name}" in gids and f"curve-oadev-{ch.name}" in gids
        assert f"model-{ch.name}" in gids
        assert f"datasheet-N-{ch.name}" in gids
        assert f"readoff-N-{ch.name}" in gids and f"region-N-{ch.name}" in gids
        for term in ch.model.resolved:
            assert f"term-{term}-{ch.name}" in gids
        for term in set("QNBKR") - set(ch.model.resolved):
            assert f"bound-{term}-{ch.name}" in gids
    # The datasheet line is N/√τ with the preset's N (SI, same unit as the panel).
    line = next(ln for ax in fig.axes for ln in ax.lines if ln.get_gid() == "datasheet-N-gyro x")
    t, s = (np.asarray(v) for v in line.get_data())
    np.testing.assert_allclose(s * np.sqrt(t), imu.PRESETS["lsm6dsl-gyro"].N, rtol=1e-12)
    # The N read-off point is drawn at τ = 1 s at the read-off value.
    pt = next(ln for ax in fig.axes for ln in ax.lines if ln.get_gid() == "readoff-N-gyro x")
    assert pt.get_xdata()[0] == 1.0
    np.testing.assert_allclose(pt.get_ydata()[0], chans[0].model.readoff["N"].value, rtol=1e-12)


def test_model_term_lines_match_model(gyro):
    chans, _ = gyro
    ch = chans[0]
    fig = plots.sigma_tau_figure([ch])
    line = next(ln for ax in fig.axes for ln in ax.lines if ln.get_gid() == "model-gyro x")
    t, s = (np.asarray(v) for v in line.get_data())
    np.testing.assert_allclose(s, ch.model.deviation(t), rtol=1e-12)
    assert len([ax for ax in fig.axes if ax.get_visible() and ax.get_title()]) == 1


def test_units_and_datasheet_conversion(gyro):
    """A panel in deg/s gets the model and a SI preset converted; mapping and (value, unit) forms agree."""
    chans, _ = gyro
    ch = chans[0]
    deg = {k: replace(r, dev=np.degrees(r.dev), ci_low=np.degrees(r.ci_low), ci_high=np.degrees(r.ci_high))
           for k, r in ch.results.items() if k != "tdev"}
    fig = plots.sigma_tau_figure([plots.ChannelCurves("gyro x", "deg/s", deg, ch.model)],
                                 datasheet={"N": (4.0, "mdps/sqrt(Hz)")})
    line = next(ln for ax in fig.axes for ln in ax.lines if ln.get_gid() == "datasheet-N-gyro x")
    t, s = (np.asarray(v) for v in line.get_data())
    np.testing.assert_allclose(s * np.sqrt(t), 4e-3, rtol=1e-12)
    model = next(ln for ax in fig.axes for ln in ax.lines if ln.get_gid() == "model-gyro x")
    t, s = (np.asarray(v) for v in model.get_data())
    np.testing.assert_allclose(s, np.degrees(ch.model.deviation(t)), rtol=1e-12)
    assert any(ax.get_ylabel() == "σ(τ) [°/s]" for ax in fig.axes)
    with pytest.raises(ParameterError, match="gyro preset"):
        plots.sigma_tau_figure([("acc", "m/s^2", {"oadev": ch.results["oadev"]})],
                               datasheet=imu.PRESETS["lsm6dsl-gyro"])
    with pytest.raises(ParameterError, match="datasheet term"):
        plots.sigma_tau_figure([ch], datasheet={"X": 1.0})


def test_statistics_selection_and_tuples(gyro):
    chans, _ = gyro
    ch = chans[1]
    fig = plots.sigma_tau_figure([(ch.name, ch.unit, ch.results)], statistics=["mdev", "oadev"])
    labels = _labels(fig)
    assert "MDEV" in labels and "OADEV" in labels and "TOTDEV" not in labels
    assert "slope-guide-+0.5" in _gids(fig)  # no model: slope guides in a corner
    with pytest.raises(ParameterError, match="statistics"):
        plots.sigma_tau_figure([ch], statistics="oadev")


def test_save_all_formats(group_figure, tmp_path):
    fig = group_figure
    paths = plots.save_figure(fig, tmp_path / "sub" / "sigma_tau", formats=("png", "svg", "pdf"))
    assert [p.name for p in paths] == ["sigma_tau.png", "sigma_tau.svg", "sigma_tau.pdf"]
    png, svg, pdf = (p.read_bytes() for p in paths)
    assert png.startswith(PNG_MAGIC) and 20_000 < len(png) < 400_000
    assert pdf.startswith(b"%PDF")
    root = ET.fromstring(svg)
    assert root.tag.endswith("svg")
    assert b"OADEV" in svg and len(svg) < 400_000  # text kept as text: small and searchable
    with pytest.raises(ParameterError, match="formats"):
        plots.save_figure(fig, tmp_path / "x", formats=("jpg",))


def test_saves_are_deterministic(gyro, tmp_path):
    """Two saves of one figure, and a rebuilt figure, give identical bytes (no dates, fixed SVG ids)."""
    chans, _ = gyro
    fig = plots.sigma_tau_figure(chans[:1], title="x")
    first = [p.read_bytes() for p in plots.save_figure(fig, tmp_path / "a", formats=("svg", "pdf"))]
    again = [p.read_bytes() for p in plots.save_figure(fig, tmp_path / "b", formats=("svg", "pdf"))]
    assert first == again
    rebuilt = plots.sigma_tau_figure(chans[:1], title="x")
    assert plots.figure_to_bytes(rebuilt, "svg") == first[0]
    uri = plots.figure_to_data_uri(rebuilt, "png")
    assert uri.startswith("data:image/png;base64,")
    assert base64.b64decode(uri.split(",", 1)[1]).startswith(PNG_MAGIC)


# ---------------------------------------------------------------- degenerate


def _result(taus, dev, lo=None, hi=None, statistic="oadev"):
    taus = np.asarray(taus, dtype=float)
    return sigmatau.StabilityResult(statistic, taus, np.round(taus * RATE), np.asarray(dev) ** 2,
                                    np.asarray(dev, dtype=float), np.full(taus.size, 10), RATE, "freq", 1000,
                                    ci_low=lo, ci_high=hi)


def test_degenerate_inputs(tmp_path):
    nan = np.full(4, np.nan)
    cases = [
        ("all-NaN bounds", {"oadev": _result([0.01, 0.02, 0.04, 0.08], [4e-3, 3e-3, 2e-3, 1e-3], nan, nan)}),
        ("single tau", {"oadev": _result([1.0], [1e-3], [0.9e-3], [1.1e-3])}),
        ("constant data", {"oadev": _result([0.01, 0.02], [0.0, 0.0]),
                           "mdev": _result([0.01, 0.02], [0.0, 0.0], statistic="mdev")}),
        ("some zeros", {"oadev": _result([0.01, 0.02, 0.04], [1e-3, 0.0, np.nan])}),
        ("no results", {}),
    ]
    fig = plots.sigma_tau_figure([(name, "rad/s", res) for name, res in cases])
    out = plots.save_figure(fig, tmp_path / "degenerate", formats=("png",))
    assert out[0].read_bytes().startswith(PNG_MAGIC)
    assert sorted(ax.get_title() for ax in fig.axes if ax.get_visible()) == sorted(name for name, _ in cases)
    fig = plots.sigma_tau_figure([("constant", "rad/s", cases[2][1])])
    texts = [t.get_text() for ax in fig.axes for t in ax.texts]
    assert any("no positive deviation" in t for t in texts)
    assert "zero values not shown on the log axis" in " ".join(fig._suptitle.get_text().split())
    with pytest.raises(ParameterError, match="empty"):
        plots.sigma_tau_figure([])
    with pytest.raises(ParameterError, match="channels\\[0\\]"):
        plots.sigma_tau_figure([42])


def test_constant_record_end_to_end():
    y = np.full(2000, 0.5)
    res = {"oadev": sigmatau.oadev(y, rate=RATE, ci=None)}
    fig = plots.sigma_tau_figure([("stuck", "rad/s", res)])
    assert fig.axes
    sig = plots.signal_figure(y, rate=RATE, name="stuck", unit="rad/s")
    assert any("no PSD" in t.get_text() for ax in sig.axes for t in ax.texts)
    assert "n/a" in sig.axes[2].get_title()


# ------------------------------------------------------------------ signal figure


def test_signal_figure(gyro, tmp_path):
    chans, y = gyro
    fig = plots.signal_figure(y, rate=RATE, name="gyro x", unit="rad/s", model=chans[0].model, max_points=5000)
    ax_t, ax_f, ax_l = fig.axes
    assert ax_t.get_title().startswith("(a)") and ax_f.get_title().startswith("(b)")
    assert ax_l.get_title().startswith("(c) lag plot, r₁ = ")
    gids = _gids(fig)
    assert {"envelope", "series", "psd", "lag", "psd-N"} <= gids
    assert ax_t.get_xlabel() == "time [min]"
    assert ax_f.get_xscale() == "log" and ax_l.get_aspect() == 1.0
    lag = next(c for c in ax_l.collections if c.get_gid() == "lag")
    assert len(lag.get_offsets()) <= 5000
    # The one-sided white level 2N² sits on the measured PSD above the flicker corner.
    psd = next(ln for ln in ax_f.lines if ln.get_gid() == "psd")
    f, p = (np.asarray(v) for v in psd.get_data())
    white = 2 * chans[0].model.N.value ** 2
    assert abs(np.median(p[f > 5.0]) / white - 1) < 0.05
    paths = plots.save_figure(fig, tmp_path / "signal", formats=("png", "svg"))
    assert paths[0].read_bytes().startswith(PNG_MAGIC)
    ET.fromstring(paths[1].read_bytes())
    assert paths[1].stat().st_size < 600_000  # lag scatter rasterised, PSD log-binned


def test_signal_figure_long_record_is_fast():
    import time

    y = np.random.default_rng(5).normal(size=1_000_000).astype(np.float32)
    t0 = time.perf_counter()
    fig = plots.signal_figure(y, rate=1000.0, name="z", unit="m/s^2")
    png = plots.figure_to_bytes(fig, "png")
    assert time.perf_counter() - t0 < 10.0
    assert png.startswith(PNG_MAGIC)
    psd = next(ln for ln in fig.axes[1].lines if ln.get_gid() == "psd")
    assert len(psd.get_xdata()) < 400
    np.testing.assert_allclose(np.median(psd.get_ydata()), 2.0 / 1000.0, rtol=0.05)  # σ² = 1 over 500 Hz


def test_signal_figure_validation():
    with pytest.raises(DataError):
        plots.signal_figure([1.0, np.nan], rate=1.0, name="a", unit="g")
    with pytest.raises(DataError):
        plots.signal_figure(np.zeros((3, 3)), rate=1.0, name="a", unit="g")
    with pytest.raises(ParameterError):
        plots.signal_figure(np.zeros(10), rate=0.0, name="a", unit="g")
    with pytest.raises(ParameterError):
        plots.signal_figure(np.zeros(10), rate=1.0, name="a", unit="g", max_points=3)
    y = np.random.default_rng(1).normal(size=300)
    y[[5, 50]] = np.nan
    fig = plots.signal_figure(y, rate=10.0, name="gappy", unit="")
    assert fig.axes[0].get_xlabel() == "time [s]"


# ---------------------------------------------------------------------- layering


def test_layering_and_missing_matplotlib():
    """``import sigmatau`` does not load matplotlib; without it a figure raises an error naming the extra."""
    code = (
        "import sys, sigmatau\n"
        "assert 'matplotlib' not in sys.modules, 'import sigmatau loaded matplotlib'\n"
        "sys.modules['matplotlib'] = None\n"
        "from sigmatau import plots\n"
        "from sigmatau.io import MissingDependencyError\n"
        "try:\n"
        "    plots.signal_figure([1.0, 2.0, 3.0, 4.0], rate=1.0, name='a', unit='g')\n"
        "except MissingDependencyError as e:\n"
        "    assert 'sigmatau[plot]' in str(e), e\n"
        "else:\n"
        "    raise SystemExit('no error')\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True)
