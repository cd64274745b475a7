"""`rayvr converge [SCENE] --views N --size WxH --report DIR`: error against GPU time that can be
trusted, for the standard configurations (or a user's list, `--configs FILE.json`).

Renders a converged, checked reference (two independent halves must agree within a tolerance;
one more bounce must change it by less than another), then every configuration: its GPU ms, its
error against the reference (FLIP of the displayed image at the headset's pixels per degree,
HDR-FLIP, PSNR, SSIM, relMSE) as mean and spread over several frames, on a still and a moving
head, and its bias floor (the configuration converged); then progressive-convergence curves.
Prints the table; with --report writes report.md, report.html, results.json, the plots and the
images into DIR, all at once (an interrupted run writes nothing). Unset sizes and frame counts
are chosen for the machine (rayvr.study.defaults) and the output says which. Every option is
checked, and the --report and --cache folders are checked for writing, before any rendering.
With --workers N (or --address) the study runs on a Ray cluster (rayvr.cluster.study): the
references split by samples, each configuration on one worker, the same cache.
"""
from __future__ import annotations

import argparse
import math
from pathlib import Path

from ..errors import OptionError
from ..study import seeds
from .options import MAX_VIEWS, integer, number, views_count

MAX_FRAMES = 100_000
MAX_SPP = 1024
MAX_BOUNCES = 64
MAX_EXPOSURE = 64.0


def add_study_arguments(p: argparse.ArgumentParser) -> None:
    """The options `rayvr converge` and `rayvr tune` share (numbers checked as they are parsed)."""
    from . import cluster as cluster_cli

    frames = integer("--frames", 1, MAX_FRAMES)
    p.add_argument("scene", nargs="?", help="glTF file or built-in scene name (default: the Cornell box)")
    p.add_argument("--views", type=views_count(), default=2,
                   help=f"view count: 1 mono, 2 stereo, N a camera grid (1 to {MAX_VIEWS}; default 2)")
    p.add_argument("--size", help="per-view WIDTHxHEIGHT (default: 32x32 on llvmpipe, 720x800 on a GPU)")
    p.add_argument("--report", help="folder for report.md, report.html, results.json, plots and images")
    p.add_argument("--configs", help="JSON file of configurations instead of the standard set")
    p.add_argument("--spp", default="1,4,16",
                   help=f"samples per pixel of the PATH_TRACED rows, each 1 to {MAX_SPP} (default 1,4,16)")
    p.add_argument("--reflect", default="auto", help="material that gets REFLECTIONS in the mixed row (auto: floor)")
    p.add_argument("--preset", default="index", help="headset whose pixels per degree FLIP uses (default index)")
    p.add_argument("--ppd", type=number("--ppd", 0, 1000, low_open=True),
                   help="pixels per degree for FLIP instead of the preset's (> 0)")
    p.add_argument("--tonemap", default="aces", help="tone mapping of the displayed images: aces, reinhard, linear")
    p.add_argument("--exposure", default="auto",
                   help=f"exposure in stops (-{MAX_EXPOSURE:g} to {MAX_EXPOSURE:g}), or 'auto' (from the reference, "
                        f"once)")
    p.add_argument("--foveation", choices=("none", "fixed", "gaze"), default="none",
                   help="also each level with rays foveated (fixed: about each view's centre), judged beside the "
                        "unfoveated one, by FLIP in the fovea and weighted by eccentricity too")
    p.add_argument("--metrics", default="flip,hdrflip,psnr,ssim,relmse,relmse_trim,fireflies,flip_fovea,flip_ecc",
                   help="metrics, comma-separated (default all: flip,hdrflip,psnr,ssim,relmse,relmse_trim,fireflies,"
                        "flip_fovea,flip_ecc)")
    p.add_argument("--frames", type=frames, help=f"judged frames per configuration, 1 to {MAX_FRAMES} (default 4)")
    p.add_argument("--timing-frames", type=integer("--timing-frames", 1, MAX_FRAMES),
                   help="timed frames per configuration (default 10 llvmpipe, 30 GPU)")
    p.add_argument("--warmup", type=integer("--warmup", 0, MAX_FRAMES),
                   help="untimed frames before timing (default 2 llvmpipe, 5 GPU)")
    p.add_argument("--warmup-s", type=number("--warmup-s", 0, 3600, unit=" s"),
                   help="seconds of untimed frames first (default 0.5 on a GPU, 0 llvmpipe)")
    p.add_argument("--reference-frames", type=integer("--reference-frames", 2, seeds.RANGE),
                   help="frames of the reference's first round, even (default 64 llvmpipe, 256 GPU); given alone, "
                        "the reference renders exactly these")
    p.add_argument("--reference-max-frames", type=integer("--reference-max-frames", 2, seeds.RANGE),
                   help="render the reference on until converged, up to this many frames, even (default 1024 "
                        "llvmpipe, 16384 GPU)")
    p.add_argument("--reference-seconds", type=number("--reference-seconds", 0, 86400, unit=" s"),
                   help="stop rendering the reference on after this many seconds, summed over the runs that "
                        "resume it from the cache (default 60 llvmpipe, 300 GPU)")
    p.add_argument("--reference-spp", type=integer("--reference-spp", 1, MAX_SPP),
                   help=f"paths per pixel per reference frame, 1 to {MAX_SPP} (default 16)")
    p.add_argument("--bounces", type=integer("--bounces", 1, MAX_BOUNCES), default=8,
                   help="bounces of the reference and PATH_TRACED rows (default 8)")
    p.add_argument("--tolerance", type=number("--tolerance", 0, 1, low_open=True), default=5e-4,
                   help="largest predicted relMSE of a converged reference (default 5e-4)")
    p.add_argument("--bounce-tolerance", type=number("--bounce-tolerance", 0, 1, low_open=True), default=0.01,
                   help="largest change of the reference's mean radiance with one more bounce (default 0.01)")
    p.add_argument("--trajectory", default="turn", help="head motion: turn, walk, still, a pose-log .json, or none")
    p.add_argument("--motion-frames", type=integer("--motion-frames", 1, MAX_FRAMES),
                   help="frames along the trajectory (default 16 llvmpipe, 32 GPU)")
    p.add_argument("--motion-samples", type=integer("--motion-samples", 1, seeds.SLOTS - 1),
                   help="trajectory frames judged, each with its own reference (default 1 llvmpipe, 3 GPU)")
    p.add_argument("--no-floors", action="store_true", help="skip the bias floors (converged configurations)")
    p.add_argument("--floor-fraction", type=number("--floor-fraction", 0, 1, low_open=True), default=None,
                   help="a bias floor renders this fraction of the reference's paths per pixel (default: 0.25 on a "
                        "GPU, 0.0625 on llvmpipe)")
    p.add_argument("--progressive-frames", type=integer("--progressive-frames", 0, MAX_FRAMES),
                   help="frames of the progressive curves (0: none)")
    p.add_argument("--cache", help="reference cache folder (default ~/.cache/rayvr/references)")
    p.add_argument("--no-cache", action="store_true", help="render the reference and floors again, store nothing")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    cluster_cli.add_arguments(p)


