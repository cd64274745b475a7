"""`CompiledGraph`: the compile stage "bind": the plan's GPU objects, the compiled passes, the
memory barriers between them, and the per-frame execute loop.

Everything a frame needs (RenderData per pass, barrier bits, timers) is built here once;
`execute()` is a fixed loop of barrier + pass.execute() calls with no allocation.

Barriers come from the pins (`Pin.access_kind`): before a pass runs, the bits that make every
shader write (image store, SSBO) its inputs come from visible to the way it reads them (texture
fetch, image load, SSBO, indirect arguments), unless an earlier barrier since that write already
carried them; a pass that image-stores into an aliased texture first waits for the reads of the
slot's earlier users; internal pins (history) are made visible again each frame; after the last
pass, marked outputs are made visible to readbacks and sinks. Passes issue no barrier between
each other; a pass with several dispatches orders its own with `ctx.barrier()`.
"""
from __future__ import annotations

import time

import moderngl
import numpy as np

from ..errors import GraphError, did_you_mean
from ..gpu.textures import zero_texture
from ..gpu.timer import acquire_timer, release_timer, timing_method
from .compiler import Plan
from .formats import NUMPY_DTYPES, get_format
from .nonfinite import NonFiniteCounters
from .profile import Profile, RollingTimes
from .ray_counters import RayCounters
from .render_pass import HOST_READ_BITS, Access, PinDirection, PinKind, RenderContext, RenderData, barrier_bits
from .report import CompileReport, ResourceInfo

SHADER_WRITES = (Access.IMAGE, Access.STORAGE)   # incoherent writes: visible only after a barrier

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
        self.uses_scene = [p for p in self.order if self.passes[p].USES_SCENE]
        if self.uses_scene and gpu_scene is None:
            p = self.uses_scene[0]
            raise GraphError(f"pass {p} ({type(self.passes[p]).__name__}) needs a scene: compile the graph with "
                             f"a scene (rv.Renderer(scene, graph) does)")
        t0 = time.perf_counter()
        self.objects = [self._allocate(s.key, s.resources[0]) for s in plan.slots]
        self.resources = {name: self.objects[r.slot] for name, r in plan.resources.items()}
        ctx = RenderContext(self.gl, self.caps, scene=gpu_scene)
        for p in self.order:
            self.passes[p].compile(ctx, plan.compile_data[p])
        self.barriers_before, self.final_barrier = frame_barriers(plan)
        self.nonfinite = NonFiniteCounters(self.gl, [p for p in self.order if self.passes[p].COUNTS_NONFINITE])
        counting = any(self.passes[p].COUNTS_RAYS for p in self.order)
        self.rays = RayCounters(self.gl, plan.views) if counting else None
        self._steps = [(self._counted(p),
                        RenderData({pin: (None if res is None else self.resources[res])
                                    for pin, res in plan.bindings[p].items()}, plan.size, plan.views),
                        self.barriers_before[i])
                       for i, p in enumerate(self.order)]
        self.stage_ms = {**plan.stage_ms, "bind": (time.perf_counter() - t0) * 1e3}
        self.frames = 0
        self._window = window
        self._timers = [acquire_timer(self.gl, self.caps.timer_queries) for _ in self.order]
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
        zero_texture(tex)
        return tex

    def _counted(self, name: str):
        """Pass `name`'s execute, after binding its non-finite counter and the ray counters when
        it counts them."""
        execute = self.passes[name].execute
        nonfinite = name in self.nonfinite.slot
        rays = self.rays is not None and self.passes[name].COUNTS_RAYS
        if not (nonfinite or rays):
            return execute
        bind, bind_rays = self.nonfinite.bind, self.rays.bind if rays else None

        def run(ctx, data):
            if nonfinite:
                bind(name)
            if bind_rays is not None:
                bind_rays()
            execute(ctx, data)
        return run

    def ray_counts(self) -> list[int]:
        """Rays per view the ray passes traced in the last frame, exact (waits for the GPU); []
        when no pass traces. profile() carries the latest without waiting (a frame or two old)."""
        return self.rays.read() if self.rays is not None else []

    def nonfinite_counts(self) -> dict[str, int]:
        """{pass: non-finite samples it set to 0 since compile or reset_nonfinite()}, for every
        pass that counts (COUNTS_NONFINITE), exact: one small readback that waits for the GPU.
        profile() and report() carry the latest counts without waiting (a frame or two old)."""
        return self.nonfinite.read()

    def reset_nonfinite(self) -> None:
        self.nonfinite.reset()

    def reset_profile(self) -> None:
        """Forget the timed frames: profile() then covers only frames after this call (frames
        whose timer queries are still in flight may yet land in it)."""
        for times in (*self._times, self._cpu):
            times.values.clear()

    def release(self) -> None:
        """Free the GPU objects now: the resources, what each pass made in compile()
        (RenderPass.release) and the timers (otherwise they live as long as the GL context)."""
        for p in self.order:
            self.passes[p].release()
        self.nonfinite.release()
        if self.rays is not None:
            self.rays.release()
            self.rays = None
        for obj in self.objects:
            obj.release()
        for timer in self._timers:
            release_timer(timer)
        self.objects, self.resources, self._steps, self._timers = [], {}, [], []

    # -- per frame -------------------------------------------------------------------------
    def execute(self, ctx: RenderContext) -> None:
        """Run every kept pass once, in order (the views are layers: one call per pass)."""
        t0 = time.perf_counter()
        gl = self.gl
        if self.uses_scene:
            bind_frame_resources(ctx)
        if self.rays is not None:
            self.rays.frame_begin()
        if self.profiling:
            for (run, data, bits), timer, times in zip(self._steps, self._timers, self._times):
                if bits:
                    gl.memory_barrier(bits)
                timer.begin()
                run(ctx, data)
                timer.end()
                ms = timer.take()
                if ms is not None:
                    times.add(ms)
        else:
            for run, data, bits in self._steps:
                if bits:
                    gl.memory_barrier(bits)
                run(ctx, data)
        if self.final_barrier:
            gl.memory_barrier(self.final_barrier)
        self.nonfinite.frame_end()
        if self.rays is not None:
            self.rays.frame_end()
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
        rays = self.rays.latest() if self.rays is not None else []
        return Profile(self.timing_method, self.frames, self._window, passes, self._cpu.stats(),
                       self.nonfinite.latest(), rays, sum(rays))

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
        barriers = {p: _bit_names(bits) for p, bits in zip(self.order, self.barriers_before) if bits}
        if self.final_barrier:
            barriers["(end of frame)"] = _bit_names(self.final_barrier)
        return CompileReport(self.graph_name, plan.size, plan.views, list(plan.order), dict(plan.pruned),
                             infos, plan.total_bytes, plan.unaliased_bytes, defines, list(plan.outputs),
                             dict(plan.unavailable), [], extra, timing, dict(self.stage_ms), barriers,
                             {n: 0 for n in self.nonfinite.names})

    def report(self) -> CompileReport:
        """The compile report (the same object each call, so subsystems can append to it), with
        the latest non-finite counts the GPU has handed back (no wait: see nonfinite_counts())."""
        if self._steps:   # not released
            self._report.nonfinite = self.nonfinite.latest()
        return self._report

    def add_report(self, entry) -> None:
        """Append an entry (anything with a readable str(), e.g. GpuScene.report()) to the report."""
        self._report.extra.append(entry)

    def __repr__(self) -> str:
        return f"CompiledGraph({self.graph_name!r}, order={self.order}, size={self.size}, views={self.views})"


