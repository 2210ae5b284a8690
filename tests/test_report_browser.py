"""report.html opened in headless Chromium: every figure renders and the console stays clean.

Needs Debian's ``chromium`` and ``chromium-driver`` (installed by ``.ci/run``) and
``selenium`` (test extra). Skipped when they are missing, unless the environment
variable ``SIGMATAU_REQUIRE_BROWSER`` is set (``.ci/run`` sets it), in which case
their absence fails the run instead of hiding the check.

The interactive σ–τ charts (:mod:`sigmatau.report.interactive`, the ``interactive``
extra, in the test extra through ``plot``) are checked here too: their data against
the analysis (no browser needed), and in Chromium, with the network switched off,
that they draw, that a legend click hides a statistic or a channel, that a hover
tells the point's numbers, that the wheel zooms, and that the page fetched nothing.
One demo report and one browser serve the whole module.
"""

from __future__ import annotations

import json
import math
import re
import shutil

import numpy as np
import pytest

from helpers import headless_chromium, simulated_imu_log
from sigmatau.cli import main

pytest.importorskip("matplotlib")


def _browser():
    driver = headless_chromium()
    driver.set_script_timeout(30)
    # No network at all: a page that needs a CDN or a web font would fail to draw.
    driver.execute_cdp_cmd("Network.enable", {})
    driver.execute_cdp_cmd("Network.emulateNetworkConditions",
                           {"offline": True, "latency": 0, "downloadThroughput": -1, "uploadThroughput": -1})
    return driver


@pytest.fixture(scope="module")
def driver():
    d = _browser()
    yield d
    d.quit()


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    """The demo's output folder, and its report.html copied alone into another folder (offline:
    the page must not need anything but itself)."""
    tmp = tmp_path_factory.mktemp("demo")
    out = tmp / "demo"
    assert main(["demo", "--out", str(out), "--duration", "900", "--rate", "52", "--quiet"]) == 0
    page_dir = tmp / "alone"
    page_dir.mkdir()
    shutil.copy(out / "report.html", page_dir / "report.html")
    return out, page_dir / "report.html"


def _open(driver, page) -> int:
    """Load ``page``, wait until its charts are drawn (0 without any); the console log is emptied first."""
    driver.get_log("browser")
    driver.get_log("performance")
    driver.get(page.as_uri())
    return driver.execute_async_script(
        "const done = arguments[arguments.length - 1];"
        "if (!window.sigmatauCharts) { done(0); return; }"
        "window.sigmatauCharts.ready.then(() => done(window.sigmatauCharts.views.length));")


def _problems(driver) -> list:
    return [entry for entry in driver.get_log("browser") if entry.get("level") in ("SEVERE", "WARNING")]


def _requests(driver) -> list[str]:
    """The URLs of every request the page made (DevTools' Network.requestWillBeSent events)."""
    urls = []
    for entry in driver.get_log("performance"):
        msg = json.loads(entry["message"])["message"]
        if msg.get("method") == "Network.requestWillBeSent":
            urls.append(msg["params"]["request"]["url"])
    return urls


@pytest.mark.slow
def test_report_renders_in_headless_chromium(demo, driver):
    _, page = demo
    _open(driver, page)
    state = driver.execute_script("return document.readyState")
    images = driver.execute_script(
        "return Array.from(document.images).map(i => ({alt: i.alt, complete: i.complete,"
        " w: i.naturalWidth, h: i.naturalHeight, shown: i.getBoundingClientRect().width}))")
    sections = driver.execute_script("return Array.from(document.querySelectorAll('h2')).map(h => h.id)")
    yaml_shown = driver.execute_script(
        "return Array.from(document.querySelectorAll('pre')).some(p => p.textContent.includes("
        "'gyroscope_noise_density'))")
    logs = driver.get_log("browser")
    assert state == "complete"
    assert len(images) == 8, images  # σ–τ of gyro and accel + a signal figure per channel
    for img in images:
        assert img["complete"] and img["w"] > 400 and img["h"] > 200 and img["shown"] > 100, img
    assert {"overview", "input", "checks", "model", "kalibr", "figures", "tables", "settings"} <= set(sections)
    assert yaml_shown
    errors = [entry for entry in logs if entry.get("level") in ("SEVERE", "WARNING")]
    assert errors == []


# ------------------------------------------------------------------ interactive charts

