"""Sampler comparison: the error at equal samples per pixel of the path tracer's two samplers,
hash-based Owen-scrambled Sobol (Burley 2020, the default) and the PCG hash (independent samples),
on one scene (default the Cornell box, what `rayvr render` shows without a scene).

For each sampler and each spp in --spp, --seeds renders of ONE frame of that many paths per
pixel (a Sobol sequence's first spp points; each seed its own 2^16-frame range, so its own
scrambles and streams), each against a converged reference (--reference-frames frames of
--reference-spp paths, half rendered with each sampler, from the error study's reference frame
range): relMSE (rayvr.study.metrics.rel_mse, eps 1e-2) and HDR-FLIP of the linear radiance, mean
and std over the seeds, and the ratio PCG / Sobol of the mean relMSE (> 1: Sobol is better).
The reference's own relMSE (its two halves against each other, divided by 4: the error of
their mean) bounds what the table can resolve. The error at equal spp does not depend on the
GPU, so llvmpipe measures it as well as any.
"""
from __future__ import annotations

import numpy as np

from rayvr.cli.options import load_scene_arg, parse_size
from rayvr.study.metrics import flip, rel_mse

from ._study import stat_cell

COLUMNS = ["scene", "size", "bounces", "spp", "seeds", "relMSE sobol", "relMSE pcg", "pcg / sobol",
           "FLIP sobol", "FLIP pcg"]
SEED_FRAMES = 1 << 16      # glsl/sampling.glsl RAYVR_SOBOL_FRAMES_LOG2: a new scramble seed every 2^16 frames


def add_arguments(parser) -> None:
    parser.add_argument("--scene", default="cornell_box", help="glTF path or built-in scene name (default cornell_box)")
    parser.add_argument("--size", default="32x32", help="WIDTHxHEIGHT of the one view (default 32x32; quick 16x16)")
    parser.add_argument("--spp", default="1,4,16,64", help="comma-separated samples per pixel (default 1,4,16,64)")
    parser.add_argument("--seeds", type=int, default=16, help="renders per sampler and spp (default 16; quick 2)")
    parser.add_argument("--max-bounces", type=int, default=8, help="PathTracer max_bounces (default 8)")
    parser.add_argument("--reference-frames", type=int, default=64, help="reference frames (default 64; quick 4)")
    parser.add_argument("--reference-spp", type=int, default=64, help="reference paths per pixel per frame (default 64)")


def _mean_image(scene, views, sampler: str, spp: int, bounces: int, frames: int, first_frame: int) -> np.ndarray:
    """The path tracer's mean radiance (views, h, w, 3) float64 over `frames` frames from `first_frame`."""
    import rayvr as rv

    graph = rv.graphs.path_traced(samples_per_pixel=spp, max_bounces=bounces)
    graph.update_pass("PathTracer", {"sampler": sampler})
    with rv.Renderer(scene, graph, views=views, first_frame=first_frame, profiling=False) as r:
        for _ in range(frames):
            r.render()
        return r.read_output("Accumulate.dst")[..., :3].astype(np.float64)


def _flip_or_none(test, ref):
    try:
        return flip(test, ref, dynamic_range="hdr")
    except Exception:   # noqa: BLE001 - flip-evaluator missing: the table says '-'
        return None


def run(args) -> dict:
    from rayvr.cli.converge import parse_list
    from rayvr.study.seeds import reference_first_frame
    from rayvr.xr.cameras import default_views

    quick = args.quick
    size = (16, 16) if quick and args.size == "32x32" else parse_size(args.size)
    seeds = min(args.seeds, 2) if quick else args.seeds
    ref_frames = min(args.reference_frames, 4) if quick else args.reference_frames
    ref_frames += ref_frames % 2
    spps = parse_list(args.spp, "--spp", int)
    scene = load_scene_arg(args.scene)
    views = default_views(scene, views=1, size=size)
    bounces = args.max_bounces

    first = reference_first_frame()
    halves = [_mean_image(scene, views, s, args.reference_spp, bounces, ref_frames // 2, first + k * SEED_FRAMES)
              for k, s in enumerate(("sobol", "pcg"))]
    ref = 0.5 * (halves[0] + halves[1])
    ref_noise = rel_mse(halves[0], halves[1]) / 4

    rows = []
    for spp in spps:
        stats = {}
        for sampler in ("sobol", "pcg"):
            errs, flips = [], []
            for seed in range(seeds):
                img = _mean_image(scene, views, sampler, spp, bounces, 1, (seed + 1) * SEED_FRAMES)
                errs.append(rel_mse(img, ref))
                f = _flip_or_none(img, ref)
                if f is not None:
                    flips.append(f)
            stats[sampler] = ({"mean": float(np.mean(errs)), "std": float(np.std(errs))},
                              {"mean": float(np.mean(flips)), "std": float(np.std(flips))} if flips else None)
        ratio = stats["pcg"][0]["mean"] / max(stats["sobol"][0]["mean"], 1e-30)
        rows.append([scene.name, f"{size[0]}x{size[1]}", bounces, spp, seeds, stat_cell(stats["sobol"][0]),
                     stat_cell(stats["pcg"][0]), round(ratio, 3), stat_cell(stats["sobol"][1]), stat_cell(stats["pcg"][1])])
    notes = [f"reference: {ref_frames} frames x {args.reference_spp} spp ({ref_frames * args.reference_spp} paths per "
             f"pixel, half with each sampler); its own relMSE (halves / 4) {ref_noise:.3g}: errors near it are "
             f"the reference's",
             "one frame of spp paths per render; mean ± std over the seeds; relMSE eps 1e-2; HDR-FLIP of the "
             "linear radiance"]
    return {"columns": COLUMNS, "rows": rows, "notes": notes}