def bind_frame_resources(ctx: RenderContext) -> None:
    """Bind what every scene-reading pass shares: the views SSBO and the GpuScene's buffers and
    textures, at their fixed points (rayvr.gpu.bindings); once per frame, before the passes."""
    from ..gpu.bindings import BINDINGS

    if ctx.views_buffer is not None:
        ctx.views_buffer.bind_to_storage_buffer(BINDINGS["RAYVR_VIEWS_SSBO"])
    if ctx.scene is not None:
        ctx.scene.bind()


def frame_barriers(plan: Plan) -> tuple[list[int], int]:
    """(bits before each pass of plan.order, bits after the last) of a frame; see the module
    docstring. Simulated once over the fixed order, two frames long so that what a frame leaves
    pending carries into the next (the second frame's bits are the steady state): a barrier with
    bit b after a resource's last shader write makes it visible to every later access of b's kind."""
    n = len(plan.order)
    writer_access = {f"{p}.{pin.name}": pin.access_kind for p in plan.order
                     for pin in plan.reflections[p].pins.values() if pin.direction is not PinDirection.INPUT}
    written_at: dict[str, float] = {}     # resource -> step of its last shader write
    slot_read_at: dict[int, float] = {}   # slot -> last step that read it
    issued: dict[int, float] = {}         # barrier bit -> last step a barrier carried it
    before, final = [], 0
    for frame in range(2):
        before = []
        for i, p in enumerate(plan.order):
            step = frame * n + i
            refl, bind = plan.reflections[p], plan.bindings[p]
            needed = 0
            for pin in refl.pins.values():
                res = bind.get(pin.name)
                if res is None:
                    continue
                r = plan.resources[res]
                if pin.direction is PinDirection.INPUT:
                    if res in written_at:
                        needed |= _missing(barrier_bits([pin.access_kind]), issued, written_at[res])
                elif pin.direction is PinDirection.INTERNAL:
                    # history written by this pass a frame ago, read again now
                    kinds = [Access.SAMPLED, Access.IMAGE] if r.kind is PinKind.TEXTURE else [Access.STORAGE]
                    needed |= _missing(barrier_bits(kinds), issued, written_at.get(res, -1))
                elif pin.access_kind in SHADER_WRITES and r.slot in slot_read_at:
                    # an image store or SSBO write into a slot read earlier: those reads first
                    needed |= _missing(barrier_bits([pin.access_kind]), issued, slot_read_at[r.slot])
            before.append(needed)
            for bit in _bits(needed):
                issued[bit] = step
            for pin in refl.pins.values():
                res = bind.get(pin.name)
                if res is None:
                    continue
                if pin.direction is PinDirection.INPUT:
                    slot_read_at[plan.resources[res].slot] = step
                elif pin.access_kind in SHADER_WRITES:
                    written_at[res] = step
        final = 0
        for ref in plan.outputs:
            if ref in written_at and writer_access.get(ref) in SHADER_WRITES:
                final |= _missing(HOST_READ_BITS, issued, written_at[ref])
        for bit in _bits(final):
            issued[bit] = frame * n + n - 0.5
    return before, final


def _bits(mask: int):
    b = 1
    while b <= mask:
        if mask & b:
            yield b
        b <<= 1


def _missing(bits: int, issued: dict[int, int], since: int) -> int:
    """The bits of `bits` no barrier has carried after step `since`."""
    return sum(b for b in _bits(bits) if issued.get(b, -1) <= since)


_BIT_NAMES = {0x8: "texture-fetch", 0x20: "image", 0x2000: "storage", 0x40: "command", 0x400: "framebuffer",
              0x100: "texture-update", 0x200: "buffer-update", 0x80: "pixel-buffer"}


def _bit_names(mask: int) -> str:
    return "+".join(_BIT_NAMES.get(b, hex(b)) for b in _bits(mask))