_VIEW = "window.sigmatauCharts.views[arguments[0]]"
#: The chart's point marks (the ones with a tooltip), as [channel, statistic] of each drawn point.
_POINTS = ("return Array.from(document.querySelectorAll('#ichart-' + arguments[0] + ' path'))"
           ".filter(e => e.__data__ && e.__data__.datum && e.__data__.datum.tau_text !== undefined)"
           ".map(e => [e.__data__.datum.channel, e.__data__.datum.statistic])")


def _click_legend(driver, chart: int, label: str) -> None:
    """Click the legend entry ``label`` of chart ``chart`` (a real click on its SVG text)."""
    for el in driver.find_elements("css selector", f"#ichart-{chart} .role-legend-label text"):
        if el.text == label:
            el.click()
            # Vega updates the drawing asynchronously: wait for it.
            driver.execute_async_script(f"{_VIEW}.runAsync().then(() => arguments[arguments.length - 1]())", chart)
            return
    raise AssertionError(f"no legend entry {label!r}")


def _topmost_point(driver, chart: int, statistic: str):
    """A point of ``statistic`` that nothing covers (where the hover lands on it), and its datum."""
    return driver.execute_script(
        "const pts = Array.from(document.querySelectorAll('#ichart-' + arguments[0] + ' path'))"
        "  .filter(e => e.__data__ && e.__data__.datum && e.__data__.datum.statistic === arguments[1]"
        "          && e.__data__.datum.tau_text !== undefined);"
        "for (const e of pts.reverse()) {"
        "  e.scrollIntoView({block: 'center'});"
        "  const r = e.getBoundingClientRect();"
        "  if (document.elementFromPoint(r.x + r.width / 2, r.y + r.height / 2) === e)"
        "    return [e, e.__data__.datum];"
        "}"
        "return null;", chart, statistic)


def _numbers(text: str) -> list[float]:
    return [float(x) for x in re.findall(r"[-+]?\d+(?:\.\d+)?(?:e[-+]?\d+)?", text)]


@pytest.mark.slow
def test_interactive_charts_draw_hide_tell_and_zoom_offline(demo, driver):
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.actions.wheel_input import ScrollOrigin
    from selenium.webdriver.support.ui import WebDriverWait

    out, page = demo
    assert _open(driver, page) == 2  # gyro and accel, each under its static figure
    boxes = driver.execute_script(
        "return Array.from(document.querySelectorAll('figure .ichart svg'))"
        ".map(s => [s.closest('figure').id, s.getBoundingClientRect().width, s.getBoundingClientRect().height])")
    assert [b[0] for b in boxes] == ["fig-sigma_tau_gyro", "fig-sigma_tau_accel"]
    assert all(w > 600 and h > 300 for _, w, h in boxes), boxes
    points = driver.execute_script(_POINTS, 0)
    # every τ of every statistic of the three gyro axes is a point (results.json has the same)
    results = json.loads((out / "results.json").read_text(encoding="utf-8"))
    gyro = [c for c in results["channels"] if c["group"] == "gyro"]
    assert len(points) == sum(len(s["taus"]) for c in gyro for s in c["statistics"].values())

    # A legend click hides a statistic (its points are gone, the selection store says so), a
    # second one shows it again; the same for a channel.
    _click_legend(driver, 0, "MDEV")
    store = driver.execute_script(f"return {_VIEW}.data('statistics_store').map(t => t.values[0])", 0)
    assert "MDEV" not in store and "OADEV" in store
    assert not any(s == "MDEV" for _, s in driver.execute_script(_POINTS, 0))
    _click_legend(driver, 0, "MDEV")
    _click_legend(driver, 0, "gyro_y")
    shown = driver.execute_script(_POINTS, 0)
    assert {c for c, _ in shown} == {"gyro_x", "gyro_z"} and any(s == "MDEV" for _, s in shown)
    # a click on one legend leaves the other's entries as they are (Vega-Lite's default would not)
    stores = f"const v = {_VIEW}; return ['statistics_store', 'channels_store'].map(n => v.data(n).length)"
    assert driver.execute_script(stores, 0) == [7, 2]
    _click_legend(driver, 0, "gyro_y")
    assert len(driver.execute_script(_POINTS, 0)) == len(points)
    assert driver.execute_script(stores, 0) == [7, 3]

    # The hover tooltip tells the point's τ, σ, interval, noise type and EDF: those of results.json.
    el, datum = _topmost_point(driver, 0, "OADEV")
    ActionChains(driver).move_to_element(el).click().perform()  # a click on a point changes nothing
    tip = WebDriverWait(driver, 5).until(lambda d: d.execute_script(
        "const t = document.getElementById('vg-tooltip-element');"
        "return t && t.classList.contains('visible') && t.innerText.includes(arguments[0]) ? t.innerText : null",
        datum["channel"]))
    assert driver.execute_script(stores, 0) == [7, 3] and len(driver.execute_script(_POINTS, 0)) == len(points)
    stat = next(c for c in gyro if c["name"] == datum["channel"])["statistics"]["oadev"]
    i = stat["taus"].index(datum["tau"])
    lines = dict(re.findall(r"^(.+?)\t?\n(.+)$", tip, flags=re.M))
    assert lines["statistic"] == "OADEV" and lines["channel"] == datum["channel"]
    assert _numbers(lines["τ"])[0] == pytest.approx(stat["taus"][i], rel=1e-3)
    assert _numbers(lines["σ"])[0] == pytest.approx(stat["dev"][i], rel=1e-4) and "rad/s" in lines["σ"]
    assert _numbers(lines["interval [min, max]"]) == pytest.approx([stat["ci_low"][i], stat["ci_high"][i]], rel=1e-4)
    assert f"α = {int(stat['alpha'][i])}" in lines["noise type"]
    assert _numbers(lines["EDF"])[0] == pytest.approx(stat["edf"][i], rel=1e-3)

    # The wheel zooms the log axes (both σ axes and τ), a double-click puts them back.
    domains = f"const v = {_VIEW}; return ['x', 'layer_0_y', 'layer_1_y'].map(s => v.scale(s).domain());"
    before = driver.execute_script(domains, 0)
    svg = driver.find_element("css selector", "#ichart-0 svg")
    ActionChains(driver).scroll_from_origin(ScrollOrigin.from_element(svg, -100, 0), 0, -300).perform()
    zoomed = WebDriverWait(driver, 5).until(
        lambda d: (lambda now: now if now != before else None)(d.execute_script(domains, 0)))
    for (lo0, hi0), (lo1, hi1) in zip(before, zoomed):
        assert lo0 < lo1 < hi1 < hi0  # zoomed in, on every axis
    ActionChains(driver).move_to_element_with_offset(svg, -100, 0).double_click().perform()
    WebDriverWait(driver, 5).until(lambda d: d.execute_script(domains, 0) == before)
    assert len(driver.execute_script(f"return {_VIEW}.data('statistics_store')", 0)) == 7  # legends untouched

    assert _problems(driver) == []
    requests = _requests(driver)
    assert requests and all(u.startswith(("file://", "data:", "blob:")) for u in requests), requests
    fetched = driver.execute_script("return performance.getEntriesByType('resource').map(e => e.name)")
    assert all(u.startswith(("data:", "blob:")) for u in fetched), fetched


