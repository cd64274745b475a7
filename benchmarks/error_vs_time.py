"""Error against GPU time that can be trusted (rayvr.tune's study), with the tuner's assignment.

For each scene (default: tauray/test.glb and the built-in Cornell box), stereo 2 x 1440x1600 with
FLIP at the `index` preset's pixels per degree: a converged, checked reference, every standard
configuration (each effect level alone and mixed, PATH_TRACED at 1/4/16 spp, + TAA, and with a
denoiser or probe GI where the graphs have them) and the tuned assignment for each --budgets
(11.1 and 5.5 ms), each with its GPU ms, its error as mean ± std over frames and views, in
motion, and its bias floor. One table row per (scene, configuration); the full report of each
scene (report.md, report.html, results.json, plots, images) goes to OUT/error_vs_time_<scene>/.
`--quick`: the Cornell box alone at llvmpipe's study sizes (those of rayvr.study.defaults: 2 x
32x32, a 64 x 16 spp reference), for a smoke run on llvmpipe; options given still win.
`--figures device`: the full size with the reduced figures of DEVICE, which fit both scenes into
one 10-minute call on the lent H200 (tools/gpu-bench study); the notes say which figures ran.
The images are judged by `--metric-workers` processes (default os.cpu_count() - 2 at this size)
while the GPU renders on (rayvr.study.pool): the same numbers as judged one after the other.
"""
from __future__ import annotations

from pathlib import Path

from ._study import add_figure_options, resolve_figures, stat_cell

DEFAULT_SCENES = [str(Path(__file__).resolve().parents[2] / "shared" / "scenes" / "tauray" / "test.glb"), "cornell_box"]


# option: (full run, --quick); an option given on the command line wins over both
FIGURES = {"size": ("1440x1600", "32x32"), "timing_frames": (50, 10), "warmup": (10, 2), "reference_frames": (256, 64),
           "reference_spp": (16, 16), "motion_frames": (32, 16), "motion_samples": (3, 2),
           "progressive_frames": (256, 16)}
# --figures device: what differs from the full run, to fit both scenes into one device call of
# 10 minutes (benchmarks/RESULTS.md, "Where the error study's time goes": ~8.8 minutes projected);
# FLIP, PSNR, SSIM and relMSE on every judged frame and view, HDR-FLIP on the first (DEVICE_HDRFLIP_FRAMES)
DEVICE = {"timing_frames": 12, "warmup": 2, "reference_frames": 64, "motion_frames": 16, "motion_samples": 1,
          "progressive_frames": 64}
DEVICE_FLOOR_FRACTION = 0.125  # floors of 128 spp (the full run: 0.25 of 4096)
DEVICE_IMAGE_STEP = 8        # the report's images at every 8th pixel: 360x200 per stereo pair, a few MB per scene
DEVICE_HDRFLIP_FRAMES = 1     # HDR-FLIP (~88 CPU-s a stereo 1440x1600 image) on each configuration's first frame


def add_arguments(parser) -> None:
    parser.add_argument("--scenes", help="glTF paths or built-in names, comma-separated (default: tauray/test.glb "
                                         "and cornell_box; quick: cornell_box)")
    parser.add_argument("--views", type=int, default=2)
    parser.add_argument("--preset", default="index", help="headset whose pixels per degree FLIP uses")
    parser.add_argument("--budgets", default="11.1,5.5", help="tuner budgets in GPU ms, comma-separated")
    parser.add_argument("--frames", type=int, default=4, help="judged frames per configuration")
    add_figure_options(parser, FIGURES)
    parser.add_argument("--figures", choices=("full", "device"), default="full",
                        help="full: the defaults above; device: the reduced figures that fit one call on the H200 "
                             f"({', '.join(f'{k} {v}' for k, v in DEVICE.items())}); options given still win")
    parser.add_argument("--floor-fraction", type=float,
                        help="bias floors render this fraction of the reference's paths per pixel (default 0.25; "
                             f"device figures: {DEVICE_FLOOR_FRACTION})")
    parser.add_argument("--hdrflip-frames", type=int,
                        help="HDR-FLIP on the first N judged frames of each configuration and its floor only, not "
                             "in motion nor on the curves (default: everywhere; device figures: 1)")
    parser.add_argument("--report-image-step", type=int,
                        help="the report's images at every Nth pixel (default 1; device figures: 8, a few MB)")
    parser.add_argument("--metric-workers", type=int,
                        help="processes judging the images while the GPU renders (default: os.cpu_count() - 2 from "
                             "256x256 per view, else 0 = one after the other here)")
    parser.add_argument("--cache", help="reference cache folder (default ~/.cache/rayvr/references)")
    parser.add_argument("--denoised-levels", choices=("auto", "on", "off"), default="auto",
                        help="the hybrid levels through SVGF, with and without probe GI (auto: in the full "
                             "figures, not in the device figures nor --quick)")


