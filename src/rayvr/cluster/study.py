"""The error study (rayvr.tune) on a cluster: its reference split by samples, its configurations
and progressive curves split over the workers.

- `converge_reference`: the study's reference (rayvr.study.reference: the same graph, seeds and
  checks) split by samples. Its frames are the frames one process renders, from the reference
  seed range of rayvr.study.seeds, cut into shares that never straddle a boundary the checks read:
  half A (its first bounce-check frames, then the rest) and half B. The shares' means merge in
  share order (deterministic float64 sums) into the two independent halves, so the convergence
  verdict is one process's up to float rounding; the bounce check's render with one more bounce
  over half A's first frames is split the same way. It is cached through
  rayvr.study.reference.cached_reference: the same files and keys as without a cluster.
- `StudyRunner`: a rayvr.study.runner for `rv.study.measure` and the tuner. References as above;
  the cost-model probe on one worker (every effect level on one GPU, as the model needs); each
  configuration's row (timing, judged frames, motion, bias floor) and each progressive curve on
  one worker, named in the row (`timed_on`). The rows use the study's seeds, so they equal one
  process's apart from the GPU times. Floors are read from and stored into the driver's cache.
- `measure`, `probe_cost_model`: rv.tune's with a StudyRunner.
"""
from __future__ import annotations

import dataclasses
import time

import numpy as np

from ..errors import OptionError
from ..study import seeds
from ..study.metrics import DEFAULT_EPS
from ..study.reference import PIN, Reference, ReferenceSettings, cached_reference, reference_graph, relative_change
from . import pool
from .jobs import SHARES_PER_WORKER, _graph_for, _scene_and_payload
from .shares import Share, split_evenly


@dataclasses.dataclass
class SplitReference(Reference):
    """A rayvr.study.Reference rendered on a cluster, with what the split tells besides:
    `stderr` the standard error of each pixel's mean from the first round's shares' means (batch
    means; None with one share or from the cache), `shares` the pieces its frames were cut into (0 from the
    cache), `workers` the worker of each piece, in order."""

    stderr: np.ndarray | None = None
    shares: int = 0
    workers: list = dataclasses.field(default_factory=list)

    @classmethod
    def of(cls, ref: Reference) -> "SplitReference":
        """`ref` as a SplitReference (one from the cache has no shares)."""
        if isinstance(ref, cls):
            return ref
        return cls(**{f.name: getattr(ref, f.name) for f in dataclasses.fields(Reference)})


def _cut(bounds, pieces: int) -> list[tuple[int, int]]:
    """[start, stop) ranges from bounds[0] to bounds[-1] in about `pieces` contiguous pieces (in
    proportion to each segment's length), none crossing one of `bounds`."""
    total = bounds[-1] - bounds[0]
    out = []
    for a, b in zip(bounds, bounds[1:]):
        if b > a:
            n = max(1, round(pieces * (b - a) / total))
            out += [(a + x, a + y) for x, y in split_evenly(b - a, n)]
    return out


class _Fold:
    """The shares' (mean, frames) folded in share order, whatever order they arrive in (so the
    float64 sums are the same on every run): a sum per part, and the batch-means spread over the
    reference's own shares."""

    MAIN = ("a_check", "a_rest", "b")       # half A's bounce-check frames, the rest of half A, half B

    def __init__(self):
        self.sum: dict = {}
        self.count: dict = {}
        self.sum_sq = None
        self.shares = 0
        self.workers: list = []
        self._waiting: dict = {}
        self._next = 0

    def add(self, share: Share, result: dict) -> None:
        self._waiting[share.index] = (share.meta["part"], result)
        while self._next in self._waiting:
            part, r = self._waiting.pop(self._next)
            m, n = r["mean"].astype(np.float64), int(r["frames"])
            self.sum[part] = self.sum.get(part, 0.0) + n * m
            self.count[part] = self.count.get(part, 0) + n
            if part in self.MAIN:
                self.sum_sq = n * m * m if self.sum_sq is None else self.sum_sq + n * m * m
                self.shares += 1
                self.workers.append(r["worker"])
            self._next += 1

    def mean(self, *parts) -> np.ndarray:
        parts = [p for p in parts if p in self.sum]
        return sum(self.sum[p] for p in parts) / sum(self.count[p] for p in parts)

    def stderr(self) -> np.ndarray | None:
        if self.shares < 2:
            return None
        n = sum(self.count.get(p, 0) for p in self.MAIN)
        m = self.mean(*self.MAIN)
        spread = np.maximum(self.sum_sq - n * m * m, 0.0) / (self.shares - 1)     # ~ per-frame variance
        return np.sqrt(spread / n).astype(np.float32)


