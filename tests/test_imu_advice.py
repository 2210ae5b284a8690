"""The stopping rule (:func:`sigmatau.imu.recording_advice`): its predictions against records
that actually ran longer, its sentences, and its argument checks.

Validation. A record of 80 min at 100 Hz is simulated, the model of its first 20 min is
analysed and advised on, and the relative half-width that the advice predicts for 80 min is
compared with the one :func:`~sigmatau.imu.analyze` gives on the whole 80 min, over ``RUNS``
records per configuration (seeds ``SEED + i``, a documented seed as conftest.py allows: the
runs are shared by several tests). The figure tested is the median of predicted/achieved; the
tolerances follow the spread of one ratio (the achieved width is itself an estimate: for B,
σ_c/ĉ with ĉ from one record, geometric sd ≈ 1.3 per ratio, so ≈ 1.1 for a median of 16)
and the known biases stated below. Truths in rad/s units, as in tests/test_imu_coverage.py:
N = 1e-3, B = 2.75e-4 (crossing N at 30 s), K = 4e-5 (crossing B at 63 s: not resolved in
20 min in most records, resolved in 80 min in most).

Measured at commit time on these 16 runs (median predicted/achieved [25–75 %]; the tests
print them): N 1.000 [0.999, 1.002] alone, 1.001 beside B, 0.999 beside B and K; B 1.03
[0.84, 1.57] beside N, 0.90 [0.74, 1.30] when K appears later (0.95 with K assumed); K
(assumed) 1.03 [1.00, 1.46] at 80 min, predicted resolved after 50 min (44.6–51.7), resolved
at 80 min in 14 of 16. With the intervals of kept terms conditional on the selection (issue
11) a K just resolved at 80 min prints a wider interval: predicted as ``ĉ ± zσ_c`` it came out
0.61; the advice now predicts the conditional interval (forecast._h_printed).
"""

from __future__ import annotations

import dataclasses
import functools
import json
import math
import warnings

import numpy as np
import pytest

from sigmatau.errors import ParameterError
from sigmatau.imu import ImuWarning, Parameter, RecordingAdvice, TermAdvice, analyze, recording_advice, simulate
from sigmatau.imu.advice import HORIZON, _format_time, _pct
from sigmatau.imu.forecast import _h, _Plan

RATE = 100.0
SHORT, LONG = 1200.0, 4800.0
RUNS = 16
SEED = 17_000
CONFIGS = {
    "N": {"N": 1e-3},
    "N+B": {"N": 1e-3, "B": 2.75e-4},
    "N+B+K": {"N": 1e-3, "B": 2.75e-4, "K": 4e-5},
}


def _analyze(y: np.ndarray):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ImuWarning)   # unresolved K is warned about; expected here
        return analyze(y, rate=RATE, unit="rad/s", checks=False)


def _width(p: Parameter) -> float:
    return (p.high - p.low) / (2.0 * p.value)


@functools.lru_cache(maxsize=None)
def _runs(config: str) -> tuple:
    """(short model, long model) of ``RUNS`` records of ``LONG`` seconds, the short one their start."""
    out = []
    for i in range(RUNS):
        y = simulate(duration=LONG, rate=RATE, unit="rad/s", rng=SEED + i, **CONFIGS[config])
        out.append((_analyze(y[: int(SHORT * RATE)]), _analyze(y)))
    return tuple(out)


def _ratios(config: str, term: str, **kw) -> np.ndarray:
    """Predicted/achieved relative half-width at ``LONG`` for the runs resolving ``term`` at both lengths."""
    out = []
    for short, long in _runs(config):
        if getattr(short, term).resolved and getattr(long, term).resolved:
            predicted = recording_advice(short, **kw).precision_at(LONG)[term]
            out.append(predicted / _width(getattr(long, term)))
    return np.array(out)


def _report(label: str, r: np.ndarray) -> float:
    q1, med, q3 = np.percentile(r, [25, 50, 75])
    print(f"{label}: median predicted/achieved {med:.3f} [{q1:.3f}, {q3:.3f}], {r.size} runs,"
          f" range {r.min():.3f}–{r.max():.3f}")
    return float(med)


