"""RTShadows: emission + ray-traced shadowed direct light, only where a material asks for it."""
from __future__ import annotations

from ...errors import OptionError
from ...gpu.rng_salts import RNG_SALTS
from ...materials.effect import Effect
from ...rendergraph.registry import register_pass
from ..effects import unused_effect_reason
from ..gbuffer.lighting_pass import GBufferLightingPass, ray_properties


@register_pass
class RTShadows(GBufferLightingPass):
    """Emission + ray-traced shadowed direct light for the pixels whose effect is SHADOWS or above.
    Area lights get soft shadows from `light_samples` samples per pixel. Over the whole image in
    one-warp workgroups (8x4 pixels; in a camera grid 2x1 pixels of 16 views): 8x8 tiles cost a
    third more (benchmarks/RESULTS.md has the measurements). A shadow ray takes the transmittance
    through alphaMode BLEND surfaces; `blend_roulette` > 0 lets it end by Russian roulette once that
    falls below the value (ray_query.glsl RQ_BLEND_ROULETTE: the same light in expectation, fewer
    surfaces visited, some noise; 0: the exact product, 1: a coin per surface)."""

    SHADER = "rt_shadows.comp"
    OUTPUT = "shadowed"
    OUTPUT_DESC = "emission + shadowed direct light (listed pixels only)"
    PIXEL_LIST = "pixels"
    COUNTS_RAYS = True
    LOWEST_EFFECT = Effect.SHADOWS
    SALT = RNG_SALTS["rt_shadows"]
    PROPERTIES = {"light_samples": 1, "blend_roulette": 0.0, **ray_properties(view_group=16)}

    def validate_property(self, key, value):
        value = super().validate_property(key, value)
        if key == "blend_roulette" and not (isinstance(value, (int, float)) and 0.0 <= value <= 1.0):
            raise OptionError(f"pass {self.name}: property 'blend_roulette' must be a number in [0, 1] (0: the exact "
                              f"transmittance through BLEND surfaces), got {value!r}")
        return value

    def skip_reason(self, cd):
        return unused_effect_reason(cd, Effect.SHADOWS)

    def shader_defines(self):
        return {"LIGHT_SAMPLES": max(1, int(self.light_samples)), "SHADE_SHADOWS": 1,
                "RQ_BLEND_ROULETTE": repr(float(self.blend_roulette))}
