"""Which REFLECTIONS surfaces the G-buffer hands to the probes instead of reflection rays.

A G-buffer pass's `reflection_max_roughness` (perceptual roughness, default 1: none) marks the
pixels of REFLECTIONS materials rougher than it, and not transmissive, as SHADOWS in the effect word
(glsl/gbuffer.glsl gbuf_encode): RTReflections then traces nothing there, the shadow pass gives the
light sample its whole specular share, and with probe GI the composite lights the specular lobe
from the probes about its dominant direction, as for any SHADOWS pixel. One glossy ray of a rough
lobe per pixel and frame is mostly noise; the probes' cosine-wide irradiance is a smooth stand-in
for such a lobe (the same cut as the roughness limits of production ray-traced reflections).
rayvr.graphs.hybrid(gi="probes") sets it to HYBRID_GI_MAX_ROUGHNESS; without probes nothing would
light those lobes, so it stays 1 there.
"""
from __future__ import annotations

from ...errors import OptionError

PROPERTY = "reflection_max_roughness"
HYBRID_GI_MAX_ROUGHNESS = 0.6


def validate(pass_name: str, value) -> float:
    """The property's value as a float in [0, 1], or an OptionError naming the pass."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        v = float("nan")
    if not 0.0 <= v <= 1.0:
        raise OptionError(f"pass {pass_name}: property '{PROPERTY}' must be a perceptual roughness from 0 to 1 "
                          f"(1: every REFLECTIONS pixel traced), got {value!r}")
    return v


def defines(value) -> dict:
    """The G-buffer shaders' define for the cutoff (none at 1: nothing is reclassified)."""
    v = float(value)
    return {} if v >= 1.0 else {"REFLECTION_MAX_ROUGHNESS": repr(v)}
