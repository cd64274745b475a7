"""PathTracer pass: unidirectional path tracing with
next-event estimation and MIS, every view in one dispatch.

Two modes (property `mode`):
- "full": every pixel from the camera (`view_primary_ray`, random sub-pixel offsets): the pure
  path-traced graph (`rayvr.graphs.path_traced()`) and reference renders.
- "gbuffer": only the pixels whose material's effect is PATH_TRACED, starting at the G-buffer
  surface (so the hybrid graph path traces per material). With the optional `pixels` input (a
  pixel list of rayvr.passes.compaction) the dispatch is indirect over those pixels; without
  it the pass runs over the screen and writes 0 where the effect is not PATH_TRACED.

The output is the mean of `samples_per_pixel` paths (rgba32f); feed it to Accumulate for a
progressive render. Paths are seeded by pixel, view, frame index and sample index. The `kernel`
property picks the form: the wavefront (what "auto", the default, runs on GPUs) or the megakernel
(what it runs on software renderers).
With `lobes` the pass also writes what the first vertex's diffuse and specular lobes reflect
(`diffuse`, `specular`, rgba16f, emission excluded; where a camera ray escapes, `diffuse` is the
background) for a denoiser that demodulates them apart (rayvr.passes.SVGF); without it those
pins do not exist and nothing is allocated for them.
With the optional `decision` input (TraceDecision) the pass traces only the pixels the decision
leaves their rays (from its `pixels` list, which either mode may read, or skipping the others
over the image) and a last dispatch fills the others from their sources (trace_decision.fill);
in "full" mode it then reads the G-buffer for the fill's albedos.
"""
from __future__ import annotations

from ...errors import OptionError
from ...gpu.program_resources import program_resources
from ...gpu.records import PATH_WAVE_FIELD_BYTES, path_wave_fields
from ...gpu.rng_salts import RNG_SALTS
from ...materials.effect import Effect
from ...rendergraph.registry import register_pass
from ...rendergraph.render_pass import Access, Choice, Reflection, RenderPass
from ..compaction.pixel_list import DISPATCH_OFFSET, pixel_list_bytes
from ..dispatch import COMPUTE_GROUP, VIEW_GROUP, check_shape, groups_2d, ray_group, ray_group_defines
from ..effects import effect_defines, scene_defines, scene_transmits, unused_effect_reason
from ..gbuffer import channels
from ..trace_decision.fill import DecisionFill

MODES = ("full", "gbuffer")
KERNELS = {"auto": "the wavefront on GPUs, the megakernel on software renderers",
           "wavefront": "each vertex's rays in a dispatch of their own",
           "megakernel": "a path's rays in one invocation"}
PIXEL_LIST_GROUP = 64   # glsl/pixel_list.glsl: the local size of a dispatch over a pixel list
QUEUE_ARGS_BYTES = 16   # pt_wave.glsl PtQueue: a queue's indirect dispatch (and count)
QUEUE_HEADER_BYTES = 3 * QUEUE_ARGS_BYTES + 3 * 8 * 4   # PtQueue ahead of its slots: 3 uvec4, 3 x PTW_BINS counters
SORTABLE_SLOTS = 1 << 29   # PTW_SORT keeps a slot's octant in bits 29..31
PERSISTENT_GROUPS = 2048   # workgroups of the persistent trace kernel (benchmarks rays' persistent layout's count)
SUBGROUP_EXTENSIONS = "#extension GL_ARB_shader_ballot : require\n#extension GL_ARB_shader_group_vote : require\n" \
                      "#extension GL_ARB_gpu_shader_int64 : require\n"
# Paths per invocation per dispatch on software renderers (path_tracer.comp PT_SAMPLE_SLICES):
# llvmpipe stops an invocation's loops after 65,535 iterations in all, so a frame's paths are
# traced in dispatches of this many. 0: all in one dispatch, as on GPUs.
SOFTWARE_PATHS_PER_DISPATCH = 1