def _render_split(c, scene, payload, view_set, settings: ReferenceSettings, first: int, eps: float, shares,
                  progress: bool) -> SplitReference:
    """The reference of frames [first, first + settings.frames) over the cluster `c`."""
    half, check = settings.frames // 2, settings.bounce_check_frames
    pieces = shares or SHARES_PER_WORKER * c.size
    graph, _ = _graph_for(reference_graph(settings), [PIN])
    more, _ = _graph_for(reference_graph(settings, settings.max_bounces + 1), [PIN])
    parts = [("a_check" if b <= check else "a_rest" if b <= half else "b", graph, a, b)
             for a, b in _cut([0, check, half, settings.frames], pieces)]
    parts += [("more", more, a, b) for a, b in _cut([0, check], max(1, round(pieces * check / settings.frames)))]
    jobs = [Share(i, "samples", {"graph": g, "views": view_set, "pin": PIN, "frames": b - a,
                                 "first_frame": first + a}, work=b - a, meta={"part": part})
            for i, (part, g, a, b) in enumerate(parts)]
    fold = _Fold()
    t0 = time.perf_counter()
    c.run(jobs, c.scene_ref(payload), on_result=fold.add, desc=f"reference {scene.name}", unit="frame",
          progress=progress)
    a, b = fold.mean("a_check", "a_rest"), fold.mean("b")
    change = relative_change(fold.mean("more"), fold.mean("a_check"))
    return SplitReference(((a + b) / 2).astype(np.float32), a.astype(np.float32), b.astype(np.float32), settings,
                          first, change, time.perf_counter() - t0, f"rendered on {c.size} worker(s)", eps,
                          stderr=fold.stderr(), shares=fold.shares, workers=fold.workers)


def _render_frames(c, scene, payload, view_set, settings: ReferenceSettings, first: int, frames: int, shares,
                   progress: bool) -> np.ndarray:
    """The mean of the reference graph's frames [first, first + frames) over the cluster `c`
    (an extension of a reference that has not converged yet)."""
    graph, _ = _graph_for(reference_graph(settings), [PIN])
    pieces = shares or SHARES_PER_WORKER * c.size
    jobs = [Share(i, "samples", {"graph": graph, "views": view_set, "pin": PIN, "frames": b - a,
                                 "first_frame": first + a}, work=b - a, meta={"part": "extension"})
            for i, (a, b) in enumerate(_cut([0, frames], pieces))]
    fold = _Fold()
    c.run(jobs, c.scene_ref(payload), on_result=fold.add, desc=f"reference {scene.name}", unit="frame",
          progress=progress)
    return fold.mean("extension").astype(np.float32)


def converge_reference(scene, views=2, size=(256, 256), settings: ReferenceSettings | None = None,
                       frames: int | None = None, spp: int | None = None, max_bounces: int | None = None,
                       seed: int = 0, cache_dir=False, eps: float = DEFAULT_EPS, cluster=None, workers=None,
                       address=None, shares: int | None = None, payload=None, progress: bool = True) -> SplitReference:
    """The error study's reference of `scene` seen by `views` (a ViewSet, or a view count from
    the scene's camera at `size`), split by samples over the workers (module docstring).

    `settings`: a rv.tune.ReferenceSettings, or give its `frames`, `spp`, `max_bounces` (the
    others at ReferenceSettings' defaults). `seed`: the reference seed range of
    rayvr.study.seeds (0: the static view's, the frames rv.tune.render_reference renders; k:
    trajectory sample k's). `cache_dir`: the study's reference cache (None: its default folder;
    False, the default here: render and store nothing). `shares`: pieces of the reference's
    frames (default 4 per worker)."""
    from ..study.timing import make_views

    given = {k: v for k, v in {"frames": frames, "spp": spp, "max_bounces": max_bounces}.items() if v is not None}
    if settings is not None and given:
        raise OptionError(f"converge_reference: give settings or {', '.join(given)}, not both")
    settings = settings or ReferenceSettings(**given)
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or not 0 <= seed < seeds.SLOTS:
        raise OptionError(f"converge_reference: seed must be an integer from 0 to {seeds.SLOTS - 1} (a reference "
                          f"seed range of rayvr.study.seeds), got {seed!r}")
    scene, payload = _scene_and_payload(scene, payload)
    view_set = make_views(scene, views, size)
    with pool.using(cluster, workers, address) as c:
        def render(first_frame: int) -> SplitReference:
            return _render_split(c, scene, payload, view_set, settings, first_frame, eps, shares, progress)

        def render_frames(first_frame: int, frames: int, tick) -> np.ndarray:
            return _render_frames(c, scene, payload, view_set, settings, first_frame, frames, shares, progress)

        ref = cached_reference(scene, view_set, settings, cache_dir, sample=int(seed), eps=eps, render=render,
                               render_frames=render_frames)
    return SplitReference.of(ref)


