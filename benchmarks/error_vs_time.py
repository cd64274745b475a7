"""Image error against GPU time per configuration: all RASTER, all SHADOWS, SHADOWS + REFLECTIONS
(on the floor, or the material with the most area), PATH_TRACED at 1/4/16 spp, on a scene, stereo
2 x 1440x1600 by default. Error = FLIP (HDR), relMSE and PSNR (sRGB) of the composited radiance of
one frame against a converged path-traced reference (cached; see rayvr.tune.reference).
Writes the table (via the harness) and error_vs_time_<metric>.png beside the results.
`--quick`: the built-in Cornell box at 2 x 32x32, a short reference, for a smoke run on llvmpipe.
"""
from __future__ import annotations

from pathlib import Path

from ._timing import WARM_UP_S

DEFAULT_SCENE = str(Path(__file__).resolve().parents[2] / "shared" / "scenes" / "tauray" / "test.glb")


def add_arguments(parser) -> None:
    parser.add_argument("--scene", default=DEFAULT_SCENE, help="glTF path or built-in scene name")
    parser.add_argument("--size", default="1440x1600", help="per-view WIDTHxHEIGHT (quick: 32x32)")
    parser.add_argument("--views", type=int, default=2)
    parser.add_argument("--frames", type=int, default=50, help="timed frames per configuration (quick: 2)")
    parser.add_argument("--warmup", type=int, default=10, help="untimed frames first (quick: 1)")
    parser.add_argument("--reflect", default="auto", help="material that gets REFLECTIONS (auto: floor or largest)")
    parser.add_argument("--spp", default="1,4,16", help="PATH_TRACED samples per pixel, comma-separated")
    parser.add_argument("--reference-frames", type=int, default=256, help="frames of the reference (quick: 16)")
    parser.add_argument("--reference-spp", type=int, default=4, help="paths per pixel per reference frame")
    parser.add_argument("--cache", help="reference cache folder (default ~/.cache/rayvr/references)")
    parser.add_argument("--metrics", default="flip,relmse,psnr",
                        help="metrics, comma-separated (HDR-FLIP takes seconds of CPU per 1440x1600 view)")
    parser.add_argument("--ppd", type=float, help="display pixels per degree for FLIP (default 67)")


def run(args) -> dict:
    import rayvr as rv
    from rayvr.cli.options import load_scene_arg, parse_size
    from rayvr.cli.tune import parse_list, parse_spp

    quick = args.quick
    scene = load_scene_arg("cornell_box" if quick and args.scene == DEFAULT_SCENE else args.scene)
    size = (32, 32) if quick else parse_size(args.size)
    frames, warmup = (2, 1) if quick else (args.frames, args.warmup)
    settings = rv.tune.ReferenceSettings(16 if quick else args.reference_frames, args.reference_spp)
    spp = parse_list(args.spp, "--spp", parse_spp)
    metrics = parse_list(args.metrics, "--metrics", str.lower)
    configs = rv.tune.standard_configs(scene, reflect=args.reflect, spp=spp)
    results = rv.tune.measure(scene, configs, size=size, views=args.views, frames=frames, warmup=warmup,
                              reference_settings=settings, cache_dir=args.cache, ppd=args.ppd,
                              metrics=metrics, warmup_s=0.0 if quick else WARM_UP_S)
    notes = [(f"timing: {results.method}; error of one frame against {settings.frames} x {settings.spp} spp "
              f"path-traced reference ({results.info['reference']})")]
    if not args.no_save:
        for metric in results.metrics():
            path = results.plot(metric, Path(args.out) / f"error_vs_time_{metric}.png")
            notes.append(f"plot: {path}")
    digits = {"flip": 4, "relmse": 5, "psnr": 2}
    rows = [[r.name, f"{args.views}x{size[0]}x{size[1]}", round(r.frame_ms, 3),
             *(round(r.errors[m], digits[m]) if m in r.errors else "" for m in digits)] for r in results.rows]
    return {"columns": ["config", "views x size", "GPU ms", "FLIP", "relMSE", "PSNR dB"], "rows": rows,
            "notes": notes}
