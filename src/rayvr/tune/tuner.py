"""The budget tuner on the GPU: probe a cost model against the trusted reference, choose each
material's effect (rayvr.tune.budget.choose_effects, which needs no GPU), check the choice.

    tuned = rv.tune.tune_effects(scene, budget_ms=11.1, size=(1440, 1600), views=2)
    print(tuned.table())
"""
from __future__ import annotations

from ..errors import OptionError
from ..graph_options import OPTIONS, realtime_option_sets
from ..materials.effect import Effect
from ..study.configs import accepts, hybrid_graph, set_effects
from ..study.display import Display
from ..study.metrics import DEFAULT_EPS
from ..study.reference import Reference, ReferenceSettings, cached_reference
from ..study.timing import make_views
from .budget import FRAME_BUDGET_MS, KNOBS, TuneResult, back_off, choose_among, choose_effects, spend_budget
from . import cost_probe
from .cost_probe import ErrorJudge, render_assignment


# The graph options the tuner tries beside each material's effect (those the graph builder takes):
# probe GI lights RASTER, SHADOWS and REFLECTIONS materials indirectly; SVGF denoises the one-sample
# light of every lit pixel (hybrid) or path (path_traced); ReSTIR resamples the direct light of SHADOWS
# pixels and above; GI and SVGF together can be the least error per ms (benchmarks/RESULTS.md has the
# tauray study), so the tuner tries every combination.
OPTION_SETS = tuple(realtime_option_sets())   # none, each real-time value alone, the combinations
# The keys of a study's configurations that tuned_study tries (OIDN, offline, never: it is no GPU time).
TUNED_OPTIONS = tuple(o.name for o in OPTIONS)


def option_sets_for(builder, options: dict, option_sets=None) -> list[dict]:
    """`options` merged with each of `option_sets` (default OPTION_SETS) that `builder` accepts,
    without repeats: the graph option sets the tuner measures a cost model for."""
    out = []
    for extra in OPTION_SETS if option_sets is None else option_sets:
        if not isinstance(extra, dict):
            raise OptionError(f"option_sets: expected dicts of graph options such as {{'gi': 'probes'}}, got {extra!r}")
        if all(accepts(builder, k) for k in extra):
            merged = {**options, **extra}
            if merged not in out:
                out.append(merged)
    return out or [dict(options)]


def choose_with_options(models, base: dict, budget_ms: float, levels, fixed: dict | None = None) -> TuneResult:
    """`choose_effects` on each (graph options, CostModel) of `models`, each choice's `options`
    being what its set adds to `base`, then `choose_among` them."""
    choices = []
    for opts, model in models:
        choice = choose_effects(model, budget_ms, levels, fixed)
        choice.options = {k: v for k, v in opts.items() if k not in base or base[k] != v}
        choices.append(choice)
    return choose_among(choices)


def make_judge(scene, view_set, metric: str, reference=None, cache_dir=None, display: Display = Display(),
               preset: str = "index", ppd: float | None = None, eps: float = DEFAULT_EPS, gpu=None) -> ErrorJudge:
    """The tuner's error maps: against `reference` (a Reference, or ReferenceSettings to load or
    render one), displayed with `display` (its exposure fixed from the reference), FLIP at the
    preset's pixels per degree unless `ppd` is given."""
    from ..xr.presets import get_preset

    if not isinstance(reference, Reference):
        reference = cached_reference(scene, view_set, reference or ReferenceSettings(), cache_dir, gpu, eps=eps)
    return ErrorJudge(reference, display.fixed(reference.image), ppd or get_preset(preset).pixels_per_degree,
                      metric, eps)