def register(sub) -> None:
    p = sub.add_parser("converge", help="error against GPU time against a converged, checked reference; report")
    add_study_arguments(p)
    p.set_defaults(func=run)


def parse_list(text: str, option: str, parse) -> list:
    """The comma-separated items of `text`, each through `parse`; an error names `option`."""
    items = [s.strip() for s in str(text).split(",") if s.strip()]
    if not items:
        raise OptionError(f"{option} {text!r}: give a comma-separated list")
    return [parse(s) for s in items]


def parse_spp(text: str) -> int:
    """One --spp item: an integer from 1 to MAX_SPP."""
    try:
        n = int(text)
    except ValueError:
        n = 0
    if not 1 <= n <= MAX_SPP:
        raise OptionError(f"--spp {text!r}: samples per pixel must be integers from 1 to {MAX_SPP}, "
                          f"e.g. --spp 1,4,16")
    return n


def parse_exposure(text: str) -> float | None:
    """--exposure: 'auto' (None) or finite stops within +-MAX_EXPOSURE."""
    if str(text).strip().lower() == "auto":
        return None
    try:
        stops = float(text)
    except ValueError:
        raise OptionError(f"--exposure {text}: give stops (e.g. 0, 1.5, -1) or 'auto'") from None
    if not (math.isfinite(stops) and abs(stops) <= MAX_EXPOSURE):
        raise OptionError(f"--exposure {text}: out of range; give stops from -{MAX_EXPOSURE:g} to "
                          f"{MAX_EXPOSURE:g} or 'auto'")
    return stops


