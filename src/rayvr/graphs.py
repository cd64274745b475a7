"""Ready-made render graphs. `hybrid()` is rayvr's main job: the Ray-VR pipeline.

    GBuffer ─┬─> Direct ───────────────────────────────────────┐
             ├─> Compaction ─┬─> Shadows ──────────────────────┤
             │               ├─> Reflections ──────────────────┼─> Composite ─> ToneMap
             │               └─> PathTracer ─> Accumulate ─────┘
             └─(G-buffer pins to every lighting pass; effect ids to Compaction and Composite)

Passes that no material needs are pruned at compile time (see the compile report).
"""
from __future__ import annotations

from .rendergraph.graph import RenderGraph

OUTPUT = "ToneMap.dst"        # display-referred rgba8, sRGB encoded
HDR_OUTPUT = "Composite.color"  # linear radiance (rgba16f), for EXR


def hybrid(max_bounces: int = 1, tonemap: str = "aces", exposure: float = 0.0,
           auto_exposure: bool = False, light_samples: int = 1, background=(0.0, 0.0, 0.0),
           multiview: str = "auto", path_bounces: int = 4, name: str = "Hybrid",
           gbuffer: str = "auto") -> RenderGraph:
    """The hybrid raster + ray-traced graph: multiview G-buffer, direct light for every pixel,
    ray-traced shadows and reflections only for the pixels whose material's effect asks for them,
    path tracing (rayvr.passes.PathTracer in G-buffer mode) for PATH_TRACED materials, composite
    and tone map. `gbuffer`: 'raster', 'rt' (ray-traced, rayvr.passes.GBufferRT) or 'auto' (raster
    unless the GPU's raster is weak against its compute: Capabilities.weak_raster, chosen at compile
    and named in the compile report); the pass is "GBuffer" either way.
    Outputs: `ToneMap.dst` (rgba8 sRGB) and `Composite.color` (HDR)."""
    from . import passes as P
    from .passes._common import GBUFFER_PINS

    g = RenderGraph(name)
    g.add_pass(P.GBufferAuto(mode=gbuffer, multiview=multiview), "GBuffer")
    g.add_pass(P.DirectLighting(light_samples=light_samples, background=list(background), raster_only=True),
               "Direct")
    path_tracing = hasattr(P, "PathTracer") and hasattr(P, "Accumulate")
    g.add_pass(P.EffectCompaction(path_list=path_tracing), "Compaction")
    g.add_pass(P.RTShadows(light_samples=light_samples), "Shadows")
    g.add_pass(P.RTReflections(max_bounces=max_bounces, light_samples=light_samples,
                               background=list(background)), "Reflections")
    if path_tracing:
        g.add_pass(P.PathTracer(mode="gbuffer", max_bounces=path_bounces, background=list(background)),
                   "PathTracer")
        g.add_pass(P.Accumulate(), "Accumulate")
    g.add_pass(P.HybridComposite(), "Composite")
    g.add_pass(P.ToneMapper(operator=tonemap, exposure=exposure, auto_exposure=auto_exposure), "ToneMap")
    for lighting in ("Direct", "Shadows", "Reflections", *(("PathTracer",) if path_tracing else ())):
        for pin in GBUFFER_PINS:
            g.add_edge(f"GBuffer.{pin}", f"{lighting}.{pin}")
    g.add_edge("GBuffer.effect", "Compaction.effect")
    g.add_edge("Compaction.shadowPixels", "Shadows.pixels")
    g.add_edge("Compaction.reflectionPixels", "Reflections.pixels")
    if path_tracing:
        g.add_edge("Compaction.pathPixels", "PathTracer.pixels")
        g.add_edge("PathTracer.color", "Accumulate.src")
        g.add_edge("Accumulate.dst", "Composite.pathTraced")
    g.add_edge("GBuffer.effect", "Composite.effect")
    g.add_edge("Direct.direct", "Composite.direct")
    g.add_edge("Shadows.shadowed", "Composite.shadowed")
    g.add_edge("Reflections.reflection", "Composite.reflection")
    g.add_edge("Composite.color", "ToneMap.src")
    g.mark_output(OUTPUT)
    g.mark_output(HDR_OUTPUT)
    return g


def __getattr__(name: str):
    """The path-tracing graph builders (rayvr.graphs_pt: path_traced, hybrid_taa) under rv.graphs."""
    if name in ("path_traced", "hybrid_taa"):
        from . import graphs_pt

        return getattr(graphs_pt, name)
    raise AttributeError(f"module 'rayvr.graphs' has no attribute '{name}'")
