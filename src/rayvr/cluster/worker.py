"""`RenderWorker`: one GPU, one rayvr context, scenes loaded once; the body of a cluster actor.

The class is plain Python (`rayvr.cluster.pool` wraps it in `ray.remote`), so it also runs in
the driver's own process. Its context is on the EGL device of the process's CUDA device
(rayvr.gpu.egl_devices), llvmpipe where there is none. Scenes arrive as ScenePayloads through
Ray's object store and are cached by key; Renderers are cached per (scene, graph, view count,
size), each with its own copy of the graph, and their temporal state (Accumulate, TAA) is reset
at the start of every share.

Job methods (called through `run`): `samples` (a frame range of a progressive render),
`views` (some views of a frame), `frames` (a frame range of a trajectory sequence), and the
error study's (rayvr.cluster.study): `measure` (one configuration's row), `curve` (one
progressive curve), `probe` (rayvr.tune.cost_probe.probe_cost_model).
"""
from __future__ import annotations

import collections
import json
import os
import socket
import time

import numpy as np

RENDERER_CACHE = 4          # Renderers kept per worker (each holds a GpuScene and its targets)
PROGRESS_INTERVAL_S = 0.2   # a worker reports progress at most this often


def _ray_gpu_ids() -> list:
    """The GPU ids Ray gave this process ([] outside a Ray worker or without GPUs)."""
    try:
        import ray

        return list(ray.get_gpu_ids()) if ray.is_initialized() else []
    except Exception:   # not a Ray worker
        return []


