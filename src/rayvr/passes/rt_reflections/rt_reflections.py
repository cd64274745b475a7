"""RTReflections: mirror and glossy reflections, only where a material asks for them."""
from __future__ import annotations

from ...materials.effect import Effect
from ...rendergraph.registry import register_pass
from ..effects import unused_effect_reason
from ..gbuffer.lighting_pass import GBufferLightingPass


@register_pass
class RTReflections(GBufferLightingPass):
    """Mirror and glossy (GGX VNDF) reflections for the pixels whose effect is REFLECTIONS or above,
    `max_bounces` deep; reflected hits are shaded with ray-traced shadows. Emitters and the
    environment that a glossy ray finds are weighed against the direct-light passes' light samples
    by the power heuristic (those weigh the specular lobes of REFLECTIONS pixels the other way:
    shading.glsl shade_direct_mis), so near-mirrors reflect the sky. The output is the
    reflected radiance already weighted by the specular BSDF (the composite adds it).
    Runs over the whole image in 8x4 tiles unless a material is PATH_TRACED (benchmarks/RESULTS.md
    compares the tile shapes and the list)."""

    SHADER = "rt_reflections.comp"
    OUTPUT = "reflection"
    OUTPUT_DESC = "specular-weighted reflected radiance (listed pixels only)"
    PIXEL_LIST = "pixels"
    LOWEST_EFFECT = Effect.REFLECTIONS
    SALT = 3
    PROPERTIES = {"max_bounces": 1, "light_samples": 1}

    def skip_reason(self, cd):
        return unused_effect_reason(cd, Effect.REFLECTIONS)

    def shader_defines(self):
        return {"MAX_BOUNCES": max(1, int(self.max_bounces)), "LIGHT_SAMPLES": max(1, int(self.light_samples)),
                "SHADE_SHADOWS": 1}
