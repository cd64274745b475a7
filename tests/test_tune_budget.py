"""The budget tuner's greedy choice on hand-made cost models (no GPU)."""
import itertools

import numpy as np
import pytest

from rayvr import Effect
from rayvr.errors import OptionError
from rayvr.tune import CostModel, choose_effects

R, S, F, P = Effect.RASTER, Effect.SHADOWS, Effect.REFLECTIONS, Effect.PATH_TRACED


def model(ms, error, base=2.0, overhead=None, rest=0.0):
    return CostModel(base, ms, error, overhead or {}, rest)


def maximal(model_, result, budget, levels=tuple(Effect)):
    """No single further upgrade both fits and lowers the error (the greedy stops only then)."""
    for m, e in result.assignment.items():
        for new in levels:
            if new > e:
                trial = {**result.assignment, m: new}
                if model_.predict_ms(trial) <= budget and model_.error[m][new] < model_.error[m][e]:
                    return False
    return True


def test_prefers_the_larger_error_reduction_per_ms():
    m = model({"A": {R: 0, S: 4.0}, "B": {R: 0, S: 1.0}},
              {"A": {R: 1.0, S: 0.2}, "B": {R: 1.0, S: 0.7}})   # A: 0.2/ms, B: 0.3/ms
    out = choose_effects(m, budget_ms=3.5, levels=[R, S])
    assert out.assignment == {"A": R, "B": S}
    assert out.predicted_ms == pytest.approx(3.0) and out.fits
    assert out.predicted_error == pytest.approx(1.7)
    out = choose_effects(m, budget_ms=7.0, levels=[R, S])      # room for both, B still first
    assert out.assignment == {"A": S, "B": S}
    assert [s.material for s in out.steps] == ["B", "A"]


def test_jumps_levels_when_the_higher_level_pays_off_better():
    m = model({"A": {R: 0, S: 1.0, F: 2.0, P: 3.0}},
              {"A": {R: 1.0, S: 0.99, F: 0.98, P: 0.1}})
    out = choose_effects(m, budget_ms=10.0)
    assert out.assignment == {"A": P}
    assert [(s.old, s.new) for s in out.steps] == [(R, P)]


def test_all_raster_over_budget_degrades_gracefully():
    m = model({"A": {R: 0, S: 1.0}}, {"A": {R: 1.0, S: 0.5}}, base=20.0)
    out = choose_effects(m, budget_ms=11.1)
    assert out.assignment == {"A": R}
    assert not out.fits and out.predicted_ms == pytest.approx(20.0)
    assert "exceeds the 11.1 ms budget" in out.notes[0]
    assert "does NOT fit" in out.table()


def test_level_overhead_is_paid_once_and_counted_in_the_budget():
    m = model({"A": {R: 0, S: 1.0}, "B": {R: 0, S: 1.0}},
              {"A": {R: 1.0, S: 0.0}, "B": {R: 1.0, S: 0.0}}, base=1.0, overhead={S: 2.0})
    assert m.predict_ms({"A": S, "B": S}) == pytest.approx(5.0)   # 1 + 2 (once) + 1 + 1
    assert choose_effects(m, budget_ms=3.9).assignment == {"A": R, "B": R}   # 1 + 2 + 1 = 4 > 3.9
    out = choose_effects(m, budget_ms=4.0)
    assert sorted(out.assignment.values()) == [R, S] and out.predicted_ms == pytest.approx(4.0)


def test_no_upgrade_without_error_reduction_and_free_upgrades_first():
    m = model({"Hidden": {R: 0, S: 0.0}, "Worse": {R: 0, S: 0.5}, "Free": {R: 0, S: 0.0}},
              {"Hidden": {R: 0.0, S: 0.0}, "Worse": {R: 0.1, S: 0.2}, "Free": {R: 0.3, S: 0.1}})
    out = choose_effects(m, budget_ms=100.0, levels=[R, S])
    assert out.assignment == {"Hidden": R, "Worse": R, "Free": S}


