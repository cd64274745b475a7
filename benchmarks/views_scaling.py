"""Views scaling (Tauray's figure 4): frame time of N views of 512x683 against one view with
the same total pixel count, for N = 1, 2, 4, ..., 64, through the hybrid graph.

Each N renders a camera grid from the scene's camera (rayvr.renderer.default_views) and a single
view scaled by sqrt(N) on both axes. Time per frame is wall time over `--frames` frames with the
GPU finished before and after (it includes the per-frame CPU work, which is what multi-view
rendering must keep flat), the fastest of `--repeats` such blocks: a busy host only ever adds to
a block's time. The GPU time per frame (timer queries, where the driver has them) is reported
beside it. Target: views overhead at 64 views <= 1.10x (Tauray: 1.26-1.29x on
Sponza). `--effects path_traced` sets every material's effect, for the path-traced rows.
"""
from __future__ import annotations

import math

from rayvr.cli.options import load_scene_arg, parse_size

from ._timing import wall_ms_per_frame

TARGET_RATIO_64 = 1.10


def add_arguments(parser) -> None:
    parser.add_argument("--scene", default="cornell_box",
                        help="glTF path or built-in scene name (default cornell_box); e.g. ../shared/scenes/...")
    parser.add_argument("--views", default="1,2,4,8,16,32,64", help="comma-separated view counts")
    parser.add_argument("--size", default="512x683", help="per-view WIDTHxHEIGHT (default 512x683)")
    parser.add_argument("--frames", type=int, default=30, help="timed frames per setting (quick: 3)")
    parser.add_argument("--warmup", type=int, default=5, help="untimed frames first (quick: 1)")
    parser.add_argument("--repeats", type=int, default=3, help="timed blocks of --frames; the fastest counts (quick: 1)")
    parser.add_argument("--effects", default="scene",
                        help="comma-separated: 'scene' (as authored) and/or an effect for every material "
                             "(raster, shadows, reflections, path_traced)")


def _measure(scene, view_set, frames: int, warmup: int, repeats: int) -> tuple[float, float | None]:
    """(wall ms per frame: the fastest of `repeats` blocks, GPU ms per frame or None)."""
    import rayvr as rv

    with rv.Renderer(scene, rv.graphs.hybrid(preset="raw"), views=view_set) as r:
        wall = min(wall_ms_per_frame(r, frames, warmup if k == 0 else 0) for k in range(repeats))
        return wall, (r.profile().total_ms if r.gpu.caps.timer_queries else None)


def _grid(n: int) -> tuple[int, int]:
    """cols x rows == n, as square as n allows (rows the largest divisor <= sqrt(n))."""
    rows = max(d for d in range(1, int(math.isqrt(n)) + 1) if n % d == 0)
    return n // rows, rows


def run(args) -> dict:
    from rayvr.materials.effect import Effect
    from rayvr.xr.cameras import default_views

    w, h = (64, 85) if args.quick and args.size == "512x683" else parse_size(args.size)
    counts = [int(v) for v in args.views.split(",")]
    if args.quick and args.views == "1,2,4,8,16,32,64":
        counts = [1, 2, 4, 8]
    frames, warmup = (3, 2) if args.quick else (args.frames, args.warmup)
    repeats = 1 if args.quick else max(1, args.repeats)
    rows = []
    for effects in args.effects.split(","):
        scene = load_scene_arg(args.scene)
        if effects != "scene":
            effect = Effect.parse(effects, where="--effects")
            for m in scene.materials:
                m.effect = effect
        for n in counts:
            multi = default_views(scene, views=n, size=(w, h), grid=_grid(n) if n > 2 else None)
            s = math.sqrt(n)
            single = default_views(scene, views=1, size=(round(w * s), round(h * s)))
            ms_multi, gpu_multi = _measure(scene, multi, frames, warmup, repeats)
            ms_single, gpu_single = _measure(scene, single, frames, warmup, repeats)
            ratio = ms_multi / ms_single
            sw, sh = single.size
            gpu = [round(gpu_multi, 3), round(gpu_single, 3), round(gpu_multi / gpu_single, 3)] \
                if gpu_multi and gpu_single else ["", "", ""]
            rows.append([effects, n, f"{w}x{h}", n * w * h, f"{sw}x{sh}", sw * sh, frames,
                         round(ms_multi, 3), round(ms_single, 3), round(ratio, 3), *gpu,
                         (("yes" if ratio <= TARGET_RATIO_64 else "NO") if n == 64 else "")])
    return {
        "columns": ["effects", "views", "view_size", "pixels", "single_size", "single_pixels", "frames",
                    "multi_ms", "single_ms", "ratio", "multi_gpu_ms", "single_gpu_ms", "gpu_ratio",
                    "meets_1.10_at_64"],
        "rows": rows,
        "notes": [f"scene {args.scene}; wall time per frame with the GPU finished around the timed frames, "
                  f"the fastest of {repeats} blocks of {frames} frames; ratio and the target use it",
                  "gpu: the graph's timer-query total per frame (mean over the last frames rendered)",
                  "single view scaled by sqrt(N) on both axes: pixel counts match to rounding"],
    }
