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


@pytest.mark.slow
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


@pytest.mark.slow
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


@pytest.mark.slow
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


# ------------------------------------------------------------------ speed levers keep the figures the same


def test_welch_matches_scipy_and_caps_segments():
    """The fast single-precision Welch is scipy's Welch; day-long records average a fixed number of segments."""
    from scipy.signal import welch

    from sigmatau.report import signalfig

    rng = np.random.default_rng(3)
    for n in (20, 33, 1000, 40_000):
        x = 9.81 + 1e-3 * rng.normal(size=n)  # a large mean: demeaned in double precision first
        f, p, nperseg, used, nseg = signalfig._welch(x, 100.0)
        f0, p0 = welch(x, fs=100.0, window="hann", nperseg=nperseg, noverlap=nperseg - max(1, nperseg // 2),
                       detrend="constant")
        np.testing.assert_allclose(f, f0, rtol=1e-12)
        np.testing.assert_allclose(p[1:], p0[1:], rtol=1e-4)
        assert used == nseg
    cap = signalfig._MAX_WELCH_SEGMENTS
    n = (cap + 40) * 16  # segments of 16: more half-overlapping segments than the cap
    x = rng.normal(size=n)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(signalfig.math, "log2", lambda v: 4.0)  # force 16-point segments
        f, p, nperseg, used, nseg = signalfig._welch(x, 10.0)
    assert nperseg == 16 and used == cap < nseg
    np.testing.assert_allclose(np.median(p[1:-1]), 2.0 / 10.0, rtol=0.2)  # σ² = 1 over 5 Hz, one-sided


def test_lag1_correlation_matches_direct_formula():
    from sigmatau.report import signalfig

    rng = np.random.default_rng(4)
    for x in (np.cumsum(rng.normal(size=5000)) + 1e3, rng.normal(size=3_000_001), np.arange(5.0)):
        a, b = x[:-1] - x[:-1].mean(), x[1:] - x[1:].mean()
        direct = float(a @ b) / np.sqrt(float(a @ a) * float(b @ b))
        assert signalfig._lag1_correlation(x, chunk=1 << 16) == pytest.approx(direct, abs=1e-12)
    assert np.isnan(signalfig._lag1_correlation(np.full(10, 0.5)))


def test_log_labels_same_per_tick_and_per_axis(group_figure):
    """format_ticks (one view lookup per axis) gives the labels of the per-tick call."""
    for ax in group_figure.axes:
        for axis in (ax.xaxis, ax.yaxis):
            for fmt, locs in ((axis.get_major_formatter(), axis.get_majorticklocs()),
                              (axis.get_minor_formatter(), axis.get_minorticklocs())):
                if type(fmt).__name__ == "_Log":
                    assert fmt.format_ticks(locs) == [fmt(v) for v in locs]
    fig = plots.signal_figure(np.random.default_rng(2).normal(size=4000), rate=100.0, name="x", unit="g")
    yaxis = fig.axes[1].yaxis  # PSD of white noise: less than two decades, minor ticks labelled
    labels = yaxis.get_minor_formatter().format_ticks(yaxis.get_minorticklocs())
    assert any("×10" in lab for lab in labels)


def _bbox_inside(inner, outer, tol=1.0):
    return (inner.x0 >= outer.x0 - tol and inner.y0 >= outer.y0 - tol and inner.x1 <= outer.x1 + tol
            and inner.y1 <= outer.y1 + tol)


@pytest.mark.slow
def test_single_layout_pass_is_settled_and_nothing_is_cut_or_overlapping(group_figure):
    """The layout done once is the constrained layout's fixed point; legends and labels fit and do not collide."""
    from matplotlib.layout_engine import ConstrainedLayoutEngine

    fig = group_figure
    renderer = fig.canvas.get_renderer()
    fig.canvas.draw()
    before = [ax.get_position().bounds for ax in fig.axes]
    fig.set_layout_engine(ConstrainedLayoutEngine())
    try:
        fig.get_layout_engine().execute(fig)
        after = [ax.get_position().bounds for ax in fig.axes]
    finally:
        fig.set_layout_engine("none")
        for ax, pos in zip(fig.axes, before):
            ax.set_position(pos)
    np.testing.assert_allclose(after, before, atol=2e-3)
    fig.canvas.draw()
    page = fig.bbox
    legends = [*fig.legends, *(ax.get_legend() for ax in fig.axes if ax.get_legend() is not None)]
    assert len(legends) == 4
    for leg in legends:
        assert _bbox_inside(leg.get_window_extent(renderer), page)
    for ax in fig.axes:
        leg = ax.get_legend()
        if leg is None:
            continue
        xlabel = ax.xaxis.label.get_window_extent(renderer)
        box = leg.get_window_extent(renderer)
        assert box.y1 < xlabel.y0  # the term legend hangs below the τ label
        assert box.y0 > fig.legends[0].get_window_extent(renderer).y1 - 1.0
    for ax in fig.axes:
        if ax.get_title():
            title = ax.title.get_window_extent(renderer)
            assert _bbox_inside(title, page) and title.y0 >= ax.get_window_extent(renderer).y1
    sig = plots.signal_figure(np.random.default_rng(2).normal(size=40_000), rate=100.0, name="x", unit="g")
    sig.canvas.draw()
    for ax in sig.axes:
        assert _bbox_inside(ax.get_tightbbox(sig.canvas.get_renderer()), sig.bbox)


def test_a_prepared_signal_draws_the_same_figure(rng):
    from sigmatau.report import plots
    from sigmatau.report.figbase import figure_to_bytes

    x = rng.standard_normal(40_000) * 1e-3
    prepared = plots.prepare_signal(x, rate=100.0, name="gyro_x")
    assert prepared.x is x and prepared.envelope is not None and prepared.psd is not None
    # PNG: the pixels (SVG ids follow process-wide counters, which other tests advance)
    with_prep = figure_to_bytes(plots.signal_figure(x, rate=100.0, name="gyro_x", unit="rad/s",
                                                    prepared=prepared), "png")
    alone = figure_to_bytes(plots.signal_figure(x, rate=100.0, name="gyro_x", unit="rad/s"), "png")
    assert with_prep == alone