class StudyPlan:
    """The validated options: everything `measure` needs, and the note on what was defaulted.
    Refuses (OptionError, OutputError) before anything is rendered or written."""

    def __init__(self, args, gpu):
        from ..study import Display
        from ..study.defaults import machine_defaults
        from ..study.metrics import METRICS
        from ..study.plan import plan_settings
        from ..xr.presets import get_preset
        from .options import parse_size

        d = machine_defaults(gpu)
        self.size = parse_size(args.size, views=args.views) if args.size else parse_size(
            f"{d.size[0]}x{d.size[1]}", "the default --size", views=args.views)
        try:
            get_preset(args.preset)
        except OptionError as exc:
            raise OptionError(f"--preset {args.preset}: {exc}") from None
        metrics = parse_list(args.metrics, "--metrics", str.lower)
        for m in metrics:
            if m not in METRICS:
                raise OptionError(f"--metrics {args.metrics}: unknown metric '{m}'; use some of {', '.join(METRICS)}")
        self.spp = parse_list(args.spp, "--spp", parse_spp)
        self.views = args.views
        exposure = parse_exposure(args.exposure)
        try:
            self.display = Display(args.tonemap.lower(), exposure)
        except OptionError as exc:
            raise OptionError(f"--tonemap {args.tonemap}: {exc}") from None
        given = {key: getattr(args, key) for key in (
            "reference_frames", "reference_max_frames", "reference_seconds", "reference_spp", "bounces", "tolerance",
            "bounce_tolerance", "trajectory", "motion_frames", "motion_samples", "frames", "timing_frames", "warmup",
            "warmup_s", "floor_fraction", "progressive_frames", "preset", "ppd")}
        given.update(floors=not args.no_floors, display=self.display, metrics=metrics)
        self.reference, self.settings, picked = plan_settings(d, given, lambda key: f"--{key.replace('_', '-')}")
        chosen = {} if args.size else {"--size": f"{d.size[0]}x{d.size[1]}"}
        chosen.update(picked)
        if args.no_cache and args.cache:
            raise OptionError(f"--cache {args.cache} with --no-cache: --no-cache stores nothing; leave one of them out")
        self.cache = False if args.no_cache else args.cache
        self.denoised_levels = d.denoised_levels
        self.probes = {"counts": list(d.probe_counts)} if d.probe_counts and not args.configs else None
        if self.probes:
            chosen["probe GI rows' probes"] = "x".join(str(c) for c in d.probe_counts)
        left_out = not d.denoised_levels and not args.configs
        self.note = d.note(chosen, left_out) if chosen or left_out else None
        self.report = Path(args.report) if args.report else None
        from ..fileio import check_writable

        if self.report is not None:
            check_writable(self.report, "--report", folder=True)
        if self.cache is not False:
            from ..study.reference import default_cache_dir

            check_writable(self.cache or default_cache_dir(), "--cache", folder=True)
        self.configs_file = args.configs
        self.foveation = getattr(args, "foveation", "none")
        if self.configs_file and self.foveation != "none":
            raise OptionError(f"--foveation {self.foveation} adds rows to the standard set; with --configs give each "
                              f"configuration its own \"options\": {{\"foveation\": \"{self.foveation}\"}}")
        self.reflect = args.reflect
        self.progress = not args.quiet

    def configs(self, scene) -> list:
        from ..study import load_configs, standard_configs

        if self.configs_file:
            return load_configs(self.configs_file)
        return standard_configs(scene, self.reference, reflect=self.reflect, spp=self.spp,
                                denoised_levels=self.denoised_levels, probes=self.probes, foveation=self.foveation)

    def notes(self) -> list[str]:
        return [self.note] if self.note else []


def run(args) -> int:
    from .cluster import study_runner
    from ..gpu import get_context
    from ..study import measure, write_report
    from .options import load_scene_arg

    plan = StudyPlan(args, get_context())
    scene = load_scene_arg(args.scene)
    configs = plan.configs(scene)
    if plan.note:
        print(plan.note)
    with study_runner(args, args.scene, scene, plan.progress) as runner:
        results = measure(scene, configs, views=plan.views, size=plan.size, reference=plan.reference,
                          settings=plan.settings, cache_dir=plan.cache, progress=plan.progress, notes=plan.notes(),
                          runner=runner)
    print_summary(results)
    if plan.report is not None:
        print(f"wrote {write_report(results, plan.report)}")
    return 0


def print_summary(results) -> None:
    """The reference's verdict and the results table."""
    s = results.study
    print(f"{s['scene']}: {s['views']} view(s) of {s['size'][0]}x{s['size'][1]}; FLIP at {s['ppd']:.1f} ppd "
          f"({s['ppd_source']}); {s['display_text']}; GPU time by {s['timing']}")
    print(f"reference: {results.reference.verdict()}")
    for frame, ref in results.motion_references:
        print(f"reference of trajectory frame {frame}: {ref.verdict()}")
    print(results.table_title())
    print(results.table())
