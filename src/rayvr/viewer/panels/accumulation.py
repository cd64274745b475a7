"""Accumulation section: progressive rendering to a target sample count or time (Lift's
statistics): frames in the running mean, samples per pixel, time since the view last changed.
Once a target is reached the viewer stops rendering and shows the converged frame; moving the
camera or changing the scene starts again."""
from __future__ import annotations

from ...passes.path_tracer import PathTracer


def draw(v, state) -> None:
    from imgui_bundle import imgui

    frames, seconds = v.accumulated()
    spp = [p.samples_per_pixel for p in v.renderer.compiled.passes.values() if isinstance(p, PathTracer)]
    imgui.text(f"frames {frames}" + (f"  ({frames * max(spp)} samples/pixel)" if spp else "")
               + f"  {seconds:.2f} s")
    if not spp:
        imgui.text_disabled("no path tracer runs (no PATH_TRACED material in a hybrid graph)")
    changed, target = imgui.input_int("target frames (0: none)", v.target_frames, 1, 16)
    if changed:
        v.target_frames = max(0, target)
    changed, target_s = imgui.input_float("target seconds (0: none)", v.target_seconds, 1.0, 10.0, "%.1f")
    if changed:
        v.target_seconds = max(0.0, target_s)
    if (v.target_frames or v.target_seconds) and not v.rendered:
        imgui.text_colored(imgui.ImVec4(0.6, 0.9, 0.6, 1.0), "converged: rendering paused")
