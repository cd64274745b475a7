"""`rayvr tune [SCENE] --budget-ms 11.1 --views 2 --size WxH [--report DIR]`: choose each
material's effect to fit a GPU frame budget, and set it against the standard configurations.

Prints the error-vs-time table (all RASTER, all SHADOWS, SHADOWS + REFLECTIONS, PATH_TRACED at
each --spp, and the tuned assignment) and the assignment. With --report it writes table.md,
results.csv, results.json, error_vs_ms_<metric>.png, assignment.md and tune.json into DIR, all under
temporary names first and renamed together at the end (the folder is checked for writability
before any rendering; a failure or Ctrl-C leaves none of them). The budget holds for the size and views given:
tune at the headset's resolution on the GPU that will render it.
"""
from __future__ import annotations

import json
from pathlib import Path

from ..cluster import cli as cluster_cli
from ..errors import OptionError
from .options import MAX_VIEWS, integer, number, views_count

METRICS = ("flip", "relmse")                 # the tuner's: per-pixel error maps
TABLE_METRICS = ("flip", "relmse", "psnr")


def register(sub) -> None:
    p = sub.add_parser("tune", help="fit per-material effects to a GPU frame budget; error vs time report")
    p.add_argument("scene", nargs="?", help="glTF file or built-in scene name (default: the Cornell box)")
    p.add_argument("--budget-ms", type=number("--budget-ms", 0, 1e6, low_open=True, unit=" ms"), default=11.1,
                   help="GPU ms per frame, > 0 (default 11.1: 90 Hz)")
    p.add_argument("--views", type=views_count(), default=2,
                   help=f"view count: 1 mono, 2 stereo, N a camera grid (1 to {MAX_VIEWS}; default 2)")
    p.add_argument("--size", default="1440x1600", help="per-view size WIDTHxHEIGHT (default 1440x1600)")
    p.add_argument("--report", help="folder for the table, CSV, JSON, plots and assignment")
    p.add_argument("--metric", default="flip", choices=METRICS, help="error the tuner minimises (default flip)")
    p.add_argument("--metrics", default="flip,relmse,psnr",
                   help="metrics of the table, comma-separated (default flip,relmse,psnr; FLIP is the slow one)")
    p.add_argument("--levels", default="raster,shadows,reflections,path_traced",
                   help="effects the tuner may choose, comma-separated (default all four)")
    p.add_argument("--spp", default="1,4,16", help="samples per pixel of the PATH_TRACED table rows (default 1,4,16)")
    p.add_argument("--frames", type=integer("--frames", 1, 100_000), default=20,
                   help="timed frames per configuration, >= 1 (default 20)")
    p.add_argument("--warmup", type=integer("--warmup", 0, 100_000), default=3, help="untimed frames first (default 3)")
    p.add_argument("--reference-frames", type=integer("--reference-frames", 1, 1_000_000), default=256,
                   help="frames of the converged reference, >= 1 (default 256)")
    p.add_argument("--reference-spp", type=integer("--reference-spp", 1, 1024), default=4,
                   help="paths per pixel per reference frame, 1 to 1024 (default 4)")
    p.add_argument("--cache", help="reference cache folder (default ~/.cache/rayvr/references)")
    p.add_argument("--ppd", type=number("--ppd", 0, 1000, low_open=True),
                   help="display pixels per degree for FLIP, > 0 (default FLIP's 67)")
    p.add_argument("--quiet", action="store_true", help="no progress bars")
    cluster_cli.add_arguments(p)
    p.set_defaults(func=run)


def parse_list(text: str, option: str, parse) -> list:
    """The comma-separated items of `text`, each through `parse`; an error names `option`."""
    items = [s.strip() for s in str(text).split(",") if s.strip()]
    if not items:
        raise OptionError(f"{option} {text!r}: give a comma-separated list")
    return [parse(s) for s in items]


def parse_spp(text: str) -> int:
    """One --spp item: an integer from 1 to 1024."""
    try:
        n = int(text)
    except ValueError:
        n = 0
    if not 1 <= n <= 1024:
        raise OptionError(f"--spp {text!r}: samples per pixel must be integers from 1 to 1024, e.g. --spp 1,4,16")
    return n


def check(args) -> tuple:
    """Validate the options argparse's types leave (the numbers are checked as they are parsed)
    before any rendering: (size, levels, spp, table metrics)."""
    from ..materials.effect import Effect
    from .options import parse_size

    size = parse_size(args.size, views=args.views)
    levels = parse_list(args.levels, "--levels", lambda s: Effect.parse(s, where="--levels"))
    spp = parse_list(args.spp, "--spp", parse_spp)
    table_metrics = parse_list(args.metrics, "--metrics", str.lower)
    for m in table_metrics:
        if m not in TABLE_METRICS:
            raise OptionError(f"--metrics {args.metrics}: unknown metric '{m}'; use some of {', '.join(TABLE_METRICS)}")
    if args.metric not in table_metrics:
        table_metrics.append(args.metric)
    return size, levels, spp, table_metrics


def run(args) -> int:
    from ..fileio import atomic_group, check_writable, write_text
    from ..tune import Config, ReferenceSettings, choose_effects, make_views, standard_configs
    from ..tune.configs import hybrid_graph
    from .options import load_scene_arg as load

    size, levels, spp, table_metrics = check(args)
    report = Path(args.report) if args.report else None
    if report is not None:
        check_writable(report, "--report", folder=True)
    from ..tune.reference import default_cache_dir

    check_writable(args.cache or default_cache_dir(), "--cache", folder=True)
    scene = load(args.scene)
    view_set = make_views(scene, args.views, size)
    settings = ReferenceSettings(args.reference_frames, args.reference_spp)
    progress = not args.quiet
    with cluster_cli.tune_functions(args, args.scene, scene) as (probe_cost_model, measure):
        model, ref, _ = probe_cost_model(scene, view_set, hybrid_graph, {}, metric=args.metric, levels=levels,
                                         frames=args.frames, warmup=args.warmup, reference_settings=settings,
                                         cache_dir=args.cache, ppd=args.ppd, progress=progress)
        tuned = choose_effects(model, args.budget_ms, levels)
        tuned_name = f"tuned for {args.budget_ms:g} ms"
        configs = standard_configs(scene, spp=spp) + [Config(tuned_name, dict(tuned.assignment))]
        results = measure(scene, configs, reference=ref, views=view_set, frames=args.frames, warmup=args.warmup,
                          ppd=args.ppd, metrics=table_metrics, progress=progress)
    row = results[tuned_name]
    tuned.record_measurement(row.frame_ms, row.errors[args.metric], results.method, "--budget-ms")
    print(results.table())
    print()
    print(f"assignment for {scene.name} within {args.budget_ms:g} ms ({len(view_set)} view(s) of {size[0]}x{size[1]}):")
    print(tuned.table())
    if report is not None:
        with atomic_group():
            written = results.write(report, budget_ms=args.budget_ms)
            written.append(write_text(report / "assignment.md", tuned.table() + "\n"))
            written.append(write_text(report / "tune.json", json.dumps(tuned.as_dict(), indent=2, default=str) + "\n"))
        for path in written:
            print(f"wrote {path}")
    return 0