@register_pass
class PathTracer(RenderPass):
    """Path-traced radiance per pixel (the module docstring has the two modes and the outputs).

    Properties: `samples_per_pixel`, `max_bounces` (scattering events; 0: emission only),
    `rr_start` (the first bounce Russian roulette may end), `clamp` (0: off; > 0 caps each sample's
    radiance, biased), `pixel_jitter`, `mode`, `sampler` ("sobol" or "pcg"), `lobes` (the
    `diffuse` and `specular` outputs; Russian roulette then spares the first vertex) and `kernel`:
    "wavefront" traces each path vertex's rays in a dispatch of their own, the paths' state in the
    `paths` buffer between them, so that the BSDF's registers do not cost the traversal its
    occupancy; "megakernel" traces a whole path in one invocation (no state, fewer dispatches: the
    faster form on software renderers); "auto" takes the wavefront on GPUs and the megakernel on
    software renderers. Every form traces the same paths with the same random numbers.

    The wavefront's knobs: `tile` and `view_group`, the image-wide dispatches' workgroups (as the
    other ray passes', passes/dispatch.py); `compact`: after a sample's first shading, every
    dispatch runs over a queue of the paths still going (the `queue` buffer, indirect dispatch)
    instead of every slot, ended paths adding their light at once; `persistent` (implies the
    queues; needs subgroup ballots): the trace kernel's lanes take the queue's paths as their rays
    finish, in a fixed set of workgroups, so no warp waits on its longest ray; `sort_directions`
    (implies the queues): each bounce's queue sorted by the octant of its BSDF rays (a counting
    sort), so a warp's rays agree on the BVH's child order."""

    COLOR = "color"
    DIFFUSE, SPECULAR = "diffuse", "specular"
    PIXELS = "pixels"
    PATHS = "paths"
    COUNTS_NONFINITE = True   # scrubs NaN/Inf samples (glsl/nonfinite.glsl)
    QUEUE = "queue"
    COUNTS_RAYS = True
    PROPERTIES = {"mode": "full", "samples_per_pixel": 1, "max_bounces": 4, "rr_start": 3,
                  "clamp": 0.0, "pixel_jitter": True, "sampler": "sobol", "lobes": False, "kernel": "auto",
                  "tile": list(COMPUTE_GROUP), "view_group": VIEW_GROUP, "compact": False,
                  "persistent": False, "sort_directions": False}
    WHOLE = {"samples_per_pixel": (1, None, "paths per pixel a frame"), "max_bounces": (0, None, "bounces"),
             "rr_start": (0, None, "the bounce Russian roulette starts at")}
    USES_SCENE = True
    CHOICES = {"mode": MODES, "kernel": KERNELS,
               "sampler": {"sobol": Choice("Owen-scrambled Sobol, the default", 1),   # RAYVR_SAMPLER
                           "pcg": Choice("", 0)}}

    def validate_property(self, key, value):
        value = super().validate_property(key, value)
        if key == "clamp" and value < 0:
            raise OptionError(f"pass {self.name}: property 'clamp' must be >= 0 (0 = off), got {value!r}")
        return check_shape(self.name, key, value)

    def reflect(self, cd):
        r = Reflection()
        decision = DecisionFill.connected(cd)
        if self.mode == "gbuffer" or decision:
            channels.add_inputs(r)
        r.add_input(self.PIXELS, "the pixels to trace (EffectCompaction); absent: whole screen").buffer(
            pixel_list_bytes(cd.size, cd.views)).optional().indirect()
        DecisionFill.add_input(r)
        r.add_output(self.COLOR, "path-traced radiance, mean of samples_per_pixel paths").format("rgba32f")
        if self.lobes:
            r.add_output(self.DIFFUSE, "what the first vertex's diffuse lobe reflects (emission excluded; "
                                       "the background where a camera ray escapes)").format("rgba16f")
            r.add_output(self.SPECULAR, "what its specular lobe reflects").format("rgba16f")
        if self.kernel != "megakernel":
            slots = self.wave_slots(cd.size, cd.views)
            r.add_output(self.PATHS, "the wavefront's path state between its dispatches (scratch)").buffer(
                slots * self.wave_slot_bytes(cd.scene))
            if self.compact or self.persistent or self.sort_directions:
                r.add_output(self.QUEUE, "the wavefront's queues of paths still going (scratch)").buffer(
                    QUEUE_HEADER_BYTES + 2 * 4 * slots).indirect()
        return r

    @staticmethod
    def wave_has_medium(scene) -> bool:
        """Whether the wavefront's state keeps a path's medium (scene_transmits). The buffer's size
        and the shaders' PTW_HAS_MEDIUM both follow it."""
        return scene_transmits(scene)

    def wave_slot_bytes(self, scene=None) -> int:
        """Bytes of the wavefront's state per path slot (wave_has_medium: one field more)."""
        fields = path_wave_fields(PTW_HAS_MEDIUM=self.wave_has_medium(scene), PT_LOBES=bool(self.lobes))
        return fields * PATH_WAVE_FIELD_BYTES

    def workgroup(self, views: int) -> tuple[int, int, int]:
        """The image-wide dispatches' workgroup shape (x, y, views) of `tile` and `view_group`."""
        return ray_group(views, tuple(self.tile), self.view_group)

    def wave_slots(self, size, views: int) -> int:
        """Path slots of the wavefront's state: one per invocation of the image-wide dispatch (its
        workgroups cover the image's edges, and a slot is its invocation's index), which is also
        at least a pixel list's length (one entry a pixel at most)."""
        group = self.workgroup(views)
        gx, gy, gz = groups_2d(size, views, group)
        return gx * gy * gz * group[0] * group[1] * group[2]

    def skip_reason(self, cd):
        if self.mode != "gbuffer":
            return None
        return unused_effect_reason(cd, Effect.PATH_TRACED)

    def compile(self, ctx, cd):
        listed = self.PIXELS in cd.input_formats
        images = [(self.COLOR, "rgba32f", "whole")]
        if self.lobes:
            images += [(self.DIFFUSE, "rgba16f", "diffuse"), (self.SPECULAR, "rgba16f", "specular")]
        self._fill = DecisionFill(images, Effect.PATH_TRACED if self.mode == "gbuffer" else 0,
                                  color_from_lobes=bool(self.lobes))
        self._fill.compile(ctx, cd)
        self._defines = {**scene_defines(ctx), **effect_defines(), "RNG_SALT": RNG_SALTS["path_tracer"],
                         "PT_FROM_GBUFFER": int(self.mode == "gbuffer"), "PIXEL_LIST_INPUT": int(listed),
                         "RAYVR_SAMPLER": self.choice_define("sampler"), "PT_LOBES": int(bool(self.lobes)),
                         **self._fill.defines()}
        software = getattr(getattr(ctx, "caps", None), "is_software", False)
        self._wave = self.kernel == "wavefront" or (self.kernel == "auto" and not software)
        self._defines["PT_WAVEFRONT"] = int(self._wave)   # named in the compile report
        # the wavefront traces one ray per invocation and dispatch: llvmpipe's loop limit is never near
        self._slice = int(SOFTWARE_PATHS_PER_DISPATCH) if software and not self._wave else 0
        self._defines["PT_SAMPLE_SLICES"] = self._slice
        self._listed = listed
        self._group = self.workgroup(cd.views)
        self._defines.update(ray_group_defines(self._group))
        self._groups = groups_2d(cd.size, cd.views, self._group)
        self._compact = self._wave and bool(self.compact or self.persistent or self.sort_directions)
        self._persistent = self._wave and bool(self.persistent)
        self._sort = self._wave and bool(self.sort_directions)
        if self._persistent and not getattr(getattr(ctx, "caps", None), "subgroups", False):
            raise OptionError(f"pass {self.name}: property 'persistent' needs subgroup ballots "
                              f"(GL_ARB_shader_ballot), which this driver lacks; set it False")
        if self._wave:
            self._defines["PTW_HAS_MEDIUM"] = int(self.wave_has_medium(cd.scene))
            self._defines["PTW_COMPACT"] = int(self._compact)
            self._defines["PTW_SORT"] = int(self._sort)
            self._defines["PTW_GROUP_SIZE"] = PIXEL_LIST_GROUP if listed else self._group[0] * self._group[1] * self._group[2]
            self._shade = self.compute_program(ctx.gl, "pt_wave_shade.comp", self._defines)
            self._trace = self.compute_program(ctx.gl, "pt_wave_trace.comp",
                                               {**self._defines, "PTW_PERSISTENT": int(self._persistent)},
                                               header=SUBGROUP_EXTENSIONS if self._persistent else "")
            self._res = program_resources(self._shade)
            self._trace_res = program_resources(self._trace)
            self._camera = self._camera_res = None
            if self.mode != "gbuffer":   # the camera rays: their code would cost the bounces' traversal registers
                self._camera = self.compute_program(ctx.gl, "pt_wave_trace.comp", {**self._defines, "PTW_CAMERA_RAYS": 1})
                self._camera_res = program_resources(self._camera)
            self._queue = self._queue_res = self._sorter = self._sort_res = None
            if self._compact:
                self._queue = self.compute_program(ctx.gl, "pt_wave_queue.comp", self._defines)
                self._queue_res = program_resources(self._queue)
            if self._sort:
                if self.wave_slots(cd.size, cd.views) >= SORTABLE_SLOTS:
                    raise OptionError(f"pass {self.name}: property 'sort_directions' takes at most "
                                      f"{SORTABLE_SLOTS - 1} path slots; render fewer pixels or set it False")
                self._sorter = self.compute_program(ctx.gl, "pt_wave_sort.comp", self._defines)
                self._sort_res = program_resources(self._sorter)
            self._slots = self.wave_slots(cd.size, cd.views)
            self._wave_size = (int(cd.size[0]), int(cd.size[1]), int(cd.views))
        else:
            self._prog = self.compute_program(ctx.gl, "path_tracer.comp", self._defines)
            self._res = program_resources(self._prog)

    def defines(self) -> dict:
        fill = self._fill.report() if hasattr(self, "_fill") else {}
        return {**getattr(self, "_defines", {}), **fill}

    def _set_uniforms(self, res) -> None:
        # with lobes Russian roulette spares the first vertex: its lobes' shares must be drawn
        rr_start = max(int(self.rr_start), 1) if self.lobes else int(self.rr_start)
        values = {"pt_samples": int(self.samples_per_pixel), "pt_max_bounces": int(self.max_bounces),
                  "pt_rr_start": rr_start, "pt_clamp": float(self.clamp),
                  "pt_pixel_jitter": bool(self.pixel_jitter)}
        for key, value in values.items():
            res.set(key, value)   # skipped where the GLSL compiler dropped the uniform

    def execute(self, ctx, data):
        res = self._res
        self._set_uniforms(res)
        if self.mode == "gbuffer":
            channels.bind_inputs(res, data)
        self._fill.bind(res, data)
        adds = self._wave or bool(self._slice)   # later dispatches add to what earlier ones stored
        res.image("dst", data[self.COLOR], read=adds)
        if self.lobes:
            res.image("dst_diffuse", data[self.DIFFUSE], read=adds)
            res.image("dst_specular", data[self.SPECULAR], read=adds)
        pixels = data.get(self.PIXELS) if self._listed else None
        if self._wave:
            self._execute_wavefront(ctx, data, pixels)
            self._fill.run(ctx, data)
            return
        if pixels is not None:
            res.buffer("PixelList", pixels)
        spp = int(self.samples_per_pixel)
        for first in range(0, spp, self._slice or spp):
            if first:
                ctx.barrier(Access.IMAGE)   # the slice before stored its share
            res.set("pt_sample_first", first)
            self._run(self._prog, pixels)
        self._fill.run(ctx, data)

    def _run(self, prog, pixels) -> None:
        if pixels is not None:
            prog.run_indirect(pixels, DISPATCH_OFFSET)
        else:
            prog.run(*self._groups)

    def _execute_wavefront(self, ctx, data, pixels) -> None:
        """Per sample, stages of (shade, trace): shade answers the last rays and makes the next
        vertex's, trace traces them. From the camera stage 0 is the trace kernel's camera ray
        alone; from the G-buffer it begins with the first vertex's shade. The last shade adds the
        sample to the outputs (compact: a path's shade adds it when the path ends)."""
        shade, trace, camera = self._res, self._trace_res, self._camera_res
        gbuffer = camera is None
        programs = tuple(p for p in (shade, trace, camera, self._queue_res, self._sort_res) if p is not None)
        queue = self._queue_buffer = data[self.QUEUE] if self._compact else None
        for res in programs:
            res.buffer("PtWave", data[self.PATHS])
            res.set("pt_wave_paths", self._slots)
            res.set("pt_wave_size", self._wave_size)
            if queue is not None:
                res.buffer("PtQueue", queue)
                res.set("ptw_groups", self._groups)
                res.set("ptq_in", 2)
            self._fill.bind(res, data)
            if pixels is not None:
                res.buffer("PixelList", pixels)
        for res in programs[1:]:   # their generators' (the camera's, BLEND decisions')
            self._set_uniforms(res)
        rays = int(self.max_bounces) + (0 if gbuffer else 1)
        first = 0 if gbuffer else 1
        for k in range(int(self.samples_per_pixel)):
            for res in programs:
                res.set("pt_sample", k)
            if queue is not None:   # both queues empty
                self._queue_res.set("ptq_reset", True)
                self._queue.run(1)
                self._queue_res.set("ptq_reset", False)
                ctx.barrier(Access.STORAGE)
            if not gbuffer:
                self._run(self._camera, pixels)
                ctx.barrier(Access.STORAGE)
            into = 2   # the queue a stage's shade reads: 2, none (every slot) at the first stage
            for stage in range(first, rays + 1):
                shade.set("pt_stage", stage)
                shade.set("pt_last", stage == rays)
                if queue is None:
                    self._run(self._shade, pixels)
                else:   # sorted: the shading fills queue 0, the sort moves it to queue 1
                    out = 0 if into != 0 or self._sort else 1
                    self._run_queue(self._shade, shade, pixels, into, out)
                if stage < rays:
                    ctx.barrier(Access.STORAGE)
                    if queue is None:
                        self._run(self._trace, pixels)
                    else:   # the queue's size for the dispatches over it
                        self._queue_res.set("ptq_in", into)
                        self._queue_res.set("ptq_out", out)
                        self._queue.run(1)
                        ctx.barrier(Access.INDIRECT)
                        into = out
                        if self._sort:
                            self._sorter.run_indirect(queue, 0)
                            ctx.barrier(Access.STORAGE)
                            into = 1
                        if self._persistent:
                            trace.set("ptq_in", into)
                            self._trace.run(PERSISTENT_GROUPS)
                        else:
                            self._run_queue(self._trace, trace, pixels, into, 2)
                    ctx.barrier(Access.STORAGE)
            ctx.barrier(Access.IMAGE, Access.STORAGE)   # the next sample adds to the outputs

    def _run_queue(self, prog, res, pixels, into: int, out: int) -> None:
        """A compact wavefront dispatch: over queue `into` (indirect), or every slot when it is 2;
        a shading one appends to queue `out`."""
        res.set("ptq_in", into)
        res.set("ptq_out", out)
        if into == 2:
            self._run(prog, pixels)
        else:
            prog.run_indirect(self._queue_buffer, into * QUEUE_ARGS_BYTES)
