"""One frame over the GPUs of this host (Tauray's mode): each worker renders a range of the
frame's views, the pixels come back through host memory (Ray's shared-memory object store) and
are written into the primary GPU's view array, a texture array on the driver's context.

Shares follow measured speed: each worker's ms per view is a moving average, and the views are
re-split in proportion to 1 / (ms per view) when that shortens the slowest share by more than
`hysteresis`. A worker compiles its graph again for a view count it has not rendered yet (it
caches RENDERER_CACHE of them), so the frame after a re-split is slower; that frame does not
count in the averages.

Latency is measured as the primary sees it: from the frame's start (before any share is sent)
to the primary's array complete (every share written and the primary's GL finished).
"""
from __future__ import annotations

import dataclasses
import time

import numpy as np

from .jobs import VIEW_STREAM_STRIDE, _graph_for, _scene_and_payload
from .shares import Share, split_by_weights, split_evenly, view_range


@dataclasses.dataclass
class FrameTiming:
    """One split frame: `latency_ms` from its start to the primary's array complete; per worker
    its views, render ms (GPU finished), readback ms and when its pixels reached the primary
    (ms after the start); `copy_ms` the primary's texture writes and finish."""

    latency_ms: float
    shares: list
    render_ms: list
    readback_ms: list
    arrival_ms: list
    copy_ms: float

    def as_dict(self) -> dict:
        return dataclasses.asdict(self)


def rebalanced(counts: list, ms_per_view: list, hysteresis: float = 0.05) -> list:
    """Views per worker in proportion to their speed (1 / ms per view), if that makes the
    slowest share (views x ms per view) shorter by more than `hysteresis`; else `counts`."""
    proposal = split_by_weights(sum(counts), [1.0 / max(m, 1e-6) for m in ms_per_view])

    def slowest(c):
        return max(n * m for n, m in zip(c, ms_per_view))

    return proposal if slowest(proposal) < (1 - hysteresis) * slowest(counts) else list(counts)


class HostFrameSplitter:
    """Split frames of `views` (a ViewSet) rendered with `graph` over `workers` GPU workers of
    this host (or the workers of `cluster`); `pin` (default the graph's first output) is
    gathered into `array` on `gpu` (default rayvr.gpu.get_context()). `initial_shares`: views
    per worker for the first frame (default even); `smoothing`: the moving average's weight of
    the newest frame; `rebalance`: follow measured speed."""

    def __init__(self, scene, graph, views, pin: str | None = None, workers: int | None = None, cluster=None,
                 gpu=None, payload=None, initial_shares=None, smoothing: float = 0.3, rebalance: bool = True,
                 hysteresis: float = 0.05):
        from ..gpu import get_context
        from .pool import Cluster

        self._own = cluster is None
        self.cluster = cluster or Cluster(workers, same_node=True)
        self.gpu = gpu or get_context()
        scene, payload = _scene_and_payload(scene, payload)
        self._scene = self.cluster.scene_ref(payload)
        self._graph, (self.pin,) = _graph_for(graph, [pin] if pin else None)
        self.views = views
        n = self.cluster.size
        self.counts = list(initial_shares) if initial_shares else [b - a for a, b in split_evenly(len(views), n)]
        self.counts += [0] * (n - len(self.counts))
        if sum(self.counts) != len(views) or len(self.counts) != n:
            raise ValueError(f"initial_shares {initial_shares} must give {len(views)} views to {n} workers")
        self.ms_per_view: list = [None] * n
        self._compiled: set = set()
        self.smoothing, self.rebalance, self.hysteresis = float(smoothing), bool(rebalance), float(hysteresis)
        self.frame_index = 0
        self.array = None
        self.history: list[FrameTiming] = []

    def _ensure_array(self, sample: np.ndarray) -> None:
        if self.array is None:
            w, h = self.views.size
            dtype = {np.dtype(np.uint8): "f1", np.dtype(np.float16): "f2", np.dtype(np.float32): "f4"}[sample.dtype]
            self.array = self.gpu.gl.texture_array((w, h, len(self.views)), sample.shape[-1], dtype=dtype)

    def render(self, views=None) -> FrameTiming:
        """Render one frame (default the splitter's views; another ViewSet of the same count
        and size for a moving head) into `array`; its timing."""
        views = views or self.views
        w, h = views.size
        n = len(self.counts)
        slots = [s.number for s in self.cluster.slots]
        shares, first = [], 0
        for k, count in enumerate(self.counts):
            if count:
                kwargs = {"graph": self._graph, "views": view_range(views, first, first + count), "pins": [self.pin],
                          "frame_index": self.frame_index + first * VIEW_STREAM_STRIDE, "flip_y": False}
                shares.append(Share(k, "views", kwargs, work=count, slot=slots[k], meta={"first": first}))
            first += count
        render_ms, readback_ms, arrival_ms = [0.0] * n, [0.0] * n, [0.0] * n
        copy_s = 0.0
        t0 = time.perf_counter()

        def write(share, result):
            nonlocal copy_s
            t = time.perf_counter()
            arrival_ms[share.index] = (t - t0) * 1e3
            a = result["pixels"][self.pin]
            self._ensure_array(a)
            self.array.write(np.ascontiguousarray(a), viewport=(0, 0, share.meta["first"], w, h, a.shape[0]))
            copy_s += time.perf_counter() - t
            render_ms[share.index] = result["render_ms"]
            readback_ms[share.index] = result["readback_ms"]

        self.cluster.run(shares, self._scene, on_result=write, desc="split frame", progress=False)
        t = time.perf_counter()
        self.gpu.gl.finish()
        t1 = time.perf_counter()
        timing = FrameTiming((t1 - t0) * 1e3, list(self.counts), render_ms, readback_ms, arrival_ms,
                             (copy_s + t1 - t) * 1e3)
        self.history.append(timing)
        self.frame_index += 1
        self._learn(timing)
        return timing

    def _learn(self, timing: FrameTiming) -> None:
        """Fold this frame's ms per view into the moving averages; re-split if it pays. A
        worker's first frame at a view count compiles its graph: it does not count."""
        for k, (count, ms) in enumerate(zip(timing.shares, timing.render_ms)):
            if count and (k, count) not in self._compiled:
                self._compiled.add((k, count))
            elif count:
                per_view = ms / count
                old = self.ms_per_view[k]
                self.ms_per_view[k] = per_view if old is None else (1 - self.smoothing) * old + self.smoothing * per_view
        if self.rebalance and all(m is not None for m in self.ms_per_view):
            self.counts = rebalanced(self.counts, self.ms_per_view, self.hysteresis)

    def pixels(self, flip_y: bool = True) -> np.ndarray:
        """The primary's view array as numpy (views, h, w, c); rows top-down unless not flip_y."""
        w, h = self.views.size
        dtype = {"f1": np.uint8, "f2": np.float16, "f4": np.float32}[self.array.dtype]
        a = np.frombuffer(self.array.read(), dtype).reshape(len(self.views), h, w, self.array.components)
        return a[:, ::-1] if flip_y else a

    def close(self) -> None:
        if self.array is not None:
            self.array.release()
            self.array = None
        if self._own:
            self.cluster.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
