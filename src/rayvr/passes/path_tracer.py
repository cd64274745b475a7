"""PathTracer pass: unidirectional path tracing with
next-event estimation and MIS, every view in one dispatch.

Two modes (property `mode`):
- "full": every pixel from the camera (`view_primary_ray`, random sub-pixel offsets): the pure
  path-traced graph (`rayvr.graphs_pt.path_traced()`) and reference renders.
- "gbuffer": only the pixels whose material's effect is PATH_TRACED, starting at the G-buffer
  surface (so the hybrid graph path traces per material). With the optional `pixels` input (a
  pixel list of rayvr.passes.compaction) the dispatch is indirect over those pixels; without
  it the pass runs over the screen and writes 0 where the effect is not PATH_TRACED.

The output is the mean of `samples_per_pixel` paths (rgba32f); feed it to Accumulate for a
progressive render. Paths are seeded by pixel, view, frame index and sample index (PCG).
"""
from __future__ import annotations

from ..errors import OptionError
from ..materials.effect import Effect
from ..rendergraph.render_pass import Reflection, RenderPass
from ._common import (
    GBUFFER_UNITS,
    bind_scene,
    build_compute,
    effect_defines,
    groups_2d,
    ray_group,
    ray_group_defines,
    register,
    require_scene,
    scene_defines,
    unused_effect_reason,
)
from .compaction import DISPATCH_OFFSET, pixel_list_bytes
from .lighting import PASS_SSBO_0, add_gbuffer_inputs, use_gbuffer

MODES = ("full", "gbuffer")
RNG_SALT = 7


@register
class PathTracer(RenderPass):
    """Path-traced radiance per pixel (see the module docstring for the two modes).

    Properties: `samples_per_pixel` (paths per pixel per frame), `max_bounces` (scattering events;
    1 = direct light only, 0 = emission only), `rr_start` (bounce from which Russian roulette
    may end a path), `clamp` (0 = off; > 0 caps each sample's radiance per channel, biased),
    `background` (radiance of rays that escape), `pixel_jitter` (random sub-pixel offsets in
    "full" mode: anti-aliasing once accumulated; off: pixel centres moved by the views' TAA
    jitter), `mode` ("full" or "gbuffer")."""

    COLOR = "color"
    PIXELS = "pixels"
    PROPERTIES = {"mode": "full", "samples_per_pixel": 1, "max_bounces": 4, "rr_start": 3,
                  "clamp": 0.0, "background": [0.0, 0.0, 0.0], "pixel_jitter": True}

    def validate_property(self, key, value):
        value = super().validate_property(key, value)
        if key == "mode" and value not in MODES:
            raise OptionError(f"pass {self.name}: property 'mode' is {value!r}; use 'full' or 'gbuffer'")
        if key == "samples_per_pixel" and (int(value) != value or value < 1):
            raise OptionError(f"pass {self.name}: property 'samples_per_pixel' must be an integer >= 1, got {value!r}")
        if key in ("max_bounces", "rr_start") and (int(value) != value or value < 0):
            raise OptionError(f"pass {self.name}: property '{key}' must be an integer >= 0, got {value!r}")
        if key == "clamp" and value < 0:
            raise OptionError(f"pass {self.name}: property 'clamp' must be >= 0 (0 = off), got {value!r}")
        if key == "background":
            try:
                value = [float(v) for v in value]
            except (TypeError, ValueError):
                value = []
            if len(value) != 3:
                raise OptionError(f"pass {self.name}: property 'background' must be three numbers (linear RGB)")
        return value

    def reflect(self, cd):
        r = Reflection()
        if self.mode == "gbuffer":
            add_gbuffer_inputs(r)
            r.add_input(self.PIXELS, "PATH_TRACED pixels (EffectCompaction); absent: whole screen").buffer(
                pixel_list_bytes(cd.size, cd.views)).optional()
        r.add_output(self.COLOR, "path-traced radiance, mean of samples_per_pixel paths").format("rgba32f")
        return r

    def skip_reason(self, cd):
        if self.mode != "gbuffer":
            return None
        return unused_effect_reason(cd, Effect.PATH_TRACED)

    def compile(self, ctx, cd):
        require_scene(ctx, self)
        listed = self.mode == "gbuffer" and self.PIXELS in cd.input_formats
        self._defines = {**scene_defines(ctx), **effect_defines(), "RNG_SALT": RNG_SALT,
                         "PT_FROM_GBUFFER": int(self.mode == "gbuffer"), "PT_PIXEL_LIST": int(listed)}
        if self.mode == "gbuffer":
            self._defines.update(GBUFFER_UNITS, PIXEL_LIST_SSBO=PASS_SSBO_0)
        self._listed = listed
        self._group = ray_group(cd.views)
        self._defines.update(ray_group_defines(self._group))
        self._prog = build_compute(ctx.gl, "pt/path_tracer.comp", self._defines)

    def defines(self) -> dict:
        return dict(getattr(self, "_defines", {}))

    def _set_uniforms(self, prog) -> None:
        values = {"pt_samples": int(self.samples_per_pixel), "pt_max_bounces": int(self.max_bounces),
                  "pt_rr_start": int(self.rr_start), "pt_clamp": float(self.clamp),
                  "pt_background": tuple(self.background), "pt_pixel_jitter": bool(self.pixel_jitter)}
        for key, value in values.items():
            if key in prog:   # the GLSL compiler drops unused uniforms
                prog[key].value = value

    def execute(self, ctx, data):
        bind_scene(ctx)
        pixels = data.get(self.PIXELS) if self._listed else None
        prog = self._prog
        self._set_uniforms(prog)
        if self.mode == "gbuffer":
            use_gbuffer(data)
        data[self.COLOR].bind_to_image(0, read=False, write=True)
        if pixels is not None:
            pixels.bind_to_storage_buffer(PASS_SSBO_0)
            prog.run_indirect(pixels, DISPATCH_OFFSET)
        else:
            prog.run(*groups_2d(data.size, data.views, self._group))
        ctx.gl.memory_barrier()

