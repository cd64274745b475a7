"""The lighting passes that read the G-buffer: DirectLighting (every pixel, no rays), RTShadows
and RTReflections (only the pixels whose effect needs their rays: from the compaction's list,
dispatched indirectly, or from the whole image in small tiles, see PIXELS_2D)."""
from __future__ import annotations

from ..gpu.bindings import BINDINGS
from ..materials.effect import Effect
from ..rendergraph.render_pass import Reflection, RenderPass
from ._common import (
    GBUFFER_PINS,
    GBUFFER_UNITS,
    bind_scene,
    build_compute,
    effect_defines,
    effects_used,
    groups_2d,
    ray_group,
    ray_group_defines,
    register,
    scene_defines,
    unused_effect_reason,
)
from .compaction import DISPATCH_OFFSET, pixel_list_bytes
from .gbuffer import OUTPUTS

GBUFFER_FORMATS = {pin: OUTPUTS[pin][0] for pin in GBUFFER_PINS}
PASS_SSBO_0 = BINDINGS["RAYVR_PASS_SSBO_0"]


def add_gbuffer_inputs(r: Reflection) -> None:
    """Declare the G-buffer pins a lighting pass reads (GBUFFER_PINS, in the writers' formats)."""
    for pin in GBUFFER_PINS:
        r.add_input(pin, f"G-buffer {pin}").format(GBUFFER_FORMATS[pin])


def use_gbuffer(data) -> None:
    """Bind the G-buffer inputs to the sampler units glsl/gbuffer.glsl reads (GBUFFER_UNITS)."""
    for pin, unit in zip(GBUFFER_PINS, GBUFFER_UNITS.values()):
        data[pin].use(location=unit)


class _GBufferLightingPass(RenderPass):
    """Shared anatomy: G-buffer inputs on fixed sampler units, one rgba16f radiance output."""

    SHADER = ""
    OUTPUT = "color"
    OUTPUT_DESC = ""
    PIXEL_LIST: str | None = None   # input pin of the pixel list, for indirect dispatch
    SALT = 0
    # A pass with a pixel list may instead run over the whole image in TILE-sized workgroups, where
    # the pixels whose effect needs no such rays leave at once: True, False (the list), or None
    # (the image unless a material is PATH_TRACED). Same pixels, same random numbers, same image.
    # Neighbouring pixels in one warp trace alike rays; the list's tiles come in random order and
    # a warp often straddles two of them.
    PIXELS_2D: bool | None = None
    TILE = (8, 4)   # one warp (ray_group spreads it over views)
    VIEW_GROUP: int | None = None   # views a workgroup spans in a camera grid (None: passes._common.VIEW_GROUP)

    def reflect(self, cd):
        r = Reflection()
        add_gbuffer_inputs(r)
        if self.PIXEL_LIST:
            pin = r.add_input(self.PIXEL_LIST, "pixels to work on (EffectCompaction)").buffer(
                pixel_list_bytes(cd.size, cd.views))
            if self._dispatch_2d(cd):
                pin.unused("runs over the whole image: no material is PATH_TRACED")
        r.add_output(self.OUTPUT, self.OUTPUT_DESC).format("rgba16f")
        return r

    def shader_defines(self) -> dict:
        return {}

    def compile(self, ctx, cd):
        self._defines = {**scene_defines(ctx), **effect_defines(), **GBUFFER_UNITS,
                         "RNG_SALT": self.SALT, **self.shader_defines()}
        self._pixels_2d = bool(self.PIXEL_LIST) and self._dispatch_2d(cd)
        self._group = ray_group(cd.views, self.TILE, self.VIEW_GROUP)
        self._defines.update(PIXELS_2D=int(self._pixels_2d), **ray_group_defines(self._group))
        if self.PIXEL_LIST and not self._pixels_2d:
            self._defines["PIXEL_LIST_SSBO"] = PASS_SSBO_0
        self._prog = build_compute(ctx.gl, self.SHADER, self._defines)

    def _dispatch_2d(self, cd) -> bool:
        if self.PIXELS_2D is not None:
            return self.PIXELS_2D
        # A PATH_TRACED pixel may be on the path tracer's list instead of this one: only the list knows.
        used = effects_used(cd)
        return used is not None and Effect.PATH_TRACED not in used

    def set_uniforms(self, prog) -> None:
        """Properties that are uniforms; set in execute() because programs are cached and shared
        between passes with the same defines."""

    def defines(self) -> dict:
        return dict(getattr(self, "_defines", {}) or self.shader_defines())

    def execute(self, ctx, data):
        bind_scene(ctx)
        self.set_uniforms(self._prog)
        use_gbuffer(data)
        data[self.OUTPUT].bind_to_image(0, read=False, write=True)
        if not self.PIXEL_LIST:
            self._prog.run(*groups_2d(data.size, data.views))
        elif self._pixels_2d:   # the shader declares no list (the compaction pass was pruned)
            self._prog.run(*groups_2d(data.size, data.views, self._group))
        else:
            pixels = data[self.PIXEL_LIST]
            pixels.bind_to_storage_buffer(PASS_SSBO_0)
            self._prog.run_indirect(pixels, DISPATCH_OFFSET)
        ctx.gl.memory_barrier()


