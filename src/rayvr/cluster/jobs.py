"""The jobs a Cluster runs on frames: one frame split by views and a sequence split by frames
(the error study's jobs, a reference split by samples and configurations split over the
workers, are in rayvr.cluster.study).

Every job takes `cluster=` (a rayvr.cluster.Cluster) or makes one from `workers=`/`address=`
for its own duration. `scene` is a Scene, a glTF path or a built-in name; `payload=` (a
ScenePayload) says how it travels when that differs (the CLI sends the glTF file's bytes).

Seeds: every random stream in rayvr's passes follows (pixel, the view's index in the whole
frame, frame index, salt) (glsl/sampling.glsl): a view share renders its views with their
global indices (PinnedViews), a sequence's frame i renders frame index `frame_index_base + i`.
"""
from __future__ import annotations

import dataclasses
import math
import time

import numpy as np

from ..errors import OptionError
from . import pool
from .payload import ScenePayload
from .shares import Share, split_evenly, view_range

SHARES_PER_WORKER = 4          # sample and sequence shares per worker: balance and cheap re-runs


def _scene_and_payload(scene, payload):
    """(driver-side Scene, ScenePayload)."""
    if isinstance(scene, ScenePayload):
        payload = payload or scene
        scene = scene.load()
    elif isinstance(scene, (str, type(None))) or hasattr(scene, "__fspath__"):
        payload = payload or ScenePayload.of(scene)
        scene = payload.load()
    return scene, payload or ScenePayload.from_scene(scene)


def _graph_for(graph, pins) -> tuple[dict, list[str]]:
    """The graph as a dict with only `pins` marked (the other outputs' passes are pruned)."""
    from ..rendergraph.graph import RenderGraph

    g = RenderGraph.from_dict(graph.to_dict())
    pins = list(pins) if pins else list(g.outputs[:1])
    for pin in pins:
        if pin not in g.outputs:
            g.mark_output(pin)
    for out in list(g.outputs):
        if out not in pins:
            g.unmark_output(out)
    return g.to_dict(), pins


# -- one frame split by views ------------------------------------------------------------------
@dataclasses.dataclass
class ViewsResult:
    """`pixels`: {pin: (views, h, w, c)} in view order (rows top-down unless flip_y was off);
    `shares`: per share its first view, view count, worker, ms per frame, readback ms, profile."""

    pixels: dict
    shares: list
    seconds: float


def render_views(scene, graph, views, pins=None, frames: int = 1, frame_index: int = 0, cluster=None,
                 workers=None, address=None, shares: int | None = None, flip_y: bool = True,
                 profiling: bool = False, payload=None, progress: bool = True) -> ViewsResult:
    """Render `graph` over the ViewSet `views` split into contiguous view ranges (default one
    per worker), `frames` frames each, and stitch `pins` (default the graph's first output).

    A view's pixels equal one process's: each share renders its views as layers 0..k-1, but the
    passes seed random numbers by the view's index in the whole frame (PinnedViews'
    first_view_index, views.glsl view_global_index). Nothing may couple views: auto exposure
    over the frame belongs after the gather (rayvr.cluster.gather.tone_map)."""
    from ..xr.views import ViewSet

    if not isinstance(views, ViewSet):
        raise OptionError("render_views: views must be a rayvr.xr.ViewSet (e.g. rayvr.renderer.default_views)")
    scene, payload = _scene_and_payload(scene, payload)
    graph_dict, pins = _graph_for(graph, pins)
    out: dict = {}
    info: list = []
    t0 = time.perf_counter()

    def gather(share, result):
        first = share.meta["first_view"]
        for pin, a in result["pixels"].items():
            if pin not in out:
                out[pin] = np.empty((len(views),) + a.shape[1:], a.dtype)
            out[pin][first:first + a.shape[0]] = a
        info.append({"first_view": first, **{k: v for k, v in result.items() if k != "pixels"}})

    with pool.using(cluster, workers, address) as c:
        jobs = []
        for i, (a, b) in enumerate(split_evenly(len(views), shares or c.size)):
            kwargs = {"graph": graph_dict, "views": view_range(views, a, b), "pins": pins, "frames": int(frames),
                      "frame_index": int(frame_index), "flip_y": flip_y,
                      "profiling": profiling}
            jobs.append(Share(i, "views", kwargs, work=(b - a) * int(frames), meta={"first_view": a}))
        c.run(jobs, c.scene_ref(payload), on_result=gather, desc=f"views {scene.name}", unit="view",
              progress=progress)
    info.sort(key=lambda d: d["first_view"])
    return ViewsResult(out, info, time.perf_counter() - t0)


