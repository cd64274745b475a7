"""The per-material effect budget tuner: pick each material's effect so the frame fits a GPU budget
(11.1 ms at 90 Hz) with the least image error.

The choice runs on a `CostModel` (no GPU needed, so it is unit-testable):

    frame ms(a)  = base_ms + max(overhead_ms[e] for e used by a) + sum_m ms[m][a[m]]
    error(a)     = rest_error + sum_m error[m][a[m]]

`base_ms` is the all-RASTER frame, `overhead_ms[e]` the passes effect level e brings in whatever
its pixel count (e.g. the compaction pass; shared passes are counted once, hence the max),
`ms[m][e]` the GPU time of material m's pixels at level e (0 for RASTER) and `error[m][e]` their
share of the image error. `rayvr.tune.cost_probe.probe_cost_model` measures one on the GPU and
`rayvr.tune.tuner.tune_effects` runs both; this module needs no GPU.

`choose_effects` is the greedy of the multiple-choice knapsack: start from every material at its
lowest allowed level; repeatedly take the upgrade (one material to any higher level) with the
largest error reduction per added ms among those that keep the predicted frame within the
budget (an upgrade that costs nothing and reduces error goes first); stop when none is left.
Ratio-greedy alone can miss one large upgrade (the 0/1 knapsack counter-example), so it also
runs once starting from the largest single error reduction that fits and keeps the better.
If even the lowest levels exceed the budget it returns them, marked `fits=False`, with a note.

The graph's own options (probe GI, a denoiser) change every material's time and error at once, so
the tuner measures one CostModel per option set and `choose_among` keeps the set whose choice
fits with the least predicted error.
"""
from __future__ import annotations

import dataclasses
import math

from ..errors import OptionError
from ..materials.effect import Effect

FRAME_BUDGET_MS = 11.1   # one frame at 90 Hz, a headset's usual refresh


@dataclasses.dataclass
class CostModel:
    """Predicted GPU ms and image error of an effect assignment (see the module docstring)."""

    base_ms: float
    ms: dict                       # material -> {Effect: ms}
    error: dict                    # material -> {Effect: error share}
    overhead_ms: dict = dataclasses.field(default_factory=dict)   # Effect -> ms
    rest_error: float = 0.0        # error of pixels no material covers (sky)
    pixels: dict = dataclasses.field(default_factory=dict)        # material -> pixel count
    metric: str = "flip"
    method: str = "model"          # how the times were measured

    def __post_init__(self):
        self.ms = {m: {Effect.parse(e): float(v) for e, v in d.items()} for m, d in self.ms.items()}
        self.error = {m: {Effect.parse(e): float(v) for e, v in d.items()} for m, d in self.error.items()}
        self.overhead_ms = {Effect.parse(e): float(v) for e, v in self.overhead_ms.items()}
        if set(self.ms) != set(self.error):
            raise OptionError(f"CostModel: ms and error must name the same materials; ms has {sorted(self.ms)}, "
                              f"error has {sorted(self.error)}")

    @property
    def materials(self) -> list[str]:
        """The material names the model covers."""
        return list(self.ms)

    def levels(self, material: str) -> list[Effect]:
        """The effect levels the model knows for `material` (both ms and error)."""
        return sorted(set(self.ms[material]) & set(self.error[material]))

    def predict_ms(self, assignment: dict) -> float:
        """Predicted GPU ms per frame of {material: effect} (the module docstring's formula)."""
        used = set(assignment.values())
        overhead = max([self.overhead_ms.get(e, 0.0) for e in used] + [0.0])
        return self.base_ms + overhead + sum(self.ms[m][e] for m, e in assignment.items())

    def predict_error(self, assignment: dict) -> float:
        """Predicted image error of {material: effect}: the rest plus each material's share."""
        return self.rest_error + sum(self.error[m][e] for m, e in assignment.items())

    def as_dict(self) -> dict:
        def name(d):
            return {e.name: v for e, v in d.items()}

        return {"base_ms": self.base_ms, "overhead_ms": name(self.overhead_ms), "rest_error": self.rest_error,
                "metric": self.metric, "method": self.method, "pixels": dict(self.pixels),
                "ms": {m: name(d) for m, d in self.ms.items()}, "error": {m: name(d) for m, d in self.error.items()}}