def test_levels_and_fixed_are_respected():
    m = model({"A": {R: 0, S: 1, F: 2, P: 3}, "B": {R: 0, S: 1, F: 2, P: 3}},
              {"A": {R: 4, S: 3, F: 2, P: 1}, "B": {R: 4, S: 3, F: 2, P: 1}})
    out = choose_effects(m, budget_ms=100.0, levels=[R, S, F], fixed={"B": S})
    assert out.assignment == {"A": F, "B": S}
    with pytest.raises(OptionError, match="no material 'C'"):
        choose_effects(m, fixed={"C": S})
    with pytest.raises(OptionError, match="budget_ms"):
        choose_effects(m, budget_ms=0)


@pytest.mark.parametrize("seed", range(25))
def test_random_models_fit_and_come_close_to_the_exhaustive_optimum(seed):
    rng = np.random.default_rng(seed)
    names = [f"M{i}" for i in range(5)]
    ms = {n: dict(zip(Effect, np.cumsum([0, *rng.uniform(0.1, 3.0, 3)]))) for n in names}
    err = {n: dict(zip(Effect, rng.uniform(0, 1, 4))) for n in names}
    base = float(rng.uniform(0.5, 3.0))
    m = model(ms, err, base=base, overhead={S: 0.3, F: 0.5, P: 0.8})
    budget = base + float(rng.uniform(0.5, 12.0))
    out = choose_effects(m, budget_ms=budget)
    assert out.fits and out.predicted_ms <= budget + 1e-9
    assert out.predicted_ms == pytest.approx(m.predict_ms(out.assignment))
    assert out.predicted_error == pytest.approx(m.predict_error(out.assignment))
    assert maximal(m, out, budget)
    # the exhaustive optimum over all 4^5 assignments is the oracle: greedy keeps most of its gain
    combos = [dict(zip(names, c)) for c in itertools.product(Effect, repeat=len(names))]
    best = min(m.predict_error(a) for a in combos if m.predict_ms(a) <= budget)
    start = m.predict_error({n: R for n in names})
    assert start - out.predicted_error >= 0.8 * (start - best) - 1e-9


def test_as_dict_round_trips_names():
    m = model({"A": {R: 0, S: 1.0}}, {"A": {R: 1.0, S: 0.5}})
    d = choose_effects(m, 5.0).as_dict()
    assert d["assignment"] == {"A": "SHADOWS"} and d["steps"][0]["to"] == "SHADOWS"
    assert d["model"]["ms"]["A"]["SHADOWS"] == 1.0


def test_choose_among_option_sets_takes_the_least_error_that_fits():
    from rayvr.tune.budget import choose_among

    plain = model({"A": {R: 0, S: 4.0}}, {"A": {R: 1.0, S: 0.5}})
    gi = model({"A": {R: 0, S: 4.0}}, {"A": {R: 0.3, S: 0.2}}, base=3.0)   # lower error everywhere, 1 ms more
    a, b = choose_effects(plain, 10.0), choose_effects(gi, 10.0)
    a.options, b.options = {}, {"gi": "probes"}
    best = choose_among([a, b])
    assert best is b and best.predicted_error == pytest.approx(0.2) and best.assignment == {"A": S}
    assert "gi=probes: predicted 7 ms" in best.notes[-1] and "the graph's defaults: predicted 6 ms" in best.notes[-1]
    assert "graph options: gi=probes" in best.table()
    assert best.as_dict()["options"] == {"gi": "probes"}
    # at 3.5 ms GI's base alone leaves no room for SHADOWS: its RASTER (0.3) still beats plain RASTER (1.0)
    a, b = choose_effects(plain, 3.5), choose_effects(gi, 3.5)
    a.options, b.options = {}, {"gi": "probes"}
    assert choose_among([a, b]) is b and b.assignment == {"A": R}
    # nothing fits: the fastest
    a, b = choose_effects(plain, 1.0), choose_effects(gi, 1.0)
    assert not a.fits and not b.fits and choose_among([a, b]) is a
    with pytest.raises(OptionError, match="no choices"):
        choose_among([])