# ----------------------------------------------------------------------------- validation
@pytest.mark.parametrize("config, term, low, high", [
    # N: every EDF ∝ T, the √(T/T') law; the ratio is tight (25–75 % within ±1 %).
    ("N", "N", 0.95, 1.05),
    ("N+B", "N", 0.95, 1.05),
    ("N+B+K", "N", 0.95, 1.05),
    # B between N and the end of the record: faster than √ while its flat bottom lengthens.
    ("N+B", "B", 0.8, 1.3),
])
@pytest.mark.slow
def test_predicted_width_matches_the_longer_record(config, term, low, high):
    """The width predicted from 20 min for 80 min matches the one the 80-min record gives."""
    r = _ratios(config, term)
    assert r.size >= RUNS - 3, r.size
    med = _report(f"{config} {term}", r)
    assert low <= med <= high, med


@pytest.mark.slow
def test_b_narrower_than_achieved_when_k_appears_later():
    """A known limit: a term not yet resolved enters the predicted curve at 0, so B's prediction
    for 80 min is too narrow when K appears in between (K widens B: median 0.90× over these 16
    runs, 0.79× over 40 before the selection-aware intervals). Given K (``assume=``, a datasheet
    figure for instance) every prediction widens, but only to 0.95× (0.84× then): the rest is the
    20-min estimate of B, which holds part of K's share."""
    truth = CONFIGS["N+B+K"]
    plain = _report("N+B+K B, K not assumed", _ratios("N+B+K", "B"))
    assumed = []
    for short, long in _runs("N+B+K"):
        if short.B.resolved and long.B.resolved and not short.K.resolved:
            predicted = recording_advice(short, assume={"K": truth["K"]}).precision_at(LONG)["B"]
            assumed.append(predicted / _width(long.B))
    given = _report("N+B+K B, K assumed", np.array(assumed))
    assert 0.6 <= plain <= 1.0, plain
    assert 0.7 <= given <= 1.2, given
    assert given >= plain


@pytest.mark.slow
def test_k_not_resolved_at_first_then_resolved_as_predicted():
    """N+B+K: K is a bound after 20 min and a value after 80 min in most records. The advice
    says so, with a finite prediction; given the true K it predicts it resolved within the
    80 min (median length; between 20 and 80 min in most runs), and its width at 80 min
    within the tolerance of B's."""
    truth = CONFIGS["N+B+K"]["K"]
    runs = _runs("N+B+K")
    short_bound = [not s.K.resolved for s, _ in runs]
    long_value = [lng.K.resolved for _, lng in runs]
    assert sum(short_bound) >= 0.75 * RUNS and sum(long_value) >= 0.6 * RUNS, (sum(short_bound), sum(long_value))
    detect, ratios = [], []
    for short, long in runs:
        if short.K.resolved:
            continue
        plain = recording_advice(short)["K"]
        assert plain.status == "not resolved" and plain.bound == short.K.high
        assert math.isfinite(plain.detect_time) and math.isfinite(plain.extra_time)
        advice = recording_advice(short, assume={"K": truth})
        detect.append(SHORT + advice["K"].detect_time)
        if long.K.resolved:
            # NaN: the advice did not expect K resolved by 80 min in this run (a median, not a promise)
            ratios.append(advice.precision_at(LONG)["K"] / _width(long.K))
    detect_a, ratios_a = np.array(detect), np.array(ratios)
    print(f"K predicted resolved after {np.median(detect_a) / 60:.3g} min (median;"
          f" {np.percentile(detect_a, 25) / 60:.3g}–{np.percentile(detect_a, 75) / 60:.3g}),"
          f" resolved at 80 min in {sum(long_value)}/{RUNS}")
    assert SHORT < np.median(detect_a) < LONG
    assert np.mean((detect_a > SHORT) & (detect_a < LONG)) >= 0.75
    assert np.isnan(ratios_a).sum() <= 2, ratios_a
    med = _report("N+B+K K (assumed, at 80 min)", ratios_a[np.isfinite(ratios_a)])
    assert 0.75 <= med <= 1.33, med


