"""`CompiledGraph`: the plan's GPU objects, compiled passes, and the per-frame execute loop.

Everything a frame needs (RenderData per pass, timers) is built here once; `execute()` is a
fixed loop of pass.execute() calls with no allocation.
"""
from __future__ import annotations

import time

import moderngl
import numpy as np

from ..errors import GraphError, did_you_mean
from ..gpu import GpuTimer
from ..gpu.timer import timing_method
from .compiler import Plan
from .formats import NUMPY_DTYPES, get_format
from .profile import Profile, RollingTimes
from .render_pass import PinKind, RenderContext, RenderData
from .report import CompileReport, ResourceInfo

class CompiledGraph:
    """A graph ready to execute at one size and view count. Build it with `RenderGraph.compile()`."""

    def __init__(self, graph, plan: Plan, gpu, gpu_scene=None, extra_report=(), profiling: bool = True,
                 window: int = 120):
        self.graph_name = graph.name
        self.plan = plan
        self.gpu = gpu
        self.gl = gpu.gl
        self.caps = gpu.caps
        self.order = list(plan.order)
        self.passes = {p: graph.get_pass(p) for p in plan.order}
        self.size, self.views = plan.size, plan.views
        self.objects = [self._allocate(s.key, s.resources[0]) for s in plan.slots]
        self.resources = {name: self.objects[r.slot] for name, r in plan.resources.items()}
        ctx = RenderContext(self.gl, self.caps, scene=gpu_scene)
        for p in self.order:
            self.passes[p].compile(ctx, plan.compile_data[p])
        self._steps = [(self.passes[p].execute,
                        RenderData({pin: (None if res is None else self.resources[res])
                                    for pin, res in plan.bindings[p].items()}, plan.size, plan.views))
                       for p in self.order]
        self.frames = 0
        self._window = window
        self._timers = [GpuTimer(self.gl, self.caps.timer_queries) for _ in self.order]
        self._times = [RollingTimes(window) for _ in self.order]
        self._cpu = RollingTimes(window)
        self.profiling = profiling
        self._report = self._build_report(list(extra_report))

    # -- GPU objects -----------------------------------------------------------------------
    def _allocate(self, key, first: str):
        kind, fmt, size, layers, byte_size = key
        if kind is PinKind.BUFFER:
            return self.gl.buffer(reserve=max(4, byte_size))
        f = get_format(fmt, where=f"resource '{first}'")
        if not f.glsl:
            raise GraphError(f"resource '{first}': format {fmt} cannot be a texture array here; "
                             f"declare r32f for depth written by a pass")
        if layers > self.caps.max_texture_layers:
            raise GraphError(f"resource '{first}': {layers} layers exceeds the driver's "
                             f"{self.caps.max_texture_layers}; compile with fewer views")
        tex = self.gl.texture_array((size[0], size[1], layers), f.components, dtype=f.dtype)
        if f.dtype == "u4":   # integer textures are incomplete (read as 0) with linear filtering
            tex.filter = (moderngl.NEAREST, moderngl.NEAREST)
        return tex

    def release(self) -> None:
        """Free the GPU objects now (otherwise they live as long as this object's GL context)."""
        for obj in self.objects:
            obj.release()
        self.objects, self.resources, self._steps = [], {}, []

    # -- per frame -------------------------------------------------------------------------
    def execute(self, ctx: RenderContext) -> None:
        """Run every kept pass once, in order (the views are layers: one call per pass)."""
        t0 = time.perf_counter()
        if self.profiling:
            for (run, data), timer, times in zip(self._steps, self._timers, self._times):
                timer.begin()
                run(ctx, data)
                timer.end()
                ms = timer.take()
                if ms is not None:
                    times.add(ms)
        else:
            for run, data in self._steps:
                run(ctx, data)
        self._cpu.add((time.perf_counter() - t0) * 1e3)
        self.frames += 1

    def make_context(self, **kwargs) -> RenderContext:
        """A RenderContext on this graph's GL context (for tests and scripts without a Renderer)."""
        return RenderContext(self.gl, self.caps, **kwargs)

    def set_profiling(self, on: bool) -> None:
        """Time each pass in execute() (on), or run the passes bare (off)."""
        self.profiling = bool(on)

    @property
    def timing_method(self) -> str:
        """'timer-query', 'finish+wall', or 'off' while profiling is off."""
        return self._timers[0].method if (self.profiling and self._timers) else "off"

    def last_frame_ms(self) -> float:
        """The passes' latest times summed, without statistics and without waiting on the GPU
        (with timer queries it is a frame or two old)."""
        return sum(times.values[-1] for times in self._times if times.values)

    def profile(self) -> Profile:
        """Per-pass GPU ms per frame (rolling mean/min/max/p95) and how it was measured."""
        if self.profiling and self.caps.timer_queries:
            # Only a pass with no sample yet waits for its latest query: the others' results
            # arrive in execute(), each once.
            for timer, times in zip(self._timers, self._times):
                if not times.values:
                    timer.resolve()
                    ms = timer.take()
                    if ms is not None:
                        times.add(ms)
        passes = {p: s for p, t in zip(self.order, self._times) if (s := t.stats()) is not None}
        return Profile(self.timing_method, self.frames, self._window, passes, self._cpu.stats())

    # -- outputs -----------------------------------------------------------------------------
    def get_output(self, ref: str):
        """The moderngl texture array (or buffer) of marked output 'Pass.pin'."""
        if ref in self.plan.unavailable:
            raise GraphError(f"output '{ref}' is not produced: {self.plan.unavailable[ref]}")
        if ref not in self.plan.outputs:
            raise GraphError(f"'{ref}' is not a marked output of graph '{self.graph_name}'"
                             f"{did_you_mean(ref, self.plan.outputs)}; mark it with mark_output('{ref}') "
                             f"(marked: {', '.join(self.plan.outputs) or '(none)'})")
        return self.resources[ref]

    def read_output(self, ref: str, flip_y: bool = False) -> np.ndarray:
        """Marked output as numpy (layers, h, w, components); rows bottom-up as GL stores them
        unless `flip_y`. For tests and image files, not per frame. Buffers: raw uint8 bytes."""
        obj = self.get_output(ref)
        res = self.plan.resources[ref]
        if res.kind is PinKind.BUFFER:
            return np.frombuffer(obj.read(), np.uint8).copy()
        f = get_format(res.fmt)
        a = np.frombuffer(obj.read(), NUMPY_DTYPES[f.dtype]).reshape(
            res.layers, res.size[1], res.size[0], f.components).copy()
        return a[:, ::-1] if flip_y else a

    # -- report ------------------------------------------------------------------------------
    def _build_report(self, extra: list) -> CompileReport:
        plan = self.plan
        infos = []
        for name, r in plan.resources.items():
            sharing = [o for o in plan.slots[r.slot].resources if o != name]
            infos.append(ResourceInfo(name, [name, *r.readers], r.fmt, r.size, r.layers, r.bytes, sharing,
                                      r.kind.value, (r.first, r.last), r.marked, r.internal))
        defines = {p: dict(self.passes[p].defines() or {}) for p in self.order}
        timing = f"{timing_method(self.caps.timer_queries)} on {self.caps.renderer}"
        return CompileReport(self.graph_name, plan.size, plan.views, list(plan.order), dict(plan.pruned),
                             infos, plan.total_bytes, plan.unaliased_bytes, defines, list(plan.outputs),
                             dict(plan.unavailable), [], extra, timing)

    def report(self) -> CompileReport:
        """The compile report (the same object each call, so subsystems can append to it)."""
        return self._report

    def add_report(self, entry) -> None:
        """Append an entry (anything with a readable str(), e.g. GpuScene.report()) to the report."""
        self._report.extra.append(entry)

    def __repr__(self) -> str:
        return f"CompiledGraph({self.graph_name!r}, order={self.order}, size={self.size}, views={self.views})"