@dataclasses.dataclass
class Upgrade:
    """One greedy step: `material` from `old` to `new`, what it added and what it saved."""

    material: str
    old: Effect
    new: Effect
    added_ms: float
    error_reduction: float
    frame_ms: float               # predicted frame ms after this step

    @property
    def ratio(self) -> float:
        """Error reduction per added ms; inf when the step costs nothing."""
        return math.inf if self.added_ms <= 0 else self.error_reduction / self.added_ms


@dataclasses.dataclass
class TuneResult:
    """The chosen effect per material, its predicted (and, after `tune_effects`, measured) cost."""

    assignment: dict              # material -> Effect
    budget_ms: float
    predicted_ms: float
    predicted_error: float
    fits: bool
    steps: list
    notes: list
    model: CostModel
    measured_ms: float | None = None
    measured_error: float | None = None
    method: str = "model"
    options: dict = dataclasses.field(default_factory=dict)   # the graph options the model was measured with

    def table(self) -> str:
        """Markdown: each material's effect, pixels, predicted ms and error share; then totals."""
        m = self.model
        lines = ["| material | effect | pixels | ms | error |", "|---|---|---|---|---|"]
        for name, effect in self.assignment.items():
            lines.append(f"| {name} | {effect.name} | {m.pixels.get(name, '-')} | {m.ms[name][effect]:.4g} | "
                         f"{m.error[name][effect]:.4g} |")
        lines.append("")
        lines.append(f"budget {self.budget_ms:g} ms: predicted {self.predicted_ms:.4g} ms, {m.metric} "
                     f"{self.predicted_error:.4g}" + ("" if self.fits else " (does NOT fit)"))
        if self.options:
            lines.append("graph options: " + ", ".join(f"{k}={v}" for k, v in sorted(self.options.items())))
        if self.measured_ms is not None:
            lines.append(f"measured {self.measured_ms:.4g} ms ({self.method}), {m.metric} {self.measured_error:.4g}")
        lines += [f"note: {n}" for n in self.notes]
        return "\n".join(lines)

    def record_measurement(self, ms: float, error: float, method: str, budget_option: str = "budget_ms") -> None:
        """Keep the measured ms and error of the assignment; a note when it ran over the budget
        (`budget_option` names the setting to lower in it)."""
        self.measured_ms, self.measured_error, self.method = ms, error, method
        if ms > self.budget_ms:
            self.notes.append(f"measured {ms:.3g} ms is over the budget (predicted {self.predicted_ms:.3g} ms); "
                              f"leave headroom with a lower {budget_option}")

    def __str__(self) -> str:
        return self.table()

    def as_dict(self) -> dict:
        return {"assignment": {k: v.name for k, v in self.assignment.items()}, "budget_ms": self.budget_ms,
                "predicted_ms": self.predicted_ms, "predicted_error": self.predicted_error, "fits": self.fits,
                "measured_ms": self.measured_ms, "measured_error": self.measured_error, "method": self.method,
                "options": dict(self.options), "notes": list(self.notes),
                "steps": [{"material": s.material, "from": s.old.name, "to": s.new.name, "added_ms": s.added_ms,
                           "error_reduction": s.error_reduction, "frame_ms": s.frame_ms} for s in self.steps],
                "model": self.model.as_dict()}


# Choices a measured overrun may replace (back_off): each asks the model for the budget scaled by
# what the last one over-promised.
BACKOFF_TRIES = 2


def back_off(first: TuneResult, choose, measure, budget_ms: float, tries: int = BACKOFF_TRIES) -> TuneResult:
    """`first` (chosen for `budget_ms`) measured, and while the measured frame runs over the budget
    a new choice for a smaller ask, at most `tries` times: the ask shrinks by budget / measured
    (how far the cost model under-predicted), and again by 10% while the model returns the same
    choice. `choose(ask_ms)` -> TuneResult; `measure(result)` -> its measured ms (recording it).
    Returns the first choice measured within the budget, else the last; its `budget_ms` is the
    budget asked for and a note names the choices it replaced."""
    def same(a, b):
        return (a.assignment, a.options) == (b.assignment, b.options)

    result, ask = first, budget_ms
    result.budget_ms = budget_ms
    ms = measure(result)
    replaced = []
    for _ in range(tries):
        if ms <= budget_ms:
            break
        ask *= budget_ms / ms
        nxt = choose(ask)
        while same(nxt, result) and ask > 0.05 * budget_ms:
            ask *= 0.9
            nxt = choose(ask)
        if same(nxt, result):
            break   # nothing cheaper to offer
        replaced.append((result.predicted_ms, ms))
        nxt.budget_ms = budget_ms
        result = nxt
        ms = measure(result)
    if replaced:
        result.notes = [n for n in result.notes if "over the budget" not in n or ms > budget_ms]
        result.notes.append("backed off from " + ", ".join(f"a choice predicted {p:.3g} ms that measured {m:.3g}"
                                                          for p, m in replaced)
                            + f"; this one was chosen for {ask:.3g} ms")
    return result


