"""The viewer's frame loop, offscreen: ms per frame of a stereo hybrid frame with and without the UI.

There is no display on the GPU machine, so the viewer runs on an OffscreenSurface: a framebuffer
of the window's size (the views side by side) on rayvr's headless EGL context, driven by the same
`Viewer.step()` as a window: input, camera, `Renderer.render`, `FrameDisplay.draw`, the ImGui
panels through imgui-bundle's OpenGL 3 backend, present (a no-op offscreen; a window's swap is
not timed). One viewer, after warm-up frames, alternates blocks of frames with the panels hidden
and shown (so drifting clocks and a shared CPU weigh on both alike):
- frame ms: the median wall time of a frame, the GPU finished after each frame;
- phase ms: further frames with the GPU finished after each phase (Viewer.sync_phases), so
  render, display and UI each include their GPU work; `ui_ms` is the UI's own cost.
The panels are drawn as a user first sees them (the Timing section open, its live plot).
Target: 2x1440x1600 hybrid + UI within 11.1 ms (90 Hz) on the GPU machine's class of GPU.
"""
from __future__ import annotations

import time

import numpy as np

from rayvr.cli.options import load_scene_arg, parse_size

BUDGET_MS = 11.1


def add_arguments(parser) -> None:
    parser.add_argument("--scene", default="cornell_box", help="glTF path or built-in scene (default cornell_box)")
    parser.add_argument("--size", default="1440x1600", help="per-view WIDTHxHEIGHT (default 1440x1600; quick 256x256)")
    parser.add_argument("--views", type=int, default=2, choices=(1, 2), help="1 or 2 views (default 2)")
    parser.add_argument("--frames", type=int, default=200, help="timed frames per setting (quick: 30)")
    parser.add_argument("--warmup", type=int, default=20, help="untimed frames first (quick: 3)")


def measure(scene, size, views: int, frames: int, warmup: int, block: int = 2) -> dict:
    """{False: ..., True: ...}: frame ms and per-phase ms of the viewer loop, panels hidden / shown."""
    from rayvr.graphs import hybrid
    from rayvr.viewer.app import Viewer
    from rayvr.viewer.offscreen import OffscreenSurface

    surface = OffscreenSurface((size[0] * views, size[1]))
    frame_ms = {False: [], True: []}
    phases = {False: [], True: []}
    with Viewer(scene, hybrid(preset="raw"), views=views, size=size, surface=surface, dt=1 / 90) as viewer:
        gl = viewer.gpu.gl
        viewer.run(warmup)
        gl.finish()
        for sync in (False, True):
            viewer.sync_phases = sync
            for i in range(2 * frames):
                viewer.show_ui = ui = (i // block) % 2 == 1
                t0 = time.perf_counter()
                viewer.step()
                gl.finish()
                (phases if sync else frame_ms)[ui].append(dict(viewer.phase_ms) if sync
                                                          else (time.perf_counter() - t0) * 1e3)
        method = viewer.renderer.profile().method
    out = {}
    for ui in (False, True):
        mean = {k: float(np.median([p[k] for p in phases[ui]])) for k in ("render", "display", "ui")}
        out[ui] = {"frame_ms": float(np.median(frame_ms[ui])), **{f"{k}_ms": v for k, v in mean.items()},
                   "method": method}
    return out


def run(args) -> dict:
    size = (256, 256) if args.quick and args.size == "1440x1600" else parse_size(args.size)
    frames, warmup = (30, 3) if args.quick else (args.frames, args.warmup)
    scene = load_scene_arg(args.scene)
    rows = []
    results = measure(scene, size, args.views, frames, warmup)
    for ui in (False, True):
        r = results[ui]
        rows.append([scene.name, f"{args.views}x{size[0]}x{size[1]}", "on" if ui else "off", frames,
                     round(r["frame_ms"], 3), round(r["render_ms"], 3), round(r["display_ms"], 3),
                     round(r["ui_ms"], 3), r["method"], BUDGET_MS,
                     "yes" if r["frame_ms"] <= BUDGET_MS else "NO"])
    ui_cost = results[True]["frame_ms"] - results[False]["frame_ms"]
    return {
        "columns": ["scene", "views", "ui", "frames", "frame_ms", "render_ms", "display_ms", "ui_ms",
                    "graph_timing", "budget_ms", "meets"],
        "rows": rows,
        "notes": [f"UI cost: {ui_cost:.3f} ms per frame (median frame ms with the panels minus without); "
                  f"the UI phase alone {results[True]['ui_ms']:.3f} ms (median)",
                  "offscreen: the same Viewer.step() as a window, on a window-sized framebuffer of the "
                  "headless context; a window's buffer swap is not included",
                  "frame ms finish the GPU once a frame; phase ms after each phase; medians over alternating blocks of 2 frames"],
    }
