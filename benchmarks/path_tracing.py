"""Path tracing throughput: ms per frame and path samples per second of the path_traced() graph
(PathTracer -> Accumulate -> ToneMap) at given samples per pixel, for 1 and 2 views.

Time per frame is wall time over `--frames` frames with the GPU finished before and after; the
PathTracer pass's own mean time comes from the graph profile (timer queries where the driver has
them). samples/s = views x pixels x spp / PathTracer time. With `--reference-frames N` each row
also gets the relMSE of one frame against an N-frame mean at the highest spp, and relMSE x ms
(lower is better: the error at equal time, since relMSE falls like 1/time).
"""
from __future__ import annotations

from rayvr.cli.options import load_scene_arg, parse_size
from rayvr.study.metrics import rel_mse

from ._timing import wall_ms_per_frame


def add_arguments(parser) -> None:
    parser.add_argument("--scene", default="cornell_box",
                        help="glTF path or built-in scene name (default cornell_box); e.g. ../shared/scenes/...")
    parser.add_argument("--size", default="512x512", help="per-view WIDTHxHEIGHT (default 512x512; quick 32x32)")
    parser.add_argument("--spp", default="1,4", help="comma-separated samples per pixel per frame")
    parser.add_argument("--views", default="1,2", help="comma-separated view counts (2 = stereo)")
    parser.add_argument("--max-bounces", type=int, default=4, help="PathTracer max_bounces (default 4)")
    parser.add_argument("--frames", type=int, default=20, help="timed frames per setting (quick: 2)")
    parser.add_argument("--warmup", type=int, default=3, help="untimed frames first (quick: 1)")
    parser.add_argument("--reference-frames", type=int, default=0,
                        help="frames of the reference for relMSE (0: no relMSE; quick: 8 if given)")


def _renderer(scene, spp: int, views: int, size, max_bounces: int):
    import rayvr as rv
    from rayvr.graphs import path_traced
    from rayvr.xr.cameras import default_views

    graph = path_traced(samples_per_pixel=spp, max_bounces=max_bounces)
    return rv.Renderer(scene, graph, views=default_views(scene, views=views, size=size))


def run(args) -> dict:
    size = (32, 32) if args.quick and args.size == "512x512" else parse_size(args.size)
    frames, warmup = (2, 1) if args.quick else (args.frames, args.warmup)
    spps = [int(v) for v in args.spp.split(",")]
    view_counts = [int(v) for v in args.views.split(",")]
    ref_frames = min(args.reference_frames, 8) if args.quick else args.reference_frames
    scene = load_scene_arg(args.scene)
    references = {}
    if ref_frames:
        for n in view_counts:
            with _renderer(scene, max(spps), n, size, args.max_bounces) as r:
                r.frame_index = 1 << 20   # seeds apart from the measured frames: an independent reference
                for _ in range(ref_frames):
                    r.render()
                references[n] = r.read_output("Accumulate.dst")
    rows = []
    for n in view_counts:
        for spp in spps:
            with _renderer(scene, spp, n, size, args.max_bounces) as r:
                frame_ms = wall_ms_per_frame(r, frames, warmup)
                prof = r.profile()
                stats = prof.passes.get("PathTracer")
                pt_ms = stats.mean_ms if stats is not None else frame_ms
                samples = n * size[0] * size[1] * spp
                row = [n, f"{size[0]}x{size[1]}", spp, args.max_bounces, frames, round(frame_ms, 3),
                       round(pt_ms, 3), round(samples / (pt_ms / 1e3) / 1e6, 3), prof.method]
                if ref_frames:
                    # one frame's estimate: the PathTracer output after a fresh frame
                    r.compiled.passes["Accumulate"].reset()
                    r.render()
                    err = rel_mse(r.read_output("Accumulate.dst"), references[n])
                    row += [round(err, 5), round(err * pt_ms, 5)]
                rows.append(row)
    columns = ["views", "view_size", "spp", "max_bounces", "frames", "frame_ms", "pathtracer_ms",
               "Msamples_per_s", "timing"]
    if ref_frames:
        columns += ["relMSE_1frame", "relMSE_x_ms"]
    notes = [f"scene {args.scene}; wall time per frame with the GPU finished around the timed frames",
             "Msamples_per_s: camera paths (views x pixels x spp) per second of PathTracer time"]
    if ref_frames:
        notes.append(f"relMSE against a {ref_frames}-frame mean at {max(spps)} spp (same views)")
    return {"columns": columns, "rows": rows, "notes": notes}