@pytest.mark.slow
def test_detection_length_is_a_median():
    """At the predicted length about half of the records resolve the term; at 1/1.6 of it
    fewer, at 1.6× more. 30 records per length (binomial sd 9 %): K over B and B over N.
    The 50 % points were calibrated on other seeds (``_Z50`` in sigmatau.imu.advice)."""
    cases = [({"N": 1e-3, "B": 2.75e-4, "K": 4e-5}, "K"), ({"N": 1e-3, "B": 1.2e-4}, "B")]
    for truth, term in cases:
        known = {t: v for t, v in truth.items() if t != term}
        base = _analyze(simulate(duration=SHORT, rate=RATE, unit="rad/s", rng=SEED - 1, **known))
        t50 = SHORT + recording_advice(base, assume={term: truth[term]})[term].detect_time
        fractions = []
        for factor in (1 / 1.6, 1.0, 1.6):
            length = t50 * factor
            hits = sum(getattr(_analyze(simulate(duration=length, rate=RATE, unit="rad/s", rng=SEED + 500 + i,
                                                 **truth)), term).resolved for i in range(30))
            fractions.append(hits / 30)
        print(f"{term}: predicted 50 % at {t50 / 60:.3g} min; resolved at ×1/1.6, ×1, ×1.6: {fractions}")
        assert fractions[0] < fractions[2]
        assert 0.2 <= fractions[1] <= 0.8, fractions
        assert fractions[0] <= 0.55 and fractions[2] >= 0.45, fractions


# ----------------------------------------------------------------------------- the advice itself
@pytest.fixture(scope="module")
def nb_model():
    """N + B after 20 min: N known, B resolved to about ±20 %, K not resolved (the first run's
    short model, made alone: the slow tests' cached runs are not needed for it)."""
    y = simulate(duration=LONG, rate=RATE, unit="rad/s", rng=SEED, **CONFIGS["N+B"])
    return _analyze(y[: int(SHORT * RATE)])


@pytest.mark.slow
def test_statuses_sentences_and_headline(nb_model):
    advice = recording_advice(nb_model, target=0.10)
    assert isinstance(advice, RecordingAdvice)
    assert [t.term for t in advice.terms] == ["Q", "N", "B", "K", "R"]
    assert advice["N"].status == "known" and advice["N"].extra_time == 0.0
    assert advice["B"].status == "resolved" and 0 < advice["B"].extra_time < math.inf
    assert advice["K"].status == "not resolved" and advice["K"].bound == nb_model.K.high
    lines = str(advice).splitlines()
    assert len(lines) == 1 + 5 and lines[0].startswith("after 20 min at 100 Hz")
    assert "rad/s/√Hz: known to ±" in lines[2]
    assert "record ≈" in lines[3] and "more for ±10 %" in lines[3]
    assert lines[4].startswith(f"  K: not yet resolved, K < {nb_model.K.high:.3g} rad/s²/√Hz")
    head = advice.headline()
    assert head.startswith("N known to ±") and "B resolved (±" in head and "not yet resolved: record ≈" in head
    assert "\n" not in head
    assert repr(advice).startswith("RecordingAdvice(20 min, target ±10 %: Q not resolved, N known")


@pytest.mark.slow
def test_predictions_are_consistent(nb_model):
    advice = recording_advice(nb_model)
    b = advice["B"]
    now = advice.precision_at(SHORT)
    assert now["B"] == pytest.approx(b.precision, rel=1e-9) and now["N"] == pytest.approx(advice["N"].precision)
    # The time to the target is where the predicted precision meets it (Brent to 2 % in T).
    assert advice.precision_at(SHORT + b.extra_time)["B"] == pytest.approx(0.10, rel=0.03)
    widths = [advice.precision_at(t)["B"] for t in (SHORT, 2 * SHORT, 4 * SHORT, 16 * SHORT)]
    assert all(a > b_ for a, b_ in zip(widths, widths[1:]))
    # N alone shrinks as √(T/T'): every EDF grows with T.
    assert advice.precision_at(4 * SHORT)["N"] / advice["N"].precision == pytest.approx(0.5, rel=0.03)
    assert advice.extra_time == b.extra_time and not advice.complete
    # A looser target: everything resolved is known, nothing more to record for it.
    loose = recording_advice(nb_model, target=0.9)
    assert loose.complete and loose.extra_time == 0.0 and loose["B"].status == "known"


@pytest.mark.slow
def test_scaling_laws_of_the_expected_widths(nb_model):
    """The asymptotes of the Notes, on the expected curve: N's σ_c/c ∝ T^−½ (every EDF ∝ T); K over
    a flat B ∝ 1/T while its line has not crossed B within the record, back towards T^−½ later."""
    plan = _Plan.of(nb_model, SHORT, {"K": 4e-5})

    def exponent(j: int, t: float) -> float:   # d ln(σ_c/c) / d ln T from t to 2t
        return math.log(plan.rel_sd(plan.samples(2 * t))[j] / plan.rel_sd(plan.samples(t))[j]) / math.log(2.0)

    assert exponent(1, SHORT) == pytest.approx(-0.5, abs=0.03)
    early, late = exponent(3, SHORT), exponent(3, 8 * SHORT)
    print(f"K over B: σ_c/c ∝ T^{early:.2f} from 20 to 40 min, T^{late:.2f} from 160 to 320 min")
    assert early < -0.8 and -0.65 < late < -0.45