class StudyRunner:
    """Where rv.study.measure and the tuner run their steps on a Cluster (module docstring); the
    methods are rayvr.study.runner.LocalRunner's. `payload`: the scene as the workers load it."""

    shows_progress = True        # the cluster's bars (frames of each reference, configurations)

    def __init__(self, cluster, payload, progress: bool = True):
        self.cluster, self.payload, self.progress = cluster, payload, progress

    def reference(self, scene, view_set, settings, cache_dir=None, sample: int = 0, eps: float = DEFAULT_EPS,
                  gpu=None, tick=None, progress=None) -> SplitReference:
        return converge_reference(scene, view_set, settings=settings, seed=sample, cache_dir=cache_dir, eps=eps,
                                  cluster=self.cluster, payload=self.payload, progress=self.progress)

    def probe(self, scene, view_set, builder, options: dict, judge, **kwargs):
        kwargs.pop("gpu", None)
        kwargs.pop("progress", None)
        c = self.cluster
        result = c.call("probe", c.scene_ref(self.payload), desc="effect levels", progress=self.progress,
                        views=view_set, builder=builder, options=dict(options), judge=judge, **kwargs)
        return result["model"], result["pin"]

    def rows(self, study, configs, reference, motion_references: dict) -> list:
        c = self.cluster
        shared = {"study": c.put(study.spec()), "reference": c.put(reference),
                  "motion_references": c.put(motion_references)}
        jobs = [Share(i, "measure", {**shared, "config": cfg, "floor": study.cached_floor(cfg) if study.s.floors
                                     else None}) for i, cfg in enumerate(configs)]
        results = c.run(jobs, c.scene_ref(self.payload), desc="configurations", unit="config",
                        progress=self.progress)
        for cfg, result in zip(configs, results):
            if result["floor"] is not None:         # rendered on the worker: into the driver's cache
                study.store_floor(cfg, result["floor"])
                result["row"].floor["source"] = result["floor"].source
        study.method = ", ".join(sorted({r["method"] for r in results}))
        return [r["row"] for r in results]

    def curves(self, study, reference) -> list:
        c = self.cluster
        shared = {"study": c.put(study.spec()), "reference": c.put(reference)}
        jobs = [Share(i, "curve", {**shared, "name": name, "options": options})
                for i, (name, options) in enumerate(study.curve_graphs())]
        return [r["curve"] for r in c.run(jobs, c.scene_ref(self.payload), desc="progressive curves", unit="curve",
                                          progress=self.progress)]


def measure(scene, configs, views=2, size=(64, 64), cluster=None, workers=None, address=None, payload=None,
            progress: bool = True, **kwargs):
    """rv.study.measure (its other keywords: reference, settings, cache_dir, curves, notes) on the
    cluster: the references split by samples, each configuration and curve on one worker."""
    from ..study.measure import measure as study

    scene, payload = _scene_and_payload(scene, payload)
    with pool.using(cluster, workers, address) as c:
        return study(scene, configs, views=views, size=size, progress=progress,
                     runner=StudyRunner(c, payload, progress), **kwargs)


def probe_cost_model(scene, view_set, builder, options: dict, judge, cluster=None, workers=None, address=None,
                     payload=None, **kwargs):
    """rv.tune.cost_probe.probe_cost_model on one worker: (CostModel, HDR pin)."""
    scene, payload = _scene_and_payload(scene, payload)
    with pool.using(cluster, workers, address) as c:
        return StudyRunner(c, payload, kwargs.pop("progress", True)).probe(scene, view_set, builder, options, judge,
                                                                           **kwargs)