def tune_effects(renderer_or_scene, budget_ms: float = FRAME_BUDGET_MS, size=None, views=None, metric: str = "flip",
                 levels=tuple(Effect), fixed: dict | None = None, graph=None, options: dict | None = None,
                 frames: int = 10, warmup: int = 3, warmup_s: float | None = None, trials: int = 2,
                 reference=None, cache_dir=None, display: Display = Display(), preset: str = "index",
                 ppd: float | None = None, verify: bool = True, apply: bool = True, progress: bool = True,
                 gpu=None, option_sets=None, spend: bool = True, knobs=KNOBS) -> TuneResult:
    """Measure a CostModel on the GPU (`rayvr.tune.cost_probe.probe_cost_model`: one render per effect
    level, timed after `warmup_s` seconds of warm-up, default 0.5 s on GPUs with timer queries),
    choose effects with `choose_effects`, then (with `verify`) render the choice and record its
    measured ms and error; a choice that measures over the budget is replaced by one chosen for a
    smaller ask (`rayvr.tune.budget.back_off`). With `apply` the scene's materials get the chosen
    effects.

    `renderer_or_scene`: a Scene (with `size`, `views`: default 2 views of 1440x1600) or an
    rv.Renderer (its scene, views and graph; `graph` then defaults to a copy of its graph; with a
    sink, views from the scene's camera at the sink's view count and size).
    `graph`: a builder `graph(**options)` (default rayvr.tune.hybrid_graph; its PATH_TRACED
    materials get the reference's bounces). `reference`: a Reference or ReferenceSettings.
    `option_sets`: graph options tried beside the effects (default OPTION_SETS, those `graph`
    takes; [{}]: `options` alone): one cost model each, and the choice that fits with the least
    predicted error wins (its `options` say which). With `spend` (and `verify`) a choice that
    measures under the budget then raises `knobs` (light samples, paths per pixel, probe density:
    rayvr.tune.budget.spend_budget) while the measured frame still fits and the error falls."""
    scene, view_set, builder, gpu = _target(renderer_or_scene, size, views, graph, gpu)
    judge = make_judge(scene, view_set, metric, reference, cache_dir, display, preset, ppd, gpu=gpu)
    options = dict(options or {})
    if accepts(builder, "path_bounces"):
        options.setdefault("path_bounces", judge.reference.settings.max_bounces)
    models = [(opts, cost_probe.probe_cost_model(scene, view_set, builder, opts, judge, levels, frames, warmup,
                                                 warmup_s, trials, progress, gpu)[0])
              for opts in option_sets_for(builder, options, option_sets)]
    def choose(ask_ms):
        return choose_with_options(models, options, ask_ms, levels, fixed)

    def render(assignment, opts):
        return render_assignment(scene, view_set, builder, opts, assignment, judge, frames, warmup, warmup_s,
                                 trials, gpu)

    def verify_choice(choice):
        choice.record_measurement(*render(choice.assignment, {**options, **choice.options}))
        return choice.measured_ms

    result = choose(budget_ms)
    if verify:
        result = back_off(result, choose, verify_choice, budget_ms)
        if spend:
            result = spend_budget(result, lambda a, o: render(a, o)[:2], budget_ms, knobs, base_options=options)
    if apply:
        set_effects(scene, result.assignment)
    return result


def _target(renderer_or_scene, size, views, graph, gpu):
    from ..renderer import Renderer
    from ..rendergraph.graph import RenderGraph

    if isinstance(renderer_or_scene, Renderer):
        r = renderer_or_scene
        if size is not None or views is not None:
            raise OptionError("tune_effects: a Renderer brings its own views; pass size/views only with a Scene")
        view_set = r.view_set if r.view_set is not None else make_views(r.scene, r.view_count, r.size)
        if graph is None:
            data = r.graph.to_dict()

            def graph(**_):
                return RenderGraph.from_dict(data)
        return r.scene, view_set, graph, gpu or r.gpu
    view_set = make_views(renderer_or_scene, 2 if views is None else views, size or (1440, 1600))
    return renderer_or_scene, view_set, graph or hybrid_graph, gpu