def run(args) -> dict:
    from rayvr.cli.converge import parse_list
    from rayvr.cli.options import load_scene_arg, parse_size
    from rayvr.study import Motion, ReferenceSettings, StudySettings, cached_reference, make_views, standard_configs
    from rayvr.study import write_report
    from rayvr.study.report import slug
    from rayvr.study.results import effects_text
    from rayvr.study.timing import GPU_WARM_UP_S
    from rayvr.study.runner import LocalRunner
    from rayvr.tune.tuner import tuned_study
    from rayvr.xr.presets import get_preset

    from rayvr.errors import OptionError

    quick = args.quick
    if quick and args.figures != "full":
        raise OptionError("error_vs_time: --quick and --figures device are two different sets of figures; give one")
    f = resolve_figures(args, FIGURES)
    if args.figures == "device":
        f.update({k: v for k, v in DEVICE.items() if getattr(args, k) is None})
    floor_fraction = args.floor_fraction or (DEVICE_FLOOR_FRACTION if args.figures == "device" else 0.25)
    image_step = args.report_image_step or (DEVICE_IMAGE_STEP if args.figures == "device" else 1)
    hdrflip_frames = args.hdrflip_frames if args.hdrflip_frames is not None else (
        DEVICE_HDRFLIP_FRAMES if args.figures == "device" else None)
    scenes = parse_list(args.scenes, "--scenes", str) if args.scenes else (["cornell_box"] if quick else DEFAULT_SCENES)
    size = parse_size(f["size"])
    budgets = parse_list(args.budgets, "--budgets", float)
    ref_settings = ReferenceSettings(f["reference_frames"], f["reference_spp"])
    motion = Motion("turn", f["motion_frames"], f["motion_samples"], get_preset(args.preset).default_refresh)
    settings = StudySettings(frames=args.frames, timing_frames=f["timing_frames"], warmup=f["warmup"],
                             warmup_s=0.0 if quick else GPU_WARM_UP_S, motion=motion,
                             progressive_frames=f["progressive_frames"], preset=args.preset,
                             floor_fraction=floor_fraction, metric_workers=args.metric_workers,
                             hdrflip_frames=hdrflip_frames)
    denoised = {"on": True, "off": False}.get(args.denoised_levels, args.figures != "device" and not quick)
    rows, notes = [], [figures_note(args.figures, f, args.frames, floor_fraction, hdrflip_frames, denoised)]
    loaded = [load_scene_arg(spec) for spec in scenes]
    if len(loaded) > 1:
        notes.append("each scene's references were rendered while the scene before it was still being judged "
                     "(the GPU idles then; the same references, from the cache)")
    for n, scene in enumerate(loaded):
        view_set = make_views(scene, args.views, size)
        ref = cached_reference(scene, view_set, ref_settings, args.cache)
        following = loaded[n + 1] if n + 1 < len(loaded) else None
        runner = LocalRunner(before_wait=(lambda s=following: prefetch_references(s, args.views, size, ref_settings,
                                                                                  motion, args.cache))
                             if following is not None else None)
        configs = standard_configs(scene, ref_settings, denoised_levels=denoised)
        results, tuned = tuned_study(scene, view_set, ref, settings, configs, budgets, cache_dir=args.cache,
                                     runner=runner,
                                     option_sets=[{}] if quick else None)   # quick: the graph's own options
        notes.append(f"{scene.name}: reference {ref.verdict()}")
        study = results.study
        notes.append(f"{scene.name}: study {study['seconds']:.0f} s wall; images judged by "
                     + (f"{study['metric_workers']} worker processes ({study['metric_worker_s']:.0f} s of their time)"
                        if study.get("metric_workers") else "this process, one after the other"))
        notes += [f"{scene.name}: tuned for {b:g} ms (predicted {t.predicted_ms:.3g} ms, measured {t.measured_ms:.3g}): "
                  f"{effects_text({m: e.name for m, e in t.assignment.items()})}"
                  + (f" ({'; '.join(t.notes)})" if t.notes else "") for b, t in tuned.items()]
        if not args.no_save:
            folder = write_report(results, Path(args.out) / f"error_vs_time_{slug(scene.name)}", budget_ms=budgets[0],
                                  image_step=image_step)
            notes.append(f"{scene.name}: report {folder}")
        # each scene's table as soon as it is made (a later scene cut short by a timeout leaves this one)
        print(f"error_vs_time {scene.name}:\n{results.table()}", flush=True)
        for r in results.rows:
            floor = r.floor or {}
            rows.append([scene.name, r.name, f"{len(view_set)}x{size[0]}x{size[1]}", round(r.gpu_ms, 3),
                         *(stat_cell(r.errors[m]) for m in ("flip", "hdrflip", "psnr", "ssim", "relmse")),
                         stat_cell((r.motion or {}).get("flip")), _round(floor.get("relmse")),
                         "within noise" if floor.get("within_noise") else _round(floor.get("bias_relmse"))])
    notes.append(f"FLIP of the displayed image at {settings.pixels_per_degree():.1f} ppd ({args.preset}); "
                 f"mean ± std over {settings.frames} frames x {args.views} views; in motion: '{motion.trajectory}', "
                 f"frames {motion.sample_frames()}; floor = the configuration converged against the reference")
    return {"columns": ["scene", "config", "views x size", "GPU ms", "FLIP", "HDR-FLIP", "PSNR dB", "SSIM", "relMSE",
                        "FLIP in motion", "floor relMSE", "floor bias"], "rows": rows, "notes": notes}