HOSTILE_CHANNELS = ["</script><script>window.__pwned = 1</script>", '"><img src=x onerror="window.__pwned = 2">',
                    "it's \"quoted\" & <b>bold</b> \u2028 ü"]


@pytest.mark.slow
def test_hostile_channel_names_are_text_in_the_interactive_chart(tmp_path, driver):
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.support.ui import WebDriverWait

    from sigmatau.analysis import analyze_log, log_from_arrays
    from sigmatau.outputs import write_outputs

    rng = np.random.default_rng(31)
    log = log_from_arrays({n: rng.standard_normal(3000) for n in HOSTILE_CHANNELS}, rate=100,
                          name="</title><script>window.__pwned = 3</script>.csv")
    analysis = analyze_log(log, statistics=["oadev", "tdev"], workers=1, model=False)
    write_outputs(analysis, tmp_path / "o", figures=("png",))
    page = tmp_path / "o" / "report.html"
    assert _open(driver, page) == 1
    assert driver.execute_script("return window.__pwned === undefined")
    assert driver.execute_script("return document.querySelectorAll('script').length") == 3  # spec, library, boot
    assert driver.execute_script(f"return {_VIEW}.scale('shape').domain()", 0) == HOSTILE_CHANNELS
    title = driver.execute_script("return document.querySelector('#ichart-0 .role-title-text').textContent")
    assert title == "other: " + ", ".join(HOSTILE_CHANNELS)
    el, datum = _topmost_point(driver, 0, "OADEV")
    ActionChains(driver).move_to_element(el).perform()
    tip = WebDriverWait(driver, 5).until(lambda d: d.execute_script(
        "const t = document.getElementById('vg-tooltip-element');"
        "return t && t.classList.contains('visible') ? [t.innerText, t.querySelectorAll('img, b, script').length]"
        " : null"))
    assert datum["channel"].split("\u2028")[0] in tip[0] and tip[1] == 0  # shown as text, no element made
    assert driver.execute_script("return window.__pwned === undefined")
    assert _problems(driver) == []


