"""The jobs a Cluster runs: a reference split by samples, a frame split by views, a sequence
split by frames, and the error-against-time study split by configurations.

Every job takes `cluster=` (a rayvr.cluster.Cluster) or makes one from `workers=`/`address=`
for its own duration. `scene` is a Scene, a glTF path or a built-in name; `payload=` (a
ScenePayload) says how it travels when that differs (the CLI sends the glTF file's bytes).

Seeds: every random stream in rayvr's passes follows the frame index (glsl/sampling.glsl:
pixel, view layer, frame index, salt). A reference's frames are numbered from `seed << 20`, so
its shares are independent streams and the merged mean uses the same paths as one process
rendering frames 0..N-1 (seed 0): the same image up to float rounding, and bit for bit the
same on a re-run with the same seed (the shares are merged in their order).
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

SEED_STRIDE = 1 << 20          # frame indices per reference seed
VIEW_STREAM_STRIDE = 1 << 16   # frame-index offset per view of a view share's first view (a
#                                multiple of the TAA jitter sequence: jitter is unchanged)
SHARES_PER_WORKER = 4          # reference and sequence shares per worker: balance and cheap re-runs


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


# -- (a) reference split by samples ------------------------------------------------------------
@dataclasses.dataclass
class Reference:
    """A converged render: `image` (views, h, w, 4) float32 linear radiance, row 0 at the top,
    the mean of `frames` x `spp` paths per pixel; `stderr` the standard error of each pixel's
    mean from the shares' means (batch means; None with one share)."""

    image: np.ndarray
    frames: int
    spp: int
    seed: int
    stderr: np.ndarray | None
    shares: int
    seconds: float
    workers: list

    @property
    def samples_per_pixel(self) -> int:
        return self.frames * self.spp


class _OrderedMean:
    """Folds (mean, count) results in share order, whatever order they arrive in, so that the
    float64 sums are the same on every run."""

    def __init__(self):
        self.sum = self.sum_sq = None
        self.count = 0
        self.shares = 0
        self._waiting: dict = {}
        self._next = 0
        self.workers: list = []

    def add(self, share: Share, result: dict) -> None:
        self._waiting[share.index] = result
        while self._next in self._waiting:
            r = self._waiting.pop(self._next)
            m, n = r["mean"].astype(np.float64), int(r["frames"])
            if self.sum is None:
                self.sum, self.sum_sq = np.zeros_like(m), np.zeros_like(m)
            self.sum += n * m
            self.sum_sq += n * m * m
            self.count += n
            self.shares += 1
            self.workers.append(r["worker"])
            self._next += 1

    def mean(self) -> np.ndarray:
        return self.sum / self.count

    def stderr(self) -> np.ndarray | None:
        if self.shares < 2:
            return None
        m = self.mean()
        spread = np.maximum(self.sum_sq - self.count * m * m, 0.0) / (self.shares - 1)   # ~ per-frame variance
        return np.sqrt(spread / self.count).astype(np.float32)


def converge_reference(scene, views=2, size=(256, 256), frames: int = 256, spp: int = 4, max_bounces: int = 8,
                       seed: int = 0, graph=None, pin: str = "Accumulate.dst", cluster=None, workers=None,
                       address=None, shares: int | None = None, payload=None, progress: bool = True) -> Reference:
    """A converged reference of `scene` seen by `views` (a ViewSet, or a view count from the
    scene's camera at `size`): `frames` frames of `spp` paths per pixel split over the workers
    by frames (see the module docstring for seeds). The default graph is the tuner's
    (rayvr.tune.path_traced_graph: paths from pixel centres, `max_bounces`), so seed 0 gives
    rv.tune.render_reference's image; `graph` and `pin` (an Accumulate output) replace it.
    `shares`: how many pieces (default 4 per worker). For `rayvr converge`."""
    from ..tune.configs import path_traced_graph
    from ..tune.measure import make_views

    if int(frames) < 1 or int(spp) < 1:
        raise OptionError(f"converge_reference: frames and spp must be >= 1, got frames={frames}, spp={spp}")
    if not 0 <= int(seed) < (1 << 32) // SEED_STRIDE:
        raise OptionError(f"converge_reference: seed must be in 0..{(1 << 32) // SEED_STRIDE - 1}, got {seed}")
    if int(frames) > SEED_STRIDE:
        raise OptionError(f"converge_reference: at most {SEED_STRIDE} frames per seed; use more spp per frame")
    scene, payload = _scene_and_payload(scene, payload)
    view_set = make_views(scene, views, size)
    graph = graph or path_traced_graph(spp=int(spp), max_bounces=int(max_bounces))
    graph_dict, _ = _graph_for(graph, [pin])
    merged = _OrderedMean()
    t0 = time.perf_counter()
    with pool.using(cluster, workers, address) as c:
        ranges = split_evenly(int(frames), shares or SHARES_PER_WORKER * c.size)
        jobs = [Share(i, "samples", {"graph": graph_dict, "views": view_set, "pin": pin, "frames": b - a,
                                     "first_frame": int(seed) * SEED_STRIDE + a}, work=b - a)
                for i, (a, b) in enumerate(ranges)]
        c.run(jobs, c.scene_ref(payload), on_result=merged.add,
              desc=f"reference {scene.name}", unit="frame", progress=progress)
    return Reference(merged.mean().astype(np.float32), int(frames), int(spp), int(seed), merged.stderr(),
                     merged.shares, time.perf_counter() - t0, merged.workers)