@dataclasses.dataclass(frozen=True)
class Knob:
    """A quality setting the tuner may raise when a choice leaves time in the budget: graph option
    `name`, its `values` from the cheapest (the graph's default) up, and `applies(result)`, whether
    it can change this choice's image (paths per pixel need a PATH_TRACED material, probe density
    probe GI; None: always, as light samples, which every lit pixel draws)."""

    name: str
    values: tuple
    applies: object = None   # callable(TuneResult) -> bool; None: always

    def level(self, options: dict) -> int:
        """The index of `options`' value of this knob in `values` (0 when not set)."""
        value = options.get(self.name, self.values[0])
        return self.values.index(value) if value in self.values else 0


def _uses(effect):
    return lambda r: any(e >= effect for e in r.assignment.values())


# What a choice may raise with time left, cheapest first. Light samples and paths per pixel scale a
# pass's rays; denser probes and more rays per probe sharpen and steady the indirect light.
KNOBS = (
    Knob("light_samples", (1, 2, 4, 8)),
    Knob("spp", (1, 2, 4, 8), _uses(Effect.PATH_TRACED)),
    Knob("probes", ({"counts": [8, 8, 8], "rays_per_probe": 128}, {"counts": [12, 12, 12], "rays_per_probe": 128},
                    {"counts": [16, 16, 16], "rays_per_probe": 256}),
         lambda r: r.options.get("gi") == "probes"),
)
# A raise must lower the measured error by this fraction to count: less is the judge's noise.
SPEND_MIN_GAIN = 0.02


def spend_budget(result: TuneResult, measure, budget_ms: float, knobs=KNOBS, base_options: dict | None = None,
                 min_gain: float = SPEND_MIN_GAIN, max_steps: int = 8) -> TuneResult:
    """Raise `result`'s quality knobs while its measured frame fits `budget_ms`: each step measures
    every knob one value up (`measure(assignment, options)` -> (ms, error), options being
    `base_options` with the result's and the knob's over them) and takes the one with the largest
    error reduction per added ms among those that fit and lower the error by at least `min_gain`
    of it; it stops when none does. `result` must carry a measurement (record_measurement). Its
    options, measured ms and error follow the steps, and a note lists them."""
    if result.measured_ms is None or result.measured_error is None:
        raise OptionError("spend_budget: measure the choice first (TuneResult.record_measurement)")
    base = dict(base_options or {})
    ms, error = float(result.measured_ms), float(result.measured_error)
    taken, seen = [], {}
    for _ in range(max_steps):
        if ms > budget_ms:
            break
        best = None
        for knob in knobs:
            if knob.applies is not None and not knob.applies(result):
                continue
            level = knob.level(result.options)
            if level + 1 >= len(knob.values):
                continue
            options = {**result.options, knob.name: knob.values[level + 1]}
            key = repr(sorted(options.items()))
            if key not in seen:
                seen[key] = measure(result.assignment, {**base, **options})
            new_ms, new_error = seen[key]
            gain = error - new_error
            if new_ms > budget_ms or gain < min_gain * error:
                continue
            score = gain / max(new_ms - ms, 1e-6)
            if best is None or score > best[0]:
                best = (score, knob, options, new_ms, new_error)
        if best is None:
            break
        _, knob, result.options, new_ms, new_error = best
        taken.append(f"{knob.name} {knob.values[knob.level(result.options)]!r} ({ms:.3g} -> {new_ms:.3g} ms, "
                     f"{result.model.metric} {error:.4g} -> {new_error:.4g})")
        ms, error = new_ms, new_error
    if taken:
        result.measured_ms, result.measured_error = ms, error
        result.notes.append("spent the budget's headroom: " + "; ".join(taken))
    return result