def test_back_off_replaces_a_choice_that_measures_over_the_budget():
    """The GPU runs 30% slower than the model says: the first choice (A and B SHADOWS, predicted
    5.0 of a 6.0 ms budget) measures 6.5; at 6.0 x 6.0 / 6.5 ms the model still offers both, so the
    ask shrinks by 10% more and the next choice keeps one upgrade: 4.55 ms. Within the budget at
    once, the first choice stands; with nothing cheaper, the overrun stays noted."""
    from rayvr.tune.budget import back_off

    m = model({"A": {R: 0, S: 1.5}, "B": {R: 0, S: 1.5}}, {"A": {R: 1.0, S: 0.1}, "B": {R: 1.0, S: 0.2}})
    measured = []

    def measure(choice):
        ms = 1.3 * choice.model.predict_ms(choice.assignment)
        measured.append(dict(choice.assignment))
        choice.record_measurement(ms, choice.model.predict_error(choice.assignment), "fake")
        return ms

    first = choose_effects(m, 6.0)
    assert first.assignment == {"A": S, "B": S} and first.predicted_ms == pytest.approx(5.0)
    out = back_off(first, lambda ask: choose_effects(m, ask), measure, 6.0)
    assert measured == [{"A": S, "B": S}, {"A": S, "B": R}]
    assert out.assignment == {"A": S, "B": R} and out.measured_ms == pytest.approx(4.55)
    assert out.budget_ms == 6.0 and not any("over the budget" in n for n in out.notes)
    assert "backed off from a choice predicted 5 ms that measured 6.5" in out.notes[-1]

    measured.clear()
    roomy = choose_effects(m, 10.0)
    assert back_off(roomy, lambda ask: choose_effects(m, ask), measure, 10.0) is roomy and len(measured) == 1

    # nothing cheaper than all RASTER: one measurement more at most, and the overrun stays noted
    slow = model({"A": {R: 0, S: 1.5}}, {"A": {R: 1.0, S: 0.1}}, base=5.0)
    measured.clear()
    out = back_off(choose_effects(slow, 5.2), lambda ask: choose_effects(slow, ask), measure, 5.2)
    assert out.assignment == {"A": R} and len(measured) == 1 and "over the budget" in out.notes[-1]


def test_spend_budget_raises_the_knob_with_the_most_error_per_ms_while_it_fits():
    from rayvr.tune.budget import Knob, spend_budget

    m = model({"A": {R: 0, S: 1.0}}, {"A": {R: 1.0, S: 0.5}})
    result = choose_effects(m, budget_ms=11.1, levels=[R, S])
    result.record_measurement(3.0, 0.5, "timer")
    knobs = (Knob("light_samples", (1, 2, 4, 8)), Knob("spp", (1, 2, 4), lambda r: False),
             Knob("probes", ("coarse", "fine"), lambda r: True))
    # light samples: each doubling +2 ms, error x0.7; finer probes: +6 ms, error -0.05
    calls = []

    def measure(assignment, options):
        calls.append(dict(options))
        ls = options.get("light_samples", 1)
        fine = options.get("probes") == "fine"
        steps = {1: 0, 2: 1, 4: 2, 8: 3}[ls]
        return 3.0 + 2.0 * steps + 6.0 * fine, 0.5 * 0.7 ** steps - 0.05 * fine

    out = spend_budget(result, measure, 11.1, knobs, base_options={"gi": "probes"})
    # 1 -> 2 -> 4 light samples (0.15/2 ms, then 0.105/2 ms beat the probes' 0.05/6 ms); at 4 the
    # frame is 7 ms: 8 samples (9 ms, -0.074) still beat fine probes (13 ms: over the budget)
    assert out.options == {"light_samples": 8}
    assert out.measured_ms == pytest.approx(9.0) and out.measured_error == pytest.approx(0.5 * 0.7 ** 3)
    assert all(c["gi"] == "probes" for c in calls) and not any("spp" in c for c in calls)
    assert "light_samples 8" in out.notes[-1]
    # a choice over its budget, or one whose raises do not lower the error, stays as it was
    flat = choose_effects(m, budget_ms=11.1, levels=[R, S])
    flat.record_measurement(3.0, 0.5, "timer")
    assert spend_budget(flat, lambda a, o: (4.0, 0.499), 11.1, knobs).options == {}
    with pytest.raises(OptionError, match="measure the choice first"):
        spend_budget(choose_effects(m, budget_ms=11.1), measure, 11.1, knobs)