# ------------------------------------------------------------------- chart data, no browser


@pytest.fixture(scope="module")
def imu_analysis():
    """A 6-axis simulated log (2 min at 50 Hz, seed 11): OADEV, MDEV, TDEV and the noise model."""
    from sigmatau.analysis import analyze_log

    log = simulated_imu_log()
    return analyze_log(log, statistics=["oadev", "mdev", "tdev"], workers=1)


def _positive(values) -> list:
    return [float(v) if math.isfinite(v) and v > 0 else None for v in np.asarray(values, dtype=float)]


def test_chart_data_are_the_analysis_values(imu_analysis):
    from sigmatau.report.interactive import MODEL_LABEL, chart_spec, statistic_label

    gyro = imu_analysis.groups()["gyro"]
    spec = chart_spec(gyro, title="gyro")
    json.dumps(spec, allow_nan=False)  # strict JSON
    records = spec["datasets"]["left"] + spec["datasets"]["right"]
    assert len(records) == 9 and {r["statistic"] for r in spec["datasets"]["right"]} == {"TDEV (right axis)"}
    for ch in gyro:
        for stat, res in ch.results.items():
            rec = next(r for r in records if r["channel"] == ch.name and r["statistic"] == statistic_label(stat))
            assert rec["tau"] == res.taus.tolist()  # exactly: the JSON floats are the result's
            assert rec["dev"] == _positive(res.dev)
            assert rec["low"] == _positive(res.ci_low) and rec["high"] == _positive(res.ci_high)
            assert rec["edf"] == _positive(res.edf)
            assert rec["alpha"] == [int(a) for a in res.alpha]
            assert all(f"α = {a}" in t for a, t in zip(rec["alpha"], rec["noise"]))
        model = next(m for m in spec["datasets"]["model"] if m["channel"] == ch.name)
        assert model["statistic"] == MODEL_LABEL
        np.testing.assert_allclose(model["dev"], ch.model.deviation(np.array(model["tau"])), rtol=1e-12)
    assert "WFM, α = 0 — white noise (ARW/VRW)" in {t for r in records for t in r["noise"]}
    legend = spec["layer"][0]["layer"][0]["encoding"]["color"]["scale"]["domain"]
    assert legend == ["OADEV", "MDEV", "TDEV (right axis)", MODEL_LABEL]


def test_charts_follow_the_sigma_tau_figures_and_their_caps(imu_analysis):
    from sigmatau.report.interactive import USAGE_NOTE, report_charts

    figures = [{"kind": "sigma-tau", "group": "gyro", "stem": "sigma_tau_gyro"},
               {"kind": "signal", "group": "gyro", "stem": "signal_gyro_x"},
               {"kind": "sigma-tau", "group": "accel", "stem": "sigma_tau_accel"}]
    charts = report_charts(imu_analysis, figures, max_channels=2)
    assert list(charts.fragments) == ["sigma_tau_gyro", "sigma_tau_accel"] and charts.note == USAGE_NOTE
    spec = json.loads(re.search(r'<script type="application/json"[^>]*>(.*?)</script>',
                                charts.fragments["sigma_tau_accel"]).group(1))
    assert [r["channel"] for r in spec["datasets"]["model"]] == ["accel_x", "accel_y"]  # the first two
    assert charts.script.count("<script>") == 2 and "vegaEmbed" in charts.script
    assert report_charts(imu_analysis, figures[1:2], max_channels=12).fragments == {}


@pytest.fixture
def without_extra(monkeypatch):
    """The interactive extra (vl-convert-python) not installed."""
    from sigmatau.report import interactive

    interactive._bundle.cache_clear()
    monkeypatch.setitem(__import__("sys").modules, "vl_convert", None)  # import vl_convert -> ImportError
    yield
    monkeypatch.undo()
    interactive._bundle.cache_clear()


@pytest.mark.slow
def test_without_the_extra_the_report_is_static_with_one_line(imu_analysis, tmp_path, without_extra):
    from sigmatau.outputs import write_outputs
    from sigmatau.report.interactive import MISSING_NOTE

    write_outputs(imu_analysis, tmp_path / "o", figures=("png",))
    page = (tmp_path / "o" / "report.html").read_text(encoding="utf-8")
    assert "<script" not in page and page.count('src="data:image/png;base64,') == 8
    assert page.count("sigmatau[interactive]") == 1
    assert MISSING_NOTE.replace('"', "&quot;") in page
