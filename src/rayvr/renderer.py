"""`rv.Renderer`: a scene, a render graph and (optionally) a sink, driven frame by frame.

    with rv.Renderer(scene, rv.graphs.hybrid(), sink=rv.xr.SimulatedHeadset()) as r:
        for frame in r.frames(300):
            frame.materials["Floor"].effect = rv.Effect.REFLECTIONS
        print(r.profile())

The Renderer owns the GpuScene and the compiled graph. Per frame Python does a fixed amount of
work: one views-SSBO upload for all views, the scene's per-frame update, the graph's fixed list of
dispatches. It recompiles the graph only when the set of effects the materials use changes.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from .errors import OptionError, RayvrError
from .xr.cameras import (  # default_views: also rayvr.renderer's, as the README uses it
    camera_pose,
    default_views,
)
from .xr.jitter import halton_jitter
from .xr.views import HEADER_BYTES, VIEW_STRUCT_FLOATS, ViewSet


@dataclasses.dataclass
class Frame:
    """What `Renderer.frames()` yields: change materials here and the frame renders with them."""

    index: int
    views: ViewSet
    materials: object
    request: object = None


class Renderer:
    """Renders `graph` over `scene` for a sink's views (or fixed `views`), see the module docstring.

    `views`: a ViewSet, or an int view count (from the scene's camera); `size`: per-view pixels;
    `jitter`: sub-pixel camera jitter per frame (default: when a pass of the compiled graph asks
    for it in its reflection, as TAA does).
    `first_frame`: the first frame's index (the renderer's random streams and TAA jitter follow
    the frame index, so renders started at disjoint frame ranges have independent noise).
    `gpu_scene`: a GpuScene of `scene` on `gpu` to render from instead of uploading the scene
    again (one loaded scene serves many Renderers one after the other; close() leaves it loaded).
    Without a sink the Renderer renders `render(view_set)` calls for its fixed views.
    """

    def __init__(self, scene, graph, sink=None, views=None, size=None, gpu=None, profiling: bool = True,
                 jitter: bool | None = None, first_frame: int = 0, gpu_scene=None):
        from .gpu import get_context

        if int(first_frame) != first_frame or not 0 <= first_frame < 2 ** 32:
            raise OptionError(f"Renderer: first_frame must be an integer in [0, 2^32), got {first_frame!r}")

        self.scene = scene
        self.graph = graph
        self.sink = sink
        self.gpu = gpu or get_context()
        self.gl = self.gpu.gl
        if sink is not None:
            self.view_count, self.size = int(sink.view_count), tuple(sink.size)
            self.view_set = None
        elif isinstance(views, ViewSet):
            self.view_set = views
            self.view_count, self.size = len(views), tuple(views.size)
        else:
            self.view_set = default_views(scene, int(views or 1), size or (256, 256))
            self.view_count, self.size = len(self.view_set), tuple(self.view_set.size)
        if size is not None and tuple(size) != self.size:
            raise OptionError(f"Renderer: size {tuple(size)} differs from the views' {self.size}; "
                              f"pass one or the other")
        from .scene.gpu_scene import GpuScene

        if gpu_scene is not None and (gpu_scene.scene is not scene or gpu_scene.gpu is not self.gpu):
            raise OptionError("Renderer: gpu_scene was loaded from another scene or GPU context; pass the GpuScene "
                              "of this scene on this context, or none")
        self._owns_scene = gpu_scene is None   # a shared GpuScene stays with its owner on close()
        self.gpu_scene = GpuScene(self.gpu, scene) if gpu_scene is None else gpu_scene
        self.views_buffer = self.gl.buffer(reserve=HEADER_BYTES + 4 * VIEW_STRUCT_FLOATS * self.view_count)
        self.profiling = profiling
        self.frame_index = int(first_frame)
        self.sample_index = 0   # frames accumulated since the views or materials last changed
        self._accum_key = None
        self.compiles = 0
        self.compiled = None
        self._materials_version = None
        self._effects = None
        self._opened = False
        self._jitter_asked = jitter
        self._compile()

    # -- compile -----------------------------------------------------------------------------
    def _compile(self) -> None:
        if self.compiled is not None:
            self.compiled.release()
        self._effects = frozenset(self.scene.effects_used())
        self._materials_version = self.scene.materials.version
        self.compiled = self.graph.compile(scene=self.scene, size=self.size, views=self.view_count,
                                           gpu=self.gpu, gpu_scene=self.gpu_scene,
                                           extra_report=[self.gpu_scene.report()], profiling=self.profiling)
        self.compiles += 1
        # Sub-pixel jitter (Halton 2,3) only helps a graph that resolves it over time.
        self._jitter = self.compiled.plan.wants_jitter if self._jitter_asked is None else bool(self._jitter_asked)

    def recompile(self) -> None:
        """Compile the graph again, keeping the GpuScene: after `graph.update_pass(...)` or other
        graph edits (the compiled graph holds the pass instances it was compiled with)."""
        self._compile()

    def _maybe_recompile(self) -> None:
        version = self.scene.materials.version
        if version == self._materials_version:
            return
        self._materials_version = version
        if frozenset(self.scene.effects_used()) != self._effects:
            self._compile()

    # -- frames ------------------------------------------------------------------------------
    def render(self, view_set: ViewSet | None = None) -> None:
        """Render one frame of `view_set` (default: the Renderer's fixed views)."""
        from .rendergraph.render_pass import RenderContext

        view_set = view_set or self.view_set
        if view_set is None:
            raise RayvrError("Renderer.render(): no views; pass a ViewSet or use frames() with a sink")
        if len(view_set) != self.view_count or tuple(view_set.size) != self.size:
            raise OptionError(f"Renderer.render(): got {len(view_set)} views of {view_set.size}, compiled for "
                              f"{self.view_count} of {self.size}; make a new Renderer for another size")
        self._maybe_recompile()
        origin = view_set.origin()
        self.gpu_scene.update(origin)
        # Accumulation restarts when the views (ViewSet.restart_key: render-space matrices and
        # origin) or what the GpuScene uploaded (instances, lights, materials) change: the one
        # restart signal, sample_index 0.
        key = (view_set.restart_key(origin), self.gpu_scene.version)
        self.sample_index = self.sample_index + 1 if key == self._accum_key else 0
        self._accum_key = key
        jitter = halton_jitter(self.frame_index) if self._jitter else (0.0, 0.0)
        self.views_buffer.write(view_set.pack(origin, self.frame_index, self.sample_index, jitter=jitter))
        ctx = RenderContext(self.gl, self.gpu.caps, scene=self.gpu_scene, views_buffer=self.views_buffer,
                            view_set=view_set, frame_index=self.frame_index, sample_index=self.sample_index)
        self.compiled.execute(ctx)
        self.frame_index += 1

    def frames(self, n: int | None = None):
        """Yield up to `n` frames (None: until the sink ends). Each frame renders after the loop
        body ran, so material changes made on the yielded frame apply to it; then it is submitted."""
        from .xr.sink import OffscreenViews

        if self.sink is None:
            self.sink = OffscreenViews(self.view_set, frames=None)
        self._open()
        count = 0
        while n is None or count < n:
            request = self.sink.wait_frame()
            if request is None:
                break
            frame = Frame(request.index, request.views, self.scene.materials, request)
            yield frame
            if request.should_render:
                self.render(request.views)
                if self.profiling and not self.gpu.caps.timer_queries:
                    # finish+wall timing is this frame's; with timer queries the latest result is
                    # a frame or two old, so the sink keeps its own clock.
                    request.render_time_s = self._last_frame_ms() / 1e3
                self.sink.submit(self.output_texture(), request)
            else:
                self.sink.submit(None, request)
            count += 1

    def _open(self) -> None:
        if not self._opened and self.sink is not None:
            if not self.sink.start_pose_given:
                # A sink with no start pose of its own stands where the scene's camera is.
                self.sink.place(camera_pose(self.scene)[0])
            self.sink.open(self.gpu)
            self._opened = True

    def _last_frame_ms(self) -> float:
        return self.compiled.last_frame_ms()

    # -- outputs -----------------------------------------------------------------------------
    @property
    def output_name(self) -> str:
        """The primary output: the graph's first marked output that is still produced."""
        outs = self.compiled.plan.outputs
        if not outs:
            raise RayvrError(f"graph '{self.graph.name}' produces no output for this scene; "
                             f"compile report:\n{self.compiled.report()}")
        return outs[0]

    def output_texture(self, name: str | None = None):
        """The texture array of output `name` ('Pass.pin', default the primary): what the sink gets."""
        return self.compiled.get_output(name or self.output_name)

    def read_output(self, name: str | None = None, flip_y: bool = False) -> np.ndarray:
        """Output `name` ('Pass.pin', default the primary) as numpy (views, h, w, c); row 0 is the
        bottom row (GL) unless `flip_y`. A readback: for tests and files, not per frame."""
        return self.compiled.read_output(name or self.output_name, flip_y=flip_y)

    def profile(self):
        """Per-pass GPU ms per frame (see rayvr.rendergraph.profile), and the rays the ray passes
        traced per view in the last frame whose GPU counters came back (`rays_per_view`, a list,
        and `rays_total`; a frame or two old: `compiled.ray_counts()` waits for the exact last)."""
        return self.compiled.profile()

    def report(self):
        """The graph's compile report (order, pruned passes and why, resources) with the scene's."""
        return self.compiled.report()

    # -- life --------------------------------------------------------------------------------
    def close(self) -> None:
        """Close the sink and free the compiled graph, the passes' own GPU objects, the GpuScene
        and the views buffer."""
        if self.sink is not None and self._opened:
            self.sink.close()
            self._opened = False
        if self.compiled is not None:
            self.compiled.release()   # its resources and what each pass made (RenderPass.release)
            self.compiled = None
        if self.gpu_scene is not None:
            if self._owns_scene:
                self.gpu_scene.release()
            self.gpu_scene = None
        if self.views_buffer is not None:
            self.views_buffer.release()
            self.views_buffer = None

    def __enter__(self):
        self._open()
        return self

    def __exit__(self, *exc):
        self.close()