def test_confidence_rescales_the_precision(nb_model):
    one_sigma = recording_advice(nb_model)
    wide = recording_advice(nb_model, confidence=0.95)
    assert wide.confidence == 0.95
    # Small widths scale with the normal quantile (1.96 at 95 %); B's is not small.
    assert wide["N"].precision / one_sigma["N"].precision == pytest.approx(1.96, rel=0.02)
    assert wide["B"].precision > one_sigma["B"].precision
    assert wide["B"].extra_time > one_sigma["B"].extra_time


def test_assumed_value_and_unreachable_target(nb_model):
    advice = recording_advice(nb_model, assume={"K": 4e-5})
    k = advice["K"]
    assert k.assumed == 4e-5 and k.bound == nb_model.K.high
    assert "of 4e-05 rad/s²/√Hz (assumed)" in k.sentence()
    tight = recording_advice(nb_model, target=0.001)
    b = tight["B"]
    assert math.isinf(b.extra_time) and not math.isfinite(tight.extra_time)
    assert f"±0.1 % is not reached within {_format_time(HORIZON * SHORT)}" in b.sentence()
    assert "is not reachable within" in tight.headline()
    capped = recording_advice(nb_model, max_duration=1.5 * SHORT)
    assert math.isinf(capped["B"].extra_time) and capped.max_duration == 1.5 * SHORT


def test_to_dict_is_json(nb_model):
    d = recording_advice(nb_model).to_dict()
    text = json.dumps(d, allow_nan=False)
    back = json.loads(text)
    assert back["terms"]["B"]["status"] == "resolved" and back["terms"]["K"]["value"] is None
    assert back["duration_s"] == SHORT and back["headline"].startswith("N known")
    assert set(back["terms"]["N"]) >= {"precision", "extra_time_s", "detect_time_s", "sentence", "unit"}


def test_term_without_bound_and_masked_quantisation(nb_model):
    masked = Parameter("Q", math.nan, 0.0, math.inf, nb_model.Q.unit, False, "fit", nb_model.confidence, "gyro")
    model = dataclasses.replace(nb_model, Q=masked, filter_time=0.004)
    q = recording_advice(model)["Q"]
    assert q.status == "not resolved" and math.isnan(q.detect_time) and math.isnan(q.extra_time)
    assert q.sentence() == ("Q: not resolved, no bound; no prediction possible: quantisation is masked by the"
                            " sensor's low-pass filter")
    assert recording_advice(model).to_dict()["terms"]["Q"]["detect_time_s"] is None


def test_terms_left_out_of_the_model_are_absent():
    y = simulate(duration=600.0, rate=RATE, unit="rad/s", rng=SEED - 2, N=1e-3, B=2.75e-4)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ImuWarning)
        model = analyze(y, rate=RATE, unit="rad/s", checks=False, terms=("N", "B", "K"))
    assert [t.term for t in recording_advice(model).terms] == ["N", "B", "K"]


# ----------------------------------------------------------------------------- formatting
def test_sentences_of_each_case():
    common = dict(unit="rad/s^2/sqrt(Hz)", target=0.1, confidence=0.683, basis="")
    known = TermAdvice("N", "known", 1.0e-3, math.nan, precision=0.0042, assumed=math.nan, detect_time=0.0,
                       extra_time=0.0, **{**common, "unit": "rad/s/sqrt(Hz)"})
    assert known.sentence() == "N = 0.001 rad/s/√Hz: known to ±0.42 % (target ±10 %)"
    wide = TermAdvice("B", "resolved", 2.8e-4, math.nan, precision=0.19, assumed=math.nan, detect_time=0.0,
                      extra_time=2100.0, **{**common, "unit": "rad/s"})
    assert wide.sentence() == "B = 0.00028 rad/s: resolved, ±19 %; record ≈ 35 min more for ±10 %"
    later = TermAdvice("K", "not resolved", math.nan, 3.85e-5, precision=math.nan, assumed=3.85e-5,
                       detect_time=2760.0, extra_time=31000.0, **common)
    assert later.sentence() == ("K: not yet resolved, K < 3.85e-05 rad/s²/√Hz; a K at that bound would be resolved"
                                " after ≈ 46 min more and known to ±10 % after ≈ 8.6 h more"
                                " (a smaller K needs longer)")
    already = dataclasses.replace(later, detect_time=0.0)
    assert "would be resolved already (in about half of such records)" in already.sentence()
    assert already.sentence().endswith("(K is probably smaller)")
    never = dataclasses.replace(later, term="R", detect_time=math.inf, extra_time=math.inf,
                                basis="within 333 h (1000× the record so far)")
    assert never.sentence().endswith("an R at that bound would not be resolved within 333 h"
                                     " (1000× the record so far)")


