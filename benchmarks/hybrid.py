"""The hybrid pipeline per pass: stereo 2 x 1440x1600 on a scene, for all-RASTER, all-SHADOWS and
SHADOWS + REFLECTIONS on the floor (or the material covering the most pixels), plus the G-buffer
drawn for both views in one multiview/layered pass against two single-view passes, and ray traced
for both views in one compute dispatch (GBufferRT). `--gbuffer` picks the hybrid rows' G-buffer.

Targets (H100): tauray/test.glb, SHADOWS everywhere + REFLECTIONS on >= 20% of the pixels,
<= 5.5 ms GPU per stereo frame; multiview G-buffer <= 0.7x two single-view passes.
`--quick` renders the built-in Cornell box at 2 x 64x64 for a smoke run on llvmpipe.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from rayvr.study.timing import timed_frames

from ._timing import warm_up

DEFAULT_SCENE = str(Path(__file__).resolve().parents[2] / "shared" / "scenes" / "tauray" / "test.glb")
TARGET_FRAME_MS = 5.5
TARGET_GBUFFER_RATIO = 0.7


def add_arguments(parser) -> None:
    parser.add_argument("--scene", default=DEFAULT_SCENE, help="glTF path or built-in scene name")
    parser.add_argument("--size", default="1440x1600", help="per-view WIDTHxHEIGHT (quick: 64x64)")
    parser.add_argument("--views", type=int, default=2)
    parser.add_argument("--frames", type=int, default=50, help="timed frames per configuration (quick: 2)")
    parser.add_argument("--warmup", type=int, default=10, help="untimed frames first (quick: 1)")
    parser.add_argument("--reflect", default="auto",
                        help="material that gets REFLECTIONS: a name, or 'auto' (a floor, else the most pixels)")
    parser.add_argument("--light-samples", type=int, default=1)
    parser.add_argument("--gbuffer", default="auto", choices=("auto", "raster", "rt"),
                        help="G-buffer of the hybrid rows: raster, ray-traced, or auto (rt on weak-raster GPUs)")


def _reflective_material(scene, renderer, choice: str) -> str:
    names = [m.name for m in scene.materials]
    if choice != "auto":
        return choice
    floors = [n for n in names if "floor" in n.lower()]
    if floors:
        return floors[0]
    ids = renderer.read_output("GBuffer.effect")[..., 0]
    ids = ids[(ids & 0xFF) != 0xFF] >> 8
    return names[int(np.bincount(ids).argmax())] if ids.size else names[0]


def _time(renderer, frames: int, warmup: int) -> tuple[dict, str]:
    """Per-pass mean GPU ms over `frames` timed frames (after the clock warm-up and `warmup`
    untimed frames), and the timing method."""
    if frames > 5:          # not for smoke runs
        warm_up(renderer)
    timing = timed_frames(renderer, frames, warmup)
    return timing.pass_ms, timing.method


def run(args) -> dict:
    import rayvr as rv
    from rayvr.cli.options import load_scene_arg, parse_size
    from rayvr.renderer import Renderer
    from rayvr.xr.cameras import default_views

    quick = args.quick
    scene = load_scene_arg("cornell_box" if quick and args.scene == DEFAULT_SCENE else args.scene)
    size = (64, 64) if quick else parse_size(args.size)
    frames, warmup = (2, 1) if quick else (args.frames, args.warmup)
    views = default_views(scene, args.views, size)
    pixels = size[0] * size[1] * args.views

    rows, notes = [], []
    passes = ["GBuffer", "Direct", "Compaction", "Shadows", "Reflections", "Composite", "ToneMap"]
    reflect_name = None
    method = "?"
    gbuffer_choice = "?"
    for label in ("all RASTER", "all SHADOWS", "SHADOWS + REFLECTIONS"):
        for m in scene.materials:
            m.effect = rv.Effect.RASTER if label == "all RASTER" else rv.Effect.SHADOWS
        g = rv.graphs.hybrid(preset="raw", light_samples=args.light_samples, gbuffer=args.gbuffer)
        g.mark_output("GBuffer.effect")   # counts the reflective pixels (a marked compaction list would keep it running)
        if label.endswith("REFLECTIONS"):
            probe_graph = rv.graphs.hybrid(preset="raw")
            probe_graph.mark_output("GBuffer.effect")
            with Renderer(scene, probe_graph, views=views) as probe:
                probe.render()
                reflect_name = _reflective_material(scene, probe, args.reflect)
            scene.materials[reflect_name].effect = rv.Effect.REFLECTIONS
        with Renderer(scene, g, views=views) as r:
            times, method = _time(r, frames, warmup)
            gb_pass = r.compiled.passes["GBuffer"]
            gbuffer_choice = f"{type(gb_pass.impl).__name__} ({gb_pass.why})"
            effect = r.read_output("GBuffer.effect")[..., 0] & 0xFF   # gbuffer.glsl: the effect in the low byte
            refl = int(((effect >= int(rv.Effect.REFLECTIONS)) & (effect != 0xFF)).sum())
        total = sum(times.values())
        rows.append([label, f"{args.views}x{size[0]}x{size[1]}", round(100.0 * refl / pixels, 1),
                     *[round(times[p], 3) if p in times else "pruned" for p in passes], round(total, 3)])
    if reflect_name:
        notes.append(f"REFLECTIONS on material '{reflect_name}'")
    notes.append(f"hybrid rows: GBuffer = {gbuffer_choice}")
    notes.append(f"timing: {method}; frame target {TARGET_FRAME_MS} ms (SHADOWS + REFLECTIONS on >= 20% px)")

    # G-buffer: every view in one pass vs one pass per view.
    for m in scene.materials:
        m.effect = rv.Effect.RASTER
    gb = {}
    for label, n, make in (("one pass, all views", args.views, rv.passes.GBufferRaster),
                           ("one view", 1, rv.passes.GBufferRaster),
                           ("ray traced, all views", args.views, rv.passes.GBufferRT)):
        g = rv.RenderGraph("GBufferOnly")
        g.add_pass(make(), "GBuffer")
        g.mark_output("GBuffer.posW")
        vs = views if n == args.views else rv.xr.ViewSet([views[0]])
        with Renderer(scene, g, views=vs) as r:
            times, _ = _time(r, frames, warmup)
            gb[label] = times["GBuffer"]
            if make is rv.passes.GBufferRaster:
                mode = "multiview" if r.compiled.passes["GBuffer"]._multiview else "layered"
    ratio = gb["one pass, all views"] / (args.views * gb["one view"])
    shape = f"{args.views}x{size[0]}x{size[1]}"
    for label, ms in ((f"G-buffer {mode}, {args.views} views in one pass", gb["one pass, all views"]),
                      (f"G-buffer {args.views} single-view passes", args.views * gb["one view"]),
                      (f"G-buffer ray traced (GBufferRT), {args.views} views in one dispatch",
                       gb["ray traced, all views"])):
        rows.append([label, shape, "", round(ms, 3), *[""] * (len(passes) - 1), round(ms, 3)])
    notes.append(f"G-buffer one pass / {args.views} passes = {ratio:.3f} (target <= {TARGET_GBUFFER_RATIO})")
    notes.append(f"G-buffer ray traced / raster one pass = "
                 f"{gb['ray traced, all views'] / gb['one pass, all views']:.3f}")
    return {"columns": ["config", "views x size", "reflection px %", *[f"{p} ms" for p in passes], "total ms"],
            "rows": rows, "notes": notes}