class RenderWorker:
    """A rayvr context on this process's GPU; see the module docstring.

    `label`: how results name this worker; `progress`: a ProgressCounter actor handle (or None);
    `device_index`: the EGL device ("auto": the CUDA device's, via EGL_NV_device_cuda); `gpu`:
    an existing GpuContext to use instead (a worker inside the driver's process)."""

    def __init__(self, label: str = "worker", progress=None, device_index="auto", backend: str | None = None,
                 gpu=None):
        from ..gpu import create_context, set_context
        from ..gpu.egl_devices import select_device

        self.label = label
        self._progress = progress
        self.gpu_ids = [str(g) for g in _ray_gpu_ids()]
        if gpu is not None:
            self.gpu, self.device_index, self.device_reason = gpu, None, "the given context"
        else:
            if device_index == "auto":
                device_index, self.device_reason = select_device(0)
            else:
                self.device_reason = "given"
            self.device_index = device_index
            self.gpu = create_context(backend, device_index)
            set_context(self.gpu)   # code that asks rayvr.gpu.get_context() gets this device
        self._scenes: dict = {}
        self._renderers: collections.OrderedDict = collections.OrderedDict()
        self._fail_after: int | None = None
        self._progress_key = None
        self._pending = 0
        self._last_report = 0.0

    # -- identity ------------------------------------------------------------------------------
    def info(self) -> dict:
        """Who this worker is: label, host, pid, Ray GPU ids, EGL device and the GL renderer."""
        return {"label": self.label, "host": socket.gethostname(), "pid": os.getpid(), "gpu_ids": self.gpu_ids,
                "egl_device": self.device_index, "egl_reason": self.device_reason,
                "renderer": self.gpu.caps.renderer, "software": self.gpu.caps.is_software}

    def describe(self) -> str:
        """One line: label, GPU ids, renderer and host (what a result row records)."""
        gpus = f" GPU {','.join(self.gpu_ids)}" if self.gpu_ids else ""
        return f"{self.label}{gpus} ({self.gpu.caps.renderer}, {socket.gethostname()})"

    def ping(self) -> str:
        return self.label

    def fail_after(self, frames: int) -> None:
        """Fault injection for tests: the process exits (os._exit) after `frames` more frames."""
        self._fail_after = int(frames)

    # -- the entry point -----------------------------------------------------------------------
    def run(self, method: str, scene, progress_key, **kwargs):
        """Call job method `method` on scene `scene` = (key, [ObjectRef or ScenePayload]) with
        `kwargs`; progress goes to the counter under `progress_key`."""
        self._progress_key, self._pending, self._last_report = progress_key, 0, time.perf_counter()
        try:
            return getattr(self, "job_" + method)(self._scene(scene), **kwargs)
        finally:
            self._flush_progress()

    def _scene(self, scene):
        if scene is None:
            return None
        key, holder = scene
        if key not in self._scenes:
            payload = holder[0]
            if not hasattr(payload, "load"):     # an ObjectRef nested in a list: fetched only here
                import ray

                payload = ray.get(payload)
            self._scenes[key] = (key, payload.load())
        return self._scenes[key]

    # -- progress and faults -------------------------------------------------------------------
    def _tick(self, n: int = 1) -> None:
        if self._fail_after is not None:
            self._fail_after -= n
            if self._fail_after <= 0:
                os._exit(1)
        self._pending += n
        now = time.perf_counter()
        if now - self._last_report >= PROGRESS_INTERVAL_S:
            self._flush_progress()
            self._last_report = now

    def _flush_progress(self) -> None:
        if self._progress is not None and self._pending and self._progress_key is not None:
            self._progress.add.remote(self._progress_key, self._pending)
        self._pending = 0

    # -- renderers -----------------------------------------------------------------------------
    def _renderer(self, scene, graph: dict, views, profiling: bool = False):
        """A cached Renderer of `scene` (key, Scene) with `graph` (RenderGraph.to_dict()) for
        len(views) views of views.size; its history reset."""
        from ..renderer import Renderer
        from ..rendergraph.graph import RenderGraph

        key = (scene[0], json.dumps(graph, sort_keys=True), len(views), tuple(views.size), bool(profiling))
        r = self._renderers.pop(key, None)
        if r is None:
            while len(self._renderers) >= RENDERER_CACHE:
                self._renderers.popitem(last=False)[1].close()
            r = Renderer(scene[1], RenderGraph.from_dict(graph), views=views, gpu=self.gpu, profiling=profiling)
        self._renderers[key] = r
        for render_pass in r.compiled.passes.values():
            reset = getattr(render_pass, "reset", None)
            if callable(reset):            # Accumulate, TAA: a share starts without history
                reset()
        return r

    def close(self) -> None:
        """Free the cached Renderers."""
        while self._renderers:
            self._renderers.popitem()[1].close()

    # -- jobs ------------------------------------------------------------------------------------
    def job_samples(self, scene, graph: dict, views, first_frame: int, frames: int, pin: str) -> dict:
        """Frames [first_frame, first_frame + frames) of a progressive render: the mean of `pin`
        (an Accumulate output, float32, rows top-down) over them and their count."""
        r = self._renderer(scene, graph, views)
        r.frame_index = int(first_frame)     # the paths' random streams follow the frame index
        t0 = time.perf_counter()
        for _ in range(int(frames)):
            r.render(views)
            self._tick()
        mean = r.read_output(pin, flip_y=True).astype(np.float32)
        return {"mean": mean, "frames": int(frames), "seconds": time.perf_counter() - t0, "worker": self.describe()}

    def job_views(self, scene, graph: dict, views, pins, frames: int = 1, frame_index: int = 0,
                  flip_y: bool = True, profiling: bool = False) -> dict:
        """Render `frames` frames of `views` (a PinnedViews share of a larger frame) and read
        `pins` after the last: {pin: (views, h, w, c)} in the pins' formats."""
        r = self._renderer(scene, graph, views, profiling)
        r.frame_index = int(frame_index)
        r.compiled.reset_nonfinite()        # the Renderer is cached: count this share alone
        t0 = time.perf_counter()
        for _ in range(int(frames)):
            r.render(views)
            self._tick(len(views))
        r.gl.finish()
        t1 = time.perf_counter()
        pixels = {pin: r.read_output(pin, flip_y=flip_y) for pin in pins}
        t2 = time.perf_counter()
        profile = str(r.profile()) if profiling else None
        return {"pixels": pixels, "render_ms": (t1 - t0) * 1e3 / max(int(frames), 1),
                "readback_ms": (t2 - t1) * 1e3, "views": len(views), "profile": profile,
                "nonfinite": r.compiled.nonfinite_counts(), "worker": self.describe()}

    def job_frames(self, scene, graph: dict, sequence, first: int, count: int, warmup: int = 0, pins=(),
                   flip_y: bool = True, frame_index_base: int = 0) -> dict:
        """Frames [first, first + count) of `sequence` (TrajectoryViews), after `warmup` frames
        before `first` rendered for history only; {pin: (count, views, h, w, c)} when `pins`."""
        start = max(0, int(first) - int(warmup))
        r = self._renderer(scene, graph, sequence.base)
        r.frame_index = int(frame_index_base) + start
        out = {pin: [] for pin in pins}
        previous = None
        t0 = time.perf_counter()
        for f in range(start, int(first) + int(count)):
            previous = sequence.views_at(f, previous)
            r.render(previous)
            if f >= first:
                for pin in pins:
                    out[pin].append(r.read_output(pin, flip_y=flip_y))
                self._tick()
        r.gl.finish()
        return {"pixels": {pin: np.stack(v) for pin, v in out.items()}, "first": int(first), "count": int(count),
                "seconds": time.perf_counter() - t0, "rendered": int(first) + int(count) - start,
                "worker": self.describe()}

    def job_measure(self, scene, study: dict, config, reference, motion_references: dict, floor=None) -> dict:
        """One configuration's row of the error study (rayvr.study.measure.Study.row, `study` its
        spec) on this worker's GPU, naming this worker (`timed_on`); a floor rendered here (none
        was given: a worker has no cache) comes back for the driver's cache."""
        from ..study.configs import effects_restored
        from ..study.measure import Study

        s = Study.from_spec(scene[1], study, self.gpu)
        with effects_restored(scene[1]):
            row = s.row(config, reference, motion_references, floor)
        row.timed_on = self.describe()
        self._tick()
        return {"row": row, "method": s.method, "floor": s.new_floors.get(config.name)}

    def job_curve(self, scene, study: dict, name: str, options: dict, reference) -> dict:
        """One progressive curve of the error study (rayvr.study.measure.Study.curve) on this GPU."""
        from ..study.measure import Study

        curve = Study.from_spec(scene[1], study, self.gpu).curve(name, options, reference)
        curve.timed_on = self.describe()
        self._tick()
        return {"curve": curve}

    def job_probe(self, scene, views, builder, options: dict, judge, **kwargs) -> dict:
        """rayvr.tune.cost_probe.probe_cost_model (its keywords) on this worker's GPU."""
        from ..tune.cost_probe import probe_cost_model

        model, pin = probe_cost_model(scene[1], views, builder, options, judge, progress=False, gpu=self.gpu,
                                      **kwargs)
        self._tick()
        return {"model": model, "pin": pin, "worker": self.describe()}