@pytest.mark.parametrize("seconds, text", [
    (45.0, "45 s"), (89.0, "89 s"), (90.0, "1.5 min"), (2100.0, "35 min"), (5399.0, "90 min"),
    (5400.0, "1.5 h"), (31_000.0, "8.6 h"), (171_000.0, "48 h"), (172_800.0, "2 days"),
    (3.6e7, "417 days"), (math.inf, "never"),
])
def test_durations_are_written_for_people(seconds, text):
    assert _format_time(seconds) == text


def test_percentages_and_half_width():
    assert [_pct(x) for x in (0.0042, 0.042, 0.1, 0.187)] == ["0.42", "4.2", "10", "19"]
    # h(a) is the relative half-width of √c for c·(1 ± a); small a: a/2.
    assert _h(0.01) == pytest.approx(0.005, rel=1e-4)
    assert _h(0.5) == pytest.approx((math.sqrt(1.5) - math.sqrt(0.5)) / 2)
    assert _h(3.0) == pytest.approx(1.0)    # lower end clipped at 0: (√4 − 0)/2


# ----------------------------------------------------------------------------- argument checks
def _one_line(exc: pytest.ExceptionInfo) -> str:
    msg = str(exc.value)
    assert "\n" not in msg and msg
    return msg


@pytest.mark.parametrize("kw, match", [
    ({"duration": 0.0}, "duration=0.0 must be a positive"),
    ({"duration": -5.0}, "duration=-5.0"),
    ({"duration": math.nan}, "duration=nan"),
    ({"duration": True}, "duration=True"),
    ({"target": 0.0}, r"target=0.0 must be in \(0, 1\)"),
    ({"target": 1.0}, "target=1.0"),
    ({"target": -0.1}, "target=-0.1"),
    ({"target": 10}, "target=10"),
    ({"target": "10 %"}, "target='10 %'"),
    ({"confidence": 1.0}, "confidence=1.0"),
    ({"max_duration": 600.0}, "max_duration=600.0 must exceed duration"),
    ({"assume": {"N": 1e-3}}, "N is resolved"),
    ({"assume": {"X": 1.0}}, "'X' is not a term"),
    ({"assume": {"K": -1.0}}, r"assume\['K'\]=-1.0"),
    ({"assume": [("K", 1.0)]}, "must be a mapping"),
])
def test_bad_arguments_raise_one_line(nb_model, kw, match):
    with pytest.raises(ParameterError, match=match) as exc:
        recording_advice(nb_model, **kw)
    _one_line(exc)


def test_a_model_with_no_terms_is_refused(nb_model):
    def unresolved(p: Parameter, method: str) -> Parameter:
        return dataclasses.replace(p, value=math.nan, low=0.0, resolved=False, method=method)

    nothing = dataclasses.replace(nb_model, fit_terms=(),
                                  **{t: unresolved(getattr(nb_model, t), "excluded") for t in "QNBKR"})
    with pytest.raises(ParameterError, match="resolves no term") as exc:
        recording_advice(nothing)
    _one_line(exc)
    bounds_only = dataclasses.replace(nb_model, fit_terms=(),
                                      **{t: unresolved(getattr(nb_model, t), "fit") for t in "QNBKR"})
    with pytest.raises(ParameterError, match="resolves no term"):
        recording_advice(bounds_only)
    with pytest.raises(ParameterError, match="must be a NoiseModel") as exc:
        recording_advice({"N": 1e-3})
    _one_line(exc)


def test_public_names():
    import sigmatau.imu as imu

    for name in ("recording_advice", "RecordingAdvice", "TermAdvice"):
        assert name in imu.__all__ and hasattr(imu, name)
