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
progressive render. Paths are seeded by pixel, view, frame index and sample index (PCG).
With `lobes` the pass also writes what the first vertex's diffuse and specular lobes reflect
(`diffuse`, `specular`, rgba16f, emission excluded; where a camera ray escapes, `diffuse` is the
background) for a denoiser that demodulates them apart (rayvr.passes.SVGF); without it those
pins do not exist and nothing is allocated for them.
"""
from __future__ import annotations

from ...errors import OptionError
from ...gpu.program_resources import program_resources
from ...materials.effect import Effect
from ...rendergraph.registry import register_pass
from ...rendergraph.render_pass import Access, Reflection, RenderPass
from ..compaction.pixel_list import DISPATCH_OFFSET, pixel_list_bytes
from ..dispatch import groups_2d, ray_group, ray_group_defines
from ..effects import effect_defines, scene_defines, unused_effect_reason
from ..gbuffer import channels

MODES = ("full", "gbuffer")
SAMPLERS = {"sobol": 1, "pcg": 0}   # glsl/sampling.glsl RAYVR_SAMPLER
# Paths per invocation per dispatch on software renderers (path_tracer.comp PT_SAMPLE_SLICES):
# llvmpipe stops an invocation's loops after 65,535 iterations in all, so a frame's paths are
# traced in dispatches of this many. 0: all in one dispatch, as on GPUs.
SOFTWARE_PATHS_PER_DISPATCH = 1
RNG_SALT = 7


@register_pass
class PathTracer(RenderPass):
    """Path-traced radiance per pixel (see the module docstring for the two modes).

    Properties: `samples_per_pixel` (paths per pixel per frame), `max_bounces` (scattering events;
    1 = direct light only, 0 = emission only), `rr_start` (bounce from which Russian roulette
    may end a path), `clamp` (0 = off; > 0 caps each sample's radiance per channel, biased),
    `pixel_jitter` (random sub-pixel offsets in
    "full" mode: anti-aliasing once accumulated; off: pixel centres moved by the views' TAA
    jitter), `mode` ("full" or "gbuffer"), `sampler` ("sobol": hash-based Owen-scrambled Sobol,
    the default; "pcg": independent PCG hash samples, for comparisons), `lobes` (also the
    `diffuse` and `specular` outputs; then Russian roulette never ends a path at its first
    vertex, and `clamp` caps each lobe of a sample on its own)."""

    COLOR = "color"
    DIFFUSE, SPECULAR = "diffuse", "specular"
    PIXELS = "pixels"
    COUNTS_NONFINITE = True   # scrubs NaN/Inf samples (glsl/nonfinite.glsl)
    PROPERTIES = {"mode": "full", "samples_per_pixel": 1, "max_bounces": 4, "rr_start": 3,
                  "clamp": 0.0, "pixel_jitter": True, "sampler": "sobol", "lobes": False}
    USES_SCENE = True

    def validate_property(self, key, value):
        value = super().validate_property(key, value)
        if key == "sampler" and value not in SAMPLERS:
            raise OptionError(f"pass {self.name}: property 'sampler' is {value!r}; use 'sobol' (Owen-scrambled "
                              f"Sobol, the default) or 'pcg'")
        if key == "mode" and value not in MODES:
            raise OptionError(f"pass {self.name}: property 'mode' is {value!r}; use 'full' or 'gbuffer'")
        if key == "samples_per_pixel" and (int(value) != value or value < 1):
            raise OptionError(f"pass {self.name}: property 'samples_per_pixel' must be an integer >= 1, got {value!r}")
        if key in ("max_bounces", "rr_start") and (int(value) != value or value < 0):
            raise OptionError(f"pass {self.name}: property '{key}' must be an integer >= 0, got {value!r}")
        if key == "clamp" and value < 0:
            raise OptionError(f"pass {self.name}: property 'clamp' must be >= 0 (0 = off), got {value!r}")
        return value

    def reflect(self, cd):
        r = Reflection()
        if self.mode == "gbuffer":
            channels.add_inputs(r)
            r.add_input(self.PIXELS, "PATH_TRACED pixels (EffectCompaction); absent: whole screen").buffer(
                pixel_list_bytes(cd.size, cd.views)).optional().indirect()
        r.add_output(self.COLOR, "path-traced radiance, mean of samples_per_pixel paths").format("rgba32f")
        if self.lobes:
            r.add_output(self.DIFFUSE, "what the first vertex's diffuse lobe reflects (emission excluded; "
                                       "the background where a camera ray escapes)").format("rgba16f")
            r.add_output(self.SPECULAR, "what its specular lobe reflects").format("rgba16f")
        return r

    def skip_reason(self, cd):
        if self.mode != "gbuffer":
            return None
        return unused_effect_reason(cd, Effect.PATH_TRACED)

    def compile(self, ctx, cd):
        listed = self.mode == "gbuffer" and self.PIXELS in cd.input_formats
        self._defines = {**scene_defines(ctx), **effect_defines(), "RNG_SALT": RNG_SALT,
                         "PT_FROM_GBUFFER": int(self.mode == "gbuffer"), "PIXEL_LIST_INPUT": int(listed),
                         "RAYVR_SAMPLER": SAMPLERS[self.sampler], "PT_LOBES": int(bool(self.lobes))}
        software = getattr(getattr(ctx, "caps", None), "is_software", False)
        self._slice = int(SOFTWARE_PATHS_PER_DISPATCH) if software else 0
        self._defines["PT_SAMPLE_SLICES"] = self._slice
        self._listed = listed
        self._group = ray_group(cd.views)
        self._defines.update(ray_group_defines(self._group))
        self._prog = self.compute_program(ctx.gl, "path_tracer.comp", self._defines)
        self._res = program_resources(self._prog)
        self._groups = groups_2d(cd.size, cd.views, self._group)

    def defines(self) -> dict:
        return dict(getattr(self, "_defines", {}))

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
        res.image("dst", data[self.COLOR])
        if self.lobes:
            res.image("dst_diffuse", data[self.DIFFUSE])
            res.image("dst_specular", data[self.SPECULAR])
        pixels = data.get(self.PIXELS) if self._listed else None
        if pixels is not None:
            res.buffer("PixelList", pixels)
        spp = int(self.samples_per_pixel)
        for first in range(0, spp, self._slice or spp):
            if first:
                ctx.barrier(Access.IMAGE)   # the slice before stored its share
            res.set("pt_sample_first", first)
            if pixels is not None:
                self._prog.run_indirect(pixels, DISPATCH_OFFSET)
            else:
                self._prog.run(*self._groups)

