"""`rayvr tune [SCENE] --budget-ms 11.1 --views 2 --size WxH [--report DIR]`: choose each
material's effect to fit a GPU frame budget, from the error study's sound measurements, and set
the choice beside every uniform configuration.

The tuner probes a cost model (one render per effect level, timed after a warm-up; per-pixel
error against the converged, checked reference, split by material) for each graph option set
(--graph-options), chooses greedily (rayvr.tune.budget) and keeps the best that fits, then the study (`rayvr converge`) measures the standard configurations and
the tuned assignment alike. Prints the table and the assignment; with --report writes the study's
report (report.md, report.html, results.json, plots, images) plus tune.json into DIR, all at
once (a failure or Ctrl-C leaves none of it). Options are checked before any rendering, as
`rayvr converge` checks them; --workers N (or --address) runs the reference, the probe and the
rows on a Ray cluster. The budget holds for the size and views given: tune at the headset's
resolution on the GPU that will render it.
"""
from __future__ import annotations

import json

from ..errors import OptionError
from .converge import StudyPlan, add_study_arguments, parse_list, print_summary
from ..tune.budget import FRAME_BUDGET_MS
from .options import number

TUNE_METRICS = ("flip", "relmse")          # the tuner's: per-pixel error maps


def register(sub) -> None:
    p = sub.add_parser("tune", help="fit per-material effects to a GPU frame budget, beside the error study")
    add_study_arguments(p)
    p.add_argument("--budget-ms", type=number("--budget-ms", 0, 1e6, low_open=True, unit=" ms"), default=FRAME_BUDGET_MS,
                   help="GPU ms per frame, > 0 (default 11.1: 90 Hz)")
    p.add_argument("--metric", default="flip", choices=TUNE_METRICS,
                   help="error the tuner minimises (default flip: displayed-image FLIP)")
    p.add_argument("--levels", default="raster,shadows,reflections,path_traced",
                   help="effects the tuner may choose, comma-separated (default all four)")
    p.add_argument("--graph-options", default="auto", choices=("auto", "none"),
                   help="graph options the tuner tries beside the effects: auto (those of the study's hybrid "
                        "configurations: probe GI, SVGF; one cost model each) or none (the graph's defaults)")
    p.set_defaults(func=run)


def run(args) -> int:
    from ..gpu import get_context
    from ..materials.effect import Effect
    from ..study import make_views, write_report
    from ..tune.tuner import tuned_study
    from .cluster import study_runner
    from .options import load_scene_arg

    levels = parse_list(args.levels, "--levels", lambda s: Effect.parse(s, where="--levels"))
    gpu = get_context()
    plan = StudyPlan(args, gpu)
    if args.metric not in plan.settings.metrics:
        raise OptionError(f"--metric {args.metric}: add it to --metrics ({','.join(plan.settings.metrics)})")
    scene = load_scene_arg(args.scene)
    configs = plan.configs(scene)
    if plan.note:
        print(plan.note)
    view_set = make_views(scene, plan.views, plan.size)
    with study_runner(args, args.scene, scene, plan.progress) as runner:
        tick = None if runner.shows_progress else _reference_bar(plan, scene)
        ref = runner.reference(scene, view_set, plan.reference, plan.cache, eps=plan.settings.eps, gpu=gpu, tick=tick)
        results, by_budget = tuned_study(scene, view_set, ref, plan.settings, configs, [args.budget_ms], args.metric,
                                         levels, cache_dir=plan.cache, progress=plan.progress, gpu=gpu,
                                         notes=plan.notes(), budget_option="--budget-ms", runner=runner,
                                         option_sets=[{}] if args.graph_options == "none" else None)
    tuned = by_budget[float(args.budget_ms)]
    print_summary(results)
    print()
    print(f"assignment for {scene.name} within {args.budget_ms:g} ms ({len(view_set)} view(s) of "
          f"{view_set.size[0]}x{view_set.size[1]}):")
    print(tuned.table())
    if plan.report is not None:
        extra = {"tune.json": json.dumps(tuned.as_dict(), indent=2, default=str) + "\n"}
        print(f"wrote {write_report(results, plan.report, budget_ms=args.budget_ms, extra=extra)}")
    return 0


def _reference_bar(plan, scene):
    """A tqdm tick for the reference render (None when quiet)."""
    if not plan.progress:
        return None
    from tqdm import tqdm

    total = plan.reference.frames + plan.reference.bounce_check_frames
    bar = tqdm(total=total, desc=f"reference {scene.name}", unit="frame", leave=False)

    def tick(done: int) -> None:
        bar.n = done
        bar.refresh()
        if done >= total:
            bar.close()

    return tick
