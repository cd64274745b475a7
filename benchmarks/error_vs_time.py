"""Error against GPU time that can be trusted (rayvr.tune's study), with the tuner's assignment.

For each scene (default: tauray/test.glb and the built-in Cornell box), stereo 2 x 1440x1600 with
FLIP at the `index` preset's pixels per degree: a converged, checked reference, every standard
configuration (each effect level alone and mixed, PATH_TRACED at 1/4/16 spp, + TAA, and with a
denoiser or probe GI where the graphs have them) and the tuned assignment for each --budgets
(11.1 and 5.5 ms), each with its GPU ms, its error as mean ± std over frames and views, in
motion, and its bias floor. One table row per (scene, configuration); the full report of each
scene (report.md, report.html, results.json, plots, images) goes to OUT/error_vs_time_<scene>/.
`--quick`: the Cornell box alone at llvmpipe's study sizes (those of rayvr.tune.defaults: 2 x
32x32, a 64 x 16 spp reference), for a smoke run on llvmpipe; options given still win.
"""
from __future__ import annotations

from pathlib import Path

from ._study import add_figure_options, resolve_figures, stat_cell

DEFAULT_SCENES = [str(Path(__file__).resolve().parents[2] / "shared" / "scenes" / "tauray" / "test.glb"), "cornell_box"]


# option: (full run, --quick); an option given on the command line wins over both
FIGURES = {"size": ("1440x1600", "32x32"), "timing_frames": (50, 10), "warmup": (10, 2), "reference_frames": (256, 64),
           "reference_spp": (16, 16), "motion_frames": (32, 16), "motion_samples": (3, 2),
           "progressive_frames": (256, 16)}


def add_arguments(parser) -> None:
    parser.add_argument("--scenes", help="glTF paths or built-in names, comma-separated (default: tauray/test.glb "
                                         "and cornell_box; quick: cornell_box)")
    parser.add_argument("--views", type=int, default=2)
    parser.add_argument("--preset", default="index", help="headset whose pixels per degree FLIP uses")
    parser.add_argument("--budgets", default="11.1,5.5", help="tuner budgets in GPU ms, comma-separated")
    parser.add_argument("--frames", type=int, default=4, help="judged frames per configuration")
    add_figure_options(parser, FIGURES)
    parser.add_argument("--cache", help="reference cache folder (default ~/.cache/rayvr/references)")


def run(args) -> dict:
    from rayvr.cli.converge import parse_list
    from rayvr.cli.options import load_scene_arg, parse_size
    from rayvr.tune import Motion, ReferenceSettings, StudySettings, cached_reference, make_views, standard_configs
    from rayvr.tune import write_report
    from rayvr.tune.report import slug
    from rayvr.tune.results import effects_text
    from rayvr.tune.timing import GPU_WARM_UP_S
    from rayvr.tune.tuner import tuned_study
    from rayvr.xr.presets import get_preset

    quick = args.quick
    f = resolve_figures(args, FIGURES)
    scenes = parse_list(args.scenes, "--scenes", str) if args.scenes else (["cornell_box"] if quick else DEFAULT_SCENES)
    size = parse_size(f["size"])
    budgets = parse_list(args.budgets, "--budgets", float)
    ref_settings = ReferenceSettings(f["reference_frames"], f["reference_spp"])
    motion = Motion("turn", f["motion_frames"], f["motion_samples"], get_preset(args.preset).default_refresh)
    settings = StudySettings(frames=args.frames, timing_frames=f["timing_frames"], warmup=f["warmup"],
                             warmup_s=0.0 if quick else GPU_WARM_UP_S, motion=motion,
                             progressive_frames=f["progressive_frames"], preset=args.preset)
    rows, notes = [], []
    for spec in scenes:
        scene = load_scene_arg(spec)
        view_set = make_views(scene, args.views, size)
        ref = cached_reference(scene, view_set, ref_settings, args.cache)
        results, tuned = tuned_study(scene, view_set, ref, settings, standard_configs(scene, ref_settings), budgets,
                                     cache_dir=args.cache)
        notes.append(f"{scene.name}: reference {ref.verdict()}")
        notes += [f"{scene.name}: tuned for {b:g} ms (predicted {t.predicted_ms:.3g} ms, measured {t.measured_ms:.3g}): "
                  f"{effects_text({m: e.name for m, e in t.assignment.items()})}"
                  + (f" ({'; '.join(t.notes)})" if t.notes else "") for b, t in tuned.items()]
        if not args.no_save:
            folder = write_report(results, Path(args.out) / f"error_vs_time_{slug(scene.name)}", budget_ms=budgets[0])
            notes.append(f"{scene.name}: report {folder}")
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


def _round(value, digits: int = 4):
    return "-" if value is None else float(f"{value:.{digits}g}")
