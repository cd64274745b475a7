"""DirectLighting: emission + unshadowed direct light for every pixel (no rays)."""
from __future__ import annotations

from ...gpu.rng_salts import RNG_SALTS
from ...materials.effect import Effect
from ...rendergraph.registry import register_pass
from ..gbuffer.lighting_pass import GBufferLightingPass


@register_pass
class DirectLighting(GBufferLightingPass):
    """Emission + unshadowed direct light (punctual and emissive-triangle lights) for every pixel;
    the sky gets the scene's environment. RASTER materials use it as is. With `raster_only` the pixels whose
    effect is SHADOWS or above are left unwritten (a ray pass lights them: the hybrid graph)."""

    SHADER = "direct_lighting.comp"
    OUTPUT = "direct"
    OUTPUT_DESC = "emission + unshadowed direct light; the environment where nothing was drawn"
    SALT = RNG_SALTS["direct_lighting"]
    PROPERTIES = {"light_samples": 1, "raster_only": False}

    def lit_effects(self):
        return {Effect.RASTER} if self.raster_only else set(Effect)

    def shader_defines(self):
        return {"LIGHT_SAMPLES": max(1, int(self.light_samples)), "SHADE_SHADOWS": 0,
                "RASTER_ONLY": int(bool(self.raster_only))}
