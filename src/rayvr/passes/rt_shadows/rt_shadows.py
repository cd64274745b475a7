"""RTShadows: emission + ray-traced shadowed direct light, only where a material asks for it."""
from __future__ import annotations

from ...errors import OptionError
from ...gpu.program_resources import program_resources
from ...gpu.rng_salts import RNG_SALTS
from ...materials.effect import Effect
from ...rendergraph.registry import register_pass
from ...rendergraph.render_pass import Access
from ..effects import unused_effect_reason
from ..gbuffer.lighting_pass import GBufferLightingPass, ray_properties
from ..trace_decision.fill import DecisionFill


@register_pass
class RTShadows(GBufferLightingPass):
    """Emission + ray-traced shadowed direct light for the pixels whose effect is SHADOWS or above.
    Area lights get soft shadows from `light_samples` samples per pixel. Over the whole image in
    one-warp workgroups (8x4 pixels; in a camera grid 2x1 pixels of 16 views): 8x8 tiles cost a
    third more (benchmarks/RESULTS.md has the measurements). A shadow ray takes the transmittance
    through alphaMode BLEND surfaces; `blend_roulette` > 0 lets it end by Russian roulette once that
    falls below the value (ray_query.glsl RQ_BLEND_ROULETTE: the same light in expectation, fewer
    surfaces visited, some noise; 0: the exact product, 1: a coin per surface).

    `share_light_samples` (hybrid(reuse='views') sets it; with a trace decision over several views
    and one light sample): the pixels of effect SHADOWS and REFLECTIONS it traces record their light
    sample and its visibility (`sharedLights`, scratch), and a pixel the decision flags
    DECISION_SHARED_LIGHT (a glossy lobe that another view's shaded light would not suit) traces no
    shadow ray: a second dispatch shades its own lobes towards its source pixel's sample, over that
    sample's visibility.

    `compact_tiles` (under a trace decision, over the image): a workgroup gathers the pixels with
    rays of that many tiles side by side and traces them a full warp at a time, in the tiles' order
    (glsl/tile_gather.glsl through pixel_list.glsl's RAY_PASS_COMPACT); 1: each workgroup its own
    tile; 0 (the default): 8 where the decision's foveation dithers which pixels trace (lanes of
    the warps with work 0.38 busy, 0.84 gathered), else 1 (view reuse's traced pixels are clustered:
    0.81 busy, 0.87 gathered; benchmarks/RESULTS.md, 2026-12-08)."""

    SHARED = "sharedLights"

    SHADER = "rt_shadows.comp"
    OUTPUT = "shadowed"
    OUTPUT_DESC = "emission + shadowed direct light (listed pixels only)"
    PIXEL_LIST = "pixels"
    COUNTS_RAYS = True
    LOWEST_EFFECT = Effect.SHADOWS
    SALT = RNG_SALTS["rt_shadows"]
    PROPERTIES = {"light_samples": 1, "blend_roulette": 0.0, "share_light_samples": False, "compact_tiles": 0,
                  **ray_properties(view_group=16)}
    WHOLE = {**GBufferLightingPass.WHOLE,
             "compact_tiles": (0, 32, "tiles a workgroup gathers its pixels from; 0: auto")}
    COMPACTS = True
    _sharing = False   # compiled with shared light samples (shares(cd))

    def validate_property(self, key, value):
        value = super().validate_property(key, value)
        if key == "blend_roulette" and not (isinstance(value, (int, float)) and 0.0 <= value <= 1.0):
            raise OptionError(f"pass {self.name}: property 'blend_roulette' must be a number in [0, 1] (0: the exact "
                              f"transmittance through BLEND surfaces), got {value!r}")
        return value

    def skip_reason(self, cd):
        return unused_effect_reason(cd, Effect.SHADOWS)

    def shares(self, cd) -> bool:
        """Whether the pass records and shares light samples (see the class docstring)."""
        return (bool(self.share_light_samples) and DecisionFill.connected(cd) and cd.views > 1
                and max(1, int(self.light_samples)) == 1)

    def reflect(self, cd):
        r = super().reflect(cd)
        if self.shares(cd):
            r.add_output(self.SHARED, "the traced pixels' light samples (scratch): light id, 1 / pdf, visibility"
                         ).format("rgba32ui")
        return r

    def shader_defines(self):
        return {"LIGHT_SAMPLES": max(1, int(self.light_samples)), "SHADE_SHADOWS": 1,
                "RQ_BLEND_ROULETTE": repr(float(self.blend_roulette)), "SHARED_LIGHT": int(self._sharing)}

    def compile(self, ctx, cd):
        self._sharing = self.shares(cd)
        super().compile(ctx, cd)
        self._take = None
        if self._sharing:
            self._take = program_resources(self.compute_program(ctx.gl, self.SHADER,
                                                                {**self._defines, "SHARED_LIGHT_TAKE": 1}))

    def execute(self, ctx, data):
        if self._take is None:
            super().execute(ctx, data)
            return
        self._res.image("shared_lights", data[self.SHARED], read=False, write=True)
        self.run_program(self._res, data)
        ctx.barrier(Access.IMAGE)   # the recorded samples, for the pixels that take them up
        self._take.image("shared_lights", data[self.SHARED], read=True, write=False)
        self.run_program(self._take, data)
        self._fill.run(ctx, data)