def _background(value):
    return [float(v) for v in value][:3]


@register
class DirectLighting(_GBufferLightingPass):
    """Emission + unshadowed direct light (punctual and emissive-triangle lights) for every pixel;
    the sky gets `background`. RASTER materials use it as is. With `raster_only` the pixels whose
    effect is SHADOWS or above are left unwritten (a ray pass lights them: the hybrid graph)."""

    SHADER = "direct_lighting.comp"
    OUTPUT = "direct"
    OUTPUT_DESC = "emission + unshadowed direct light; background where nothing was drawn"
    SALT = 1
    PROPERTIES = {"light_samples": 1, "background": [0.0, 0.0, 0.0], "raster_only": False}

    def shader_defines(self):
        return {"LIGHT_SAMPLES": max(1, int(self.light_samples)), "SHADE_SHADOWS": 0,
                "RASTER_ONLY": int(bool(self.raster_only))}

    def set_uniforms(self, prog):
        prog["background"] = tuple(_background(self.background))


@register
class RTShadows(_GBufferLightingPass):
    """Emission + ray-traced shadowed direct light for the pixels whose effect is SHADOWS or above.
    Area lights get soft shadows from `light_samples` samples per pixel."""

    SHADER = "rt_shadows.comp"
    OUTPUT = "shadowed"
    OUTPUT_DESC = "emission + shadowed direct light (listed pixels only)"
    PIXEL_LIST = "pixels"
    SALT = 2
    PROPERTIES = {"light_samples": 1}
    # H100, tauray, all SHADOWS (the list is nearly full), list / 8x4 tiles / 8x8 tiles: stereo
    # 2x1440x1600 1.69 / 1.78 / 1.72 ms; 1x4096x5464 7.89 / 8.14 / 7.88; 64x512x683 camera grid,
    # tiles over 4 views (ray_group) 8.77 / 8.52 / 8.15. At 56559cc, 8x8 tiles over 4 / 8 views
    # (4x4 / 4x2 pixels each): 7.18 / 6.99 ms (one 4096x5464 view: 6.95).
    TILE = (8, 8)
    VIEW_GROUP = 8

    def skip_reason(self, cd):
        return unused_effect_reason(cd, Effect.SHADOWS)

    def shader_defines(self):
        return {"LIGHT_SAMPLES": max(1, int(self.light_samples)), "SHADE_SHADOWS": 1}


@register
class RTReflections(_GBufferLightingPass):
    """Mirror and glossy (GGX VNDF) reflections for the pixels whose effect is REFLECTIONS or above,
    `max_bounces` deep; reflected hits are shaded with ray-traced shadows. The output is the
    reflected radiance already weighted by the specular BSDF (the composite adds it).
    Runs over the whole image in 8x4 tiles unless a material is PATH_TRACED (H100, tauray, 40% of
    the pixels reflective: list 5.1 ms, 8x8 tiles 2.8, 8x4 2.48, 4x8 2.45, 16x2 2.51, 32x1 2.57)."""

    SHADER = "rt_reflections.comp"
    OUTPUT = "reflection"
    OUTPUT_DESC = "specular-weighted reflected radiance (listed pixels only)"
    PIXEL_LIST = "pixels"
    SALT = 3
    PROPERTIES = {"max_bounces": 1, "light_samples": 1, "background": [0.0, 0.0, 0.0]}

    def skip_reason(self, cd):
        return unused_effect_reason(cd, Effect.REFLECTIONS)

    def shader_defines(self):
        return {"MAX_BOUNCES": max(1, int(self.max_bounces)), "LIGHT_SAMPLES": max(1, int(self.light_samples)),
                "SHADE_SHADOWS": 1}

    def set_uniforms(self, prog):
        prog["background"] = tuple(_background(self.background))
