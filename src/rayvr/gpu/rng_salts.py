"""The salts of the random streams (glsl/sampling.glsl rng_init's `salt`), one per consumer,
declared once: two consumers with one salt would draw the same numbers at a pixel. A pass takes
its stream's salt from RNG_SALTS; the shaders see the same table as `const uint RNG_SALT_<NAME>`
(the generated include "rng_salts.glsl", included by sampling.glsl).
"""
from __future__ import annotations

RNG_SALTS = {
    "lighting": 0,          # a G-buffer lighting pass without a stream of its own
    "direct_lighting": 1,
    "rt_shadows": 2,
    "rt_reflections": 3,
    # the G-buffer writers' alphaMode BLEND decisions: GBufferRaster (a fragment, its key's ray 1)
    # and GBufferRT (its pixel's first ray) keep or drop a surface alike
    "gbuffer": 5,
    "path_tracer": 7,
    "probe_trace": 11,      # the probe update's stages (passes/probe_gi)
    "probe_shade": 12,
    "probe_shadow": 13,
    "restir_candidates": 17,   # ReSTIR DI's stages (passes/restir_di)
    "restir_temporal": 19,
    "restir_spatial": 23,
}
assert len(set(RNG_SALTS.values())) == len(RNG_SALTS), "two random streams share a salt"


def glsl_source() -> str:
    """The generated "rng_salts.glsl"."""
    lines = ["// Generated from rayvr/gpu/rng_salts.py RNG_SALTS: edit the table, not this text."]
    lines += [f"const uint RNG_SALT_{name.upper()} = {salt}u;" for name, salt in RNG_SALTS.items()]
    return "\n".join(lines) + "\n"