# -- (b) one frame split by views -----------------------------------------------------------------
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

    A view's pixels equal one process's when nothing random depends on its layer: each share
    renders its views as layers 0..k-1, and the passes seed random numbers by layer (so random
    passes give another, equally valid sample there; shares' streams are decorrelated through
    the frame index, VIEW_STREAM_STRIDE). Nothing may couple views either: auto exposure over
    the frame belongs after the gather (rayvr.cluster.gather.tone_map)."""
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
                      "frame_index": int(frame_index) + a * VIEW_STREAM_STRIDE, "flip_y": flip_y,
                      "profiling": profiling}
            jobs.append(Share(i, "views", kwargs, work=(b - a) * int(frames), meta={"first_view": a}))
        c.run(jobs, c.scene_ref(payload), on_result=gather, desc=f"views {scene.name}", unit="view",
              progress=progress)
    info.sort(key=lambda d: d["first_view"])
    return ViewsResult(out, info, time.perf_counter() - t0)


# -- (c) a sequence split by frames ----------------------------------------------------------------
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


# -- (d) the error study split by configurations ------------------------------------------------------
def _reference_for(scene, payload, view_set, reference, settings, cache_dir, c, progress):
    """measure's reference: given (array or .npz), cached, or converged on the cluster (and cached)."""
    from ..tune.measure import load_reference
    from ..tune.reference import ReferenceSettings, cached_reference, reference_path, store_reference

    if reference is not None:
        return load_reference(scene, view_set, reference, None, None, None, progress)
    settings = settings or ReferenceSettings()
    path = None if cache_dir is False else reference_path(scene, view_set, settings, cache_dir)
    image = cached_reference(path) if path is not None else None
    if image is not None:
        return image, str(path)
    ref = converge_reference(scene, view_set, frames=settings.frames, spp=settings.spp,
                             max_bounces=settings.max_bounces, cluster=c, payload=payload, progress=progress)
    if path is not None:
        store_reference(path, ref.image, scene, view_set, settings)
    return ref.image, str(path) if path else f"rendered on {c.size} workers ({settings.frames} frames x {settings.spp} spp)"


def measure(scene, configs, reference=None, size=(256, 256), views=2, frames: int = 20, warmup: int = 3,
            reference_settings=None, cache_dir=None, ppd: float | None = None, eps: float = 1e-2,
            metrics=None, keep_images: bool = False, warmup_s: float = 0.0, cluster=None, workers=None,
            address=None, payload=None, progress: bool = True):
    """rayvr.tune.measure with its configurations split over the workers: each is rendered and
    timed on one worker's GPU, and its row's `timed_on` names that worker. The reference (when
    not given) converges split by samples and goes into the same cache as tune's. Rows keep the
    order of `configs`."""
    from ..tune import metrics as M
    from ..tune.measure import check_configs, make_views
    from ..tune.results import Results

    configs = check_configs(configs)
    metrics = M.check_metrics(tuple(M.METRICS) if metrics is None else metrics)
    scene, payload = _scene_and_payload(scene, payload)
    view_set = make_views(scene, views, size)
    rows: dict = {}
    infos: list = []
    with pool.using(cluster, workers, address) as c:
        ref, source = _reference_for(scene, payload, view_set, reference, reference_settings, cache_dir, c, progress)
        ref_obj = c.put(np.asarray(ref))
        kw = {"frames": frames, "warmup": warmup, "ppd": ppd, "eps": eps, "metrics": metrics,
              "keep_images": keep_images, "warmup_s": warmup_s}
        jobs = [Share(i, "measure", {"config": cfg, "reference": ref_obj, "views": view_set, **kw})
                for i, cfg in enumerate(configs)]

        def collect(share, result):
            rows[share.index] = result["row"]
            infos.append(result["info"])

        c.run(jobs, c.scene_ref(payload), on_result=collect, desc="configurations", unit="config",
              progress=progress)
    methods = sorted({i["method"] for i in infos})
    info = {**infos[0], "method": methods[0] if len(methods) == 1 else ", ".join(methods), "reference": source,
            "workers": sorted({r.timed_on for r in rows.values()})}
    return Results([rows[i] for i in sorted(rows)], info)


def probe_cost_model(scene, view_set, builder, options: dict, metric: str = "flip", levels=None, frames: int = 10,
                     warmup: int = 3, reference=None, reference_settings=None, cache_dir=None, ppd=None,
                     cluster=None, workers=None, address=None, payload=None, progress: bool = True):
    """rayvr.tune.probe_cost_model on one worker (all levels on one GPU, as the cost model
    needs), the reference converged over all of them: (CostModel, reference, HDR pin)."""
    from ..materials.effect import Effect

    scene, payload = _scene_and_payload(scene, payload)
    with pool.using(cluster, workers, address) as c:
        ref, _ = _reference_for(scene, payload, view_set, reference, reference_settings, cache_dir, c, progress)
        result = c.call("probe", c.scene_ref(payload), desc="effect levels", views=view_set, builder=builder,
                        options=dict(options), reference=c.put(np.asarray(ref)), metric=metric,
                        levels=tuple(Effect) if levels is None else tuple(levels), frames=frames, warmup=warmup,
                        ppd=ppd)
    return result["model"], ref, result["pin"]
