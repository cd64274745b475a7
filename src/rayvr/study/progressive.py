"""Means over many frames, read at chosen frame counts: the converged renders of the error study
(references, bias floors) and the progressive-convergence curve.

`render_mean` renders a graph for a number of frames from a given first frame (its seed range,
rayvr.study.seeds) and returns the running mean of one output at the frame counts asked for, with
the wall seconds spent rendering up to each (the GPU finished; readbacks not counted). The mean
is an Accumulate pass: the graph's own when the output already is an unlimited Accumulate's,
else one added after the output ("StudyMean"), the graph's own Accumulate passes then passing
each frame through, so that the mean is over independent frames.
"""
from __future__ import annotations

import dataclasses
import time

import numpy as np

from ..errors import OptionError
from . import seeds

MEAN_PASS = "StudyMean"


@dataclasses.dataclass
class Snapshot:
    """The running mean after `frames` frames and the wall seconds spent rendering them."""

    frames: int
    image: np.ndarray      # (views, h, w, 4) float32 linear radiance, row 0 at the top
    wall_s: float


def accumulate_passes(graph) -> list[str]:
    """The graph's Accumulate passes, by name."""
    return [n for n, p in graph.passes.items() if type(p).__name__ == "Accumulate"]


def mean_output(graph, pin: str) -> str:
    """The pin holding the running mean of `pin` over frames, adding an Accumulate after `pin`
    (and making the graph's own pass each frame through) when `pin` is not already one."""
    from ..passes import Accumulate

    name, _, field = pin.partition(".")
    own = graph.passes.get(name)
    if type(own).__name__ == "Accumulate" and field == Accumulate.DST and own.max_frames == 0 and own.enabled:
        return pin
    for acc in accumulate_passes(graph):
        graph.update_pass(acc, {"enabled": False})
    graph.add_pass(Accumulate(), MEAN_PASS)
    graph.add_edge(pin, f"{MEAN_PASS}.{Accumulate.SRC}")
    graph.mark_output(f"{MEAN_PASS}.{Accumulate.DST}")
    return f"{MEAN_PASS}.{Accumulate.DST}"


def render_mean(scene, graph, pin: str, view_set, frames: int, first_frame: int, snapshots=(), gpu=None,
                tick=None) -> list[Snapshot]:
    """The mean of `pin` over `frames` frames from `first_frame`, read after each frame count in
    `snapshots` and after the last frame (sorted, one Snapshot each). `tick(frames_done)` is
    called after every frame (progress)."""
    from ..renderer import Renderer

    if frames < 1:
        raise OptionError(f"render_mean: frames must be >= 1, got {frames}")
    seeds.check_length(frames, f"mean of {pin}")
    counts = sorted({int(n) for n in snapshots if 1 <= int(n) <= frames} | {int(frames)})
    mean_pin = mean_output(graph, pin)
    with Renderer(scene, graph, views=view_set, gpu=gpu, profiling=False, first_frame=first_frame) as r:
        return list(read_after(r, mean_pin, counts, tick))


def read_after(renderer, pin: str, counts, tick=None):
    """Render on, yielding a Snapshot of `pin` after each of the (increasing) frame `counts`;
    its wall seconds count the rendering only (the GPU finished before each reading). Each frame
    is finished before the next is submitted: a reference's 32 frames of 16 spp at 2x1440x1600
    (~19 s of GPU work) queued between two readings have left the running mean as it was at the
    first (its halves came out identical), where a reading every 4 frames did not."""
    wall, done = 0.0, 0
    renderer.gl.finish()
    for count in counts:
        t0 = time.perf_counter()
        for _ in range(count - done):
            renderer.render()
            renderer.gl.finish()
            done += 1
            if tick is not None:
                tick(done)
        renderer.gl.finish()
        wall += time.perf_counter() - t0
        yield Snapshot(count, renderer.read_output(pin, flip_y=True).astype(np.float32), wall)


def split_halves(first_half: np.ndarray, whole: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(half A, half B) from the mean of the first half of the frames and the mean of all of them
    (equal halves: B = 2 whole - A)."""
    a = first_half.astype(np.float32)
    # Rounding can leave -1e-8 where B's pixel is black; radiance is never negative.
    return a, np.maximum(2.0 * whole.astype(np.float64) - a, 0.0).astype(np.float32)


def snapshot_counts(frames: int) -> list[int]:
    """1, 2, 4, ... up to and including `frames`: where a progressive curve is read."""
    out, k = [], 1
    while k < frames:
        out.append(k)
        k *= 2
    return out + [int(frames)]


def hdr_output(graph) -> str:
    """The graph's linear-radiance output: the last marked output that is not the tone mapper's."""
    outs = [o for o in graph.outputs if not o.startswith("ToneMap.")]
    if not outs:
        raise OptionError(f"graph '{graph.name}' marks no linear-radiance output; mark one (e.g. Accumulate.dst)")
    return outs[-1]


def progressive_curve(scene, name: str, graph, settings: dict, view_set, frames: int, reference, judge,
                      timing_frames: int, warmup: int, warmup_s: float, first_frame: int, gpu=None, tick=None,
                      step=None, later: bool = False, quiet=None):
    """Error against accumulated time of a progressive render (Lift's figure): the graph's HDR
    output read after 1, 2, 4, ... `frames` frames and judged by `judge(image, reference_image,
    name)` (-> per-view metrics first, or a rayvr.study.pool.Pending of them). Wall seconds are
    measured (GPU finished, readback and metrics not counted); GPU seconds are frames x the GPU
    ms per frame timed first (`timing_frames` after the warm-up), after which the accumulation
    and every history (TAA, SVGF) restart. `step(kind, units, label)`: a progress step around the
    renderer's setup ("setup", 1) and each stretch of rendering ("render", frames). `later`:
    return the function that waits for the judgements and gives the Curve (the caller renders
    on meanwhile) instead of the Curve. `quiet`: held around the timing (timed_frames)."""
    import contextlib

    from ..renderer import Renderer
    from .results import Curve
    from .timing import timed_frames

    step = step or (lambda kind, units, label: contextlib.nullcontext(lambda fraction: None))
    pin = hdr_output(graph)
    counts = snapshot_counts(frames)
    shots = []
    with step("setup", 1, name):
        r = Renderer(scene, graph, views=view_set, gpu=gpu, first_frame=first_frame)
    with r:
        with step("render", warmup + timing_frames, name):
            timing = timed_frames(r, timing_frames, warmup, warmup_s, quiet)
        for p in r.compiled.passes.values():
            if hasattr(p, "reset"):   # Accumulate, and the history of TAA and SVGF
                p.reset()
        readings, done = read_after(r, pin, counts, tick), 0
        for count in counts:
            with step("render", count - done, name):
                shot = next(readings)
            done = count
            shots.append((shot, judge(shot.image, reference.image, f"{name} after {shot.frames} frames")))

    def finish():
        points = []
        for shot, judged in shots:
            per_view = (judged.get() if hasattr(judged, "get") else judged)[0]
            points.append({"frames": shot.frames, "wall_s": shot.wall_s, "gpu_s": shot.frames * timing.frame_ms / 1e3,
                           **{m: float(np.mean(v)) for m, v in per_view.items()}})
        return Curve(name, {"graph": "path_traced", "output": pin, **settings}, timing.frame_ms, points)

    return finish if later else finish()
