"""One frame over the GPUs of this host (Tauray's mode): each worker renders a range of the
frame's views, the pixels come back through host memory (Ray's shared-memory object store) and
are written into the primary GPU's view array, a texture array on the driver's context.

Shares follow measured speed: each worker keeps a moving average of its render ms at each view
count it rendered, and a line through them (`WorkerSpeed`: a fixed cost per frame plus ms per
view; ms per view alone until it has rendered two counts). The views are re-split to make the
slowest predicted share shortest when that shortens it by more than `hysteresis`. A worker
compiles its graph again for a view count it has not rendered yet (it caches RENDERER_CACHE of
them), so the frame after a re-split is slower; that frame does not count in the averages.

Latency is measured as the primary sees it: from the frame's start (before any share is sent)
to the primary's array complete (every share written and the primary's GL finished).
"""
from __future__ import annotations

import dataclasses
import time

import numpy as np

from .jobs import _graph_for, _scene_and_payload
from .shares import Share, split_evenly, view_range


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


@dataclasses.dataclass
class WorkerSpeed:
    """One worker's render ms as `fixed + per_view * views`, fitted (least squares) to moving
    averages of its ms at each view count it rendered; through the origin while it has one."""

    smoothing: float = 0.3
    by_count: dict = dataclasses.field(default_factory=dict)

    def observe(self, views: int, ms: float) -> None:
        old = self.by_count.get(views)
        self.by_count[views] = ms if old is None else (1 - self.smoothing) * old + self.smoothing * ms

    @property
    def known(self) -> bool:
        return bool(self.by_count)

    def line(self) -> tuple[float, float]:
        """(fixed ms, ms per view)."""
        n = np.array(list(self.by_count), np.float64)
        t = np.array(list(self.by_count.values()), np.float64)
        through_origin = (0.0, float((n * t).sum() / (n * n).sum()))
        if len(n) < 2:
            return through_origin
        slope, fixed = np.polyfit(n, t, 1)
        if fixed < 0 or slope <= 0:     # noise: fall back to ms per view
            return through_origin
        return float(fixed), float(slope)

    def predict(self, views: int) -> float:
        fixed, per_view = self.line()
        return fixed + per_view * views if views else 0.0


def rebalanced(counts: list, speeds: list, hysteresis: float = 0.05) -> list:
    """Views per worker that make the slowest predicted share (WorkerSpeed.predict) shortest,
    every worker keeping at least one view, if that beats `counts` by `hysteresis`; else one
    view moved from the slowest to the fastest worker while either has been seen at one view
    count only (a probe for its fixed cost); else `counts`."""
    total, n = sum(counts), len(counts)
    proposal = [1] * n if total >= n else [0] * n
    for _ in range(total - sum(proposal)):   # each view to the worker that would finish first with it
        k = min(range(n), key=lambda i: speeds[i].predict(proposal[i] + 1))
        proposal[k] += 1

    def slowest(c):
        return max(speed.predict(v) for speed, v in zip(speeds, c))

    if slowest(proposal) < (1 - hysteresis) * slowest(counts):
        return proposal
    times = [speed.predict(v) for speed, v in zip(speeds, counts)]
    slow, fast = max(range(n), key=times.__getitem__), min(range(n), key=times.__getitem__)
    if counts[slow] > 1 and times[slow] > (1 + hysteresis) * times[fast] and \
            any(len(speeds[k].by_count) < 2 for k in (slow, fast)):
        # Uneven, but ms per view alone cannot say whether a fixed cost per frame is why: move
        # one view, so that both workers are seen at a second view count and get their line.
        probe = list(counts)
        probe[slow] -= 1
        probe[fast] += 1
        return probe
    return list(counts)


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
        self.speeds = [WorkerSpeed(float(smoothing)) for _ in range(n)]
        self._compiled: set = set()
        self.rebalance, self.hysteresis = bool(rebalance), float(hysteresis)
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
                          "frame_index": self.frame_index, "flip_y": False}
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
        """Fold this frame's render times into the workers' speeds; re-split if it pays. A
        worker's first frame at a view count compiles its graph: it does not count."""
        for k, (count, ms) in enumerate(zip(timing.shares, timing.render_ms)):
            if count and (k, count) not in self._compiled:
                self._compiled.add((k, count))
            elif count:
                self.speeds[k].observe(count, ms)
        if self.rebalance and all(s.known for s in self.speeds):
            self.counts = rebalanced(self.counts, self.speeds, self.hysteresis)

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