def tuned_study(scene, view_set, reference: Reference, settings, configs, budgets=(FRAME_BUDGET_MS,), metric: str = "flip",
                levels=tuple(Effect), trials: int = 2, cache_dir=None, progress: bool = True, gpu=None,
                notes=(), budget_option: str = "budget_ms", runner=None, option_sets=None, spend: bool = True,
                knobs=KNOBS):
    """The error study with the tuner on top: probe a cost model against `reference` (judged as
    the study judges), choose effects for each of `budgets`, and measure `configs` plus one
    "tuned for B ms" row per budget alike. A tuned row that measures over its budget is chosen
    again for a smaller ask and measured alone (`rayvr.tune.budget.back_off`, at most twice).
    Returns (Results, {budget: TuneResult}); each TuneResult records its row's measured ms and
    error (a note names `budget_option` when the row still runs over), and Results.tuned is the
    first. `runner`: where the probe and the study run
    (default here; rayvr.cluster.StudyRunner: the probe on one worker, the rows over all).
    `option_sets`: the graph options tuned beside the effects (default: those of `configs` on the
    hybrid graph, e.g. probe GI and SVGF, and none), one cost model each (tune_effects). With
    `spend` a tuned row that measures under its budget raises `knobs` as tune_effects does (here,
    with a local runner) and is measured again."""
    from ..study.configs import Config
    from ..study.measure import measure
    from ..study.pool import MetricPool
    from ..study.runner import LocalRunner

    runner = runner or LocalRunner()
    options = {"path_bounces": reference.settings.max_bounces}
    if option_sets is None:
        option_sets = [{}] + [{k: v for k, v in c.options.items() if k in TUNED_OPTIONS}
                              for c in configs if c.builder is hybrid_graph
                              and all(o.is_realtime(c.options.get(o.name)) for o in OPTIONS)]
    # a local probe's error maps are made by worker processes while it renders (as the study's)
    workers = settings.workers_for(view_set) if isinstance(runner, LocalRunner) else 0
    with MetricPool(workers) as pool:
        judge = ErrorJudge(reference, settings.display.fixed(reference.image), settings.pixels_per_degree(), metric,
                           settings.eps, pool=pool if workers else None)
        probe = getattr(runner, "probe", cost_probe.probe_cost_model)   # the runner's own (a worker's), else here
        models = [(opts, probe(scene, view_set, hybrid_graph, opts, judge, levels=levels,
                                      frames=settings.timing_frames, warmup=settings.warmup,
                                      warmup_s=settings.warmup_s, trials=trials, progress=progress, gpu=gpu)[0])
                  for opts in option_sets_for(hybrid_graph, options, option_sets)]
    def choose(ask_ms):
        return choose_with_options(models, options, ask_ms, levels)

    def row_config(b, choice):
        return Config(f"tuned for {b:g} ms", dict(choice.assignment), options={**options, **choice.options})

    first = {float(b): choose(b) for b in budgets}
    results = measure(scene, list(configs) + [row_config(b, t) for b, t in first.items()], views=view_set,
                      reference=reference, settings=settings, cache_dir=cache_dir, progress=progress, gpu=gpu,
                      notes=notes, runner=runner)

    def measured_row(b, choice, again: bool = False):
        """The study's row for `choice` (measured with the rest, or now alone after an overrun or
        a raised knob: its row only, the progressive curves are the study's)."""
        config = row_config(b, choice)
        if again or choice is not first[b]:
            alone = measure(scene, [config], views=view_set, reference=reference, settings=settings,
                            cache_dir=cache_dir, progress=progress, gpu=gpu, curves=False, runner=runner)
            results.rows[[r.name for r in results.rows].index(config.name)] = alone[config.name]
        row = results[config.name]
        row.tuned = True
        choice.record_measurement(row.gpu_ms, row.mean(metric), results.method, budget_option)
        return row.gpu_ms

    tuned = {b: back_off(t, choose, lambda choice, b=b: measured_row(b, choice), b) for b, t in first.items()}
    if spend and isinstance(runner, LocalRunner):
        judge = ErrorJudge(reference, settings.display.fixed(reference.image), settings.pixels_per_degree(), metric,
                           settings.eps)

        def render(assignment, opts):
            return render_assignment(scene, view_set, hybrid_graph, opts, assignment, judge, settings.timing_frames,
                                     settings.warmup, settings.warmup_s, trials, gpu)[:2]

        for b, t in tuned.items():
            before = dict(t.options)
            spend_budget(t, render, b, knobs, base_options=options)
            if t.options != before:
                measured_row(b, t, again=True)
    results.tuned = next(iter(tuned.values()))
    return results, tuned