def choose_among(results) -> TuneResult:
    """Of choices made on several CostModels (one per graph option set), the one that fits with the
    least predicted error (ties: the faster); when none fits, the fastest. A note names the others."""
    results = list(results)
    if not results:
        raise OptionError("choose_among: no choices to compare")
    fitting = [r for r in results if r.fits]
    best = (min(fitting, key=lambda r: (r.predicted_error, r.predicted_ms)) if fitting
            else min(results, key=lambda r: r.predicted_ms))
    others = [r for r in results if r is not best]
    if others:
        def name(r):
            return ", ".join(f"{k}={v}" for k, v in sorted(r.options.items())) or "the graph's defaults"

        best.notes.append("graph options chosen among " + "; ".join(
            f"{name(r)}: predicted {r.predicted_ms:.3g} ms, {r.model.metric} {r.predicted_error:.4g}"
            + ("" if r.fits else " (over)") for r in [best] + others))
    return best


def choose_effects(model: CostModel, budget_ms: float = FRAME_BUDGET_MS, levels=tuple(Effect), fixed: dict | None = None) -> TuneResult:
    """The greedy choice of the module docstring. `levels`: the effects it may choose;
    `fixed`: {material: effect} kept as given."""
    if not (isinstance(budget_ms, (int, float)) and budget_ms > 0 and math.isfinite(budget_ms)):
        raise OptionError(f"budget_ms must be a positive number of milliseconds (11.1 at 90 Hz), got {budget_ms!r}")
    allowed = sorted({Effect.parse(e, where="levels") for e in levels})
    if not allowed:
        raise OptionError("levels: allow at least one effect, e.g. levels=[Effect.RASTER, Effect.SHADOWS]")
    fixed = {m: Effect.parse(e, where=f"fixed['{m}']") for m, e in (fixed or {}).items()}
    for m in fixed:
        if m not in model.ms:
            raise OptionError(f"fixed: no material '{m}' in the cost model; materials: {', '.join(model.materials)}")
    options = {}
    for m in model.materials:
        opts = [fixed[m]] if m in fixed else [e for e in allowed if e in model.levels(m)]
        if not opts:
            raise OptionError(f"material '{m}': the cost model has none of the allowed levels "
                              f"{[e.name for e in allowed]} (it has {[e.name for e in model.levels(m)]})")
        options[m] = opts
    lowest = {m: opts[0] for m, opts in options.items()}
    frame = model.predict_ms(lowest)
    notes = []
    if frame > budget_ms:
        notes.append(f"even the cheapest assignment ({frame:.3g} ms) exceeds the {budget_ms:g} ms budget: every "
                     f"material stays at its lowest level; render fewer or smaller views or drop passes")
        current, steps = lowest, []
    else:
        current, steps = _greedy(model, options, lowest, budget_ms, [])
        # Ratio-greedy alone can miss one large upgrade that fits (the knapsack counter-example):
        # also start from the single largest error reduction and keep the better result.
        first = max(_upgrades(model, options, lowest, budget_ms), key=lambda u: (u.error_reduction, -u.frame_ms),
                    default=None)
        if first is not None:
            alt, alt_steps = _greedy(model, options, {**lowest, first.material: first.new}, budget_ms, [first])
            if model.predict_error(alt) < model.predict_error(current) - 1e-12:
                current, steps = alt, alt_steps
        frame = model.predict_ms(current)
    return TuneResult(current, float(budget_ms), frame, model.predict_error(current), frame <= budget_ms, steps,
                      notes, model, method=model.method)


def _upgrades(model: CostModel, options: dict, current: dict, budget_ms: float):
    """Every single-material upgrade from `current` that fits the budget and lowers the error."""
    frame = model.predict_ms(current)
    for m, opts in options.items():
        for new in opts:
            if new <= current[m]:
                continue
            after = model.predict_ms({**current, m: new})
            gain = model.error[m][current[m]] - model.error[m][new]
            if after <= budget_ms and gain > 0:
                yield Upgrade(m, current[m], new, after - frame, gain, after)


def _greedy(model: CostModel, options: dict, current: dict, budget_ms: float, steps: list):
    """Take the best error reduction per added ms (ties: larger reduction, cheaper frame) until none fits."""
    current, steps = dict(current), list(steps)
    while True:
        best = max(_upgrades(model, options, current, budget_ms),
                   key=lambda u: (u.ratio, u.error_reduction, -u.frame_ms), default=None)
        if best is None:
            return current, steps
        current[best.material] = best.new
        steps.append(best)