def prefetch_references(scene, views: int, size, ref_settings, motion, cache_dir) -> None:
    """Render `scene`'s references (the static view's and one per judged trajectory frame) into
    the cache, as the study would (same views, seeds and settings), so that they are rendered
    while the GPU would otherwise wait for the previous scene's metrics."""
    from rayvr.study import cached_reference, make_views
    from rayvr.study.motion import trajectory_views
    from rayvr.xr.views import ViewSet

    view_set = make_views(scene, views, size)
    cached_reference(scene, view_set, ref_settings, cache_dir)
    frames = trajectory_views(view_set, motion)
    for k, i in enumerate(motion.sample_frames()):
        cached_reference(scene, ViewSet(frames[i]), ref_settings, cache_dir, sample=k + 1)


def figures_note(figures: str, f: dict, frames: int, floor_fraction: float, hdrflip_frames=None,
                 denoised: bool = False) -> str:
    """What this run computed, on how many frames (the table's statistics depend on it)."""
    ref = f"reference {f['reference_frames']} x {f['reference_spp']} spp"
    metrics = ("every metric (FLIP, HDR-FLIP, PSNR, SSIM, relMSE)" if hdrflip_frames is None else
               f"FLIP, PSNR, SSIM, relMSE on all, HDR-FLIP on the first {min(hdrflip_frames, frames)} (not in "
               f"motion, on the floors nor on the curves) of")
    return (f"figures '{figures}': {ref}; GPU ms over {f['timing_frames']} frames after {f['warmup']}; {metrics} "
            f"{frames} judged frames x every view; in motion "
            f"{f['motion_frames']} frames, judged at {f['motion_samples']}; floors at {floor_fraction:g} of the "
            f"reference's paths; progressive curves to {f['progressive_frames']} frames"
            + (" (reduced from the full run's defaults to fit one device call"
               + ("" if denoised else "; the hybrid levels through SVGF, with and without probe GI, left out: "
                                      "give them with --denoised-levels on") + ")"
               if figures == "device" else ""))


def _round(value, digits: int = 4):
    return "-" if value is None else float(f"{value:.{digits}g}")