# -- a sequence split by frames ----------------------------------------------------------------
@dataclasses.dataclass
class SequenceResult:
    """`frames`: {pin: (frames, views, h, w, c)} when kept; `chunks`: per chunk its first frame,
    count, frames rendered (with warm-up), seconds and worker."""

    frames: dict
    chunks: list
    seconds: float

    @property
    def fps(self) -> float:
        n = sum(c["count"] for c in self.chunks)
        return n / self.seconds if self.seconds > 0 else math.inf


def render_sequence(scene, graph, sequence, pins=None, chunk: int | None = None, warmup: int = 0,
                    on_frame=None, keep: bool = True, frame_index_base: int = 0, cluster=None, workers=None,
                    address=None, payload=None, progress: bool = True) -> SequenceResult:
    """Render `sequence` (rayvr.cluster.TrajectoryViews) with `graph` in chunks of contiguous
    frames (default: 4 chunks per worker) and deliver `pins` (None: the first output; empty:
    none, for timing) per frame, in frame order, to `on_frame(index, {pin: array})` and/or keep
    them. Frame i renders with frame index `frame_index_base + i`, as one process would.
    History: each chunk starts without it; `warmup` frames before a chunk's first are rendered
    for history only. Graphs without temporal passes give one process's frames exactly (with
    warmup >= 1 motion vectors too); TAA's exponential history only approaches them."""
    scene, payload = _scene_and_payload(scene, payload)
    no_pins = pins is not None and len(pins) == 0
    graph_dict, pins = (graph.to_dict(), []) if no_pins else _graph_for(graph, pins)
    frames = int(sequence.frames)
    kept: dict = {pin: [None] * frames for pin in pins} if keep else {}
    chunks: list = []
    waiting: dict = {}
    state = {"next": 0}

    def deliver(share, result):
        chunks.append({k: v for k, v in result.items() if k != "pixels"})
        waiting[result["first"]] = result
        while state["next"] in waiting:
            r = waiting.pop(state["next"])
            for k in range(r["count"]):
                frame = {pin: r["pixels"][pin][k] for pin in pins}
                if keep:
                    for pin in pins:
                        kept[pin][r["first"] + k] = frame[pin]
                if on_frame is not None:
                    on_frame(r["first"] + k, frame)
            state["next"] = r["first"] + r["count"]

    t0 = time.perf_counter()
    with pool.using(cluster, workers, address) as c:
        ranges = split_evenly(frames, max(1, frames // int(chunk)) if chunk else SHARES_PER_WORKER * c.size)
        jobs = [Share(i, "frames", {"graph": graph_dict, "sequence": sequence, "first": a, "count": b - a,
                                    "warmup": int(warmup), "pins": pins, "frame_index_base": int(frame_index_base)},
                      work=b - a) for i, (a, b) in enumerate(ranges)]
        c.run(jobs, c.scene_ref(payload), on_result=deliver, desc=f"sequence {scene.name}", unit="frame",
              progress=progress)
    chunks.sort(key=lambda d: d["first"])
    stacked = {pin: np.stack(v) for pin, v in kept.items()} if keep and pins else {}
    return SequenceResult(stacked, chunks, time.perf_counter() - t0)
