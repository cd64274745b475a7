"""Ready-made render graphs. `hybrid()` is rayvr's main job: the Ray-VR pipeline.

    GBuffer ─┬─> Direct ───────────────────────────────────────┐
             ├─> Compaction ─┬─> Shadows ──────────────────────┤
             │               ├─> Reflections ──────────────────┼─> Composite ─> ToneMap
             │               └─> PathTracer ─> Accumulate ─────┘
             └─(G-buffer pins to every lighting pass; effect ids to Compaction and Composite)

Passes that no material needs are pruned at compile time (see the compile report).
"""
from __future__ import annotations

from .graphs_pt import hybrid_taa, path_traced  # noqa: F401  (rv.graphs.path_traced, rv.graphs.hybrid_taa)
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
    g.add_pass(P.EffectCompaction(path_list=True), "Compaction")
    g.add_pass(P.RTShadows(light_samples=light_samples), "Shadows")
    g.add_pass(P.RTReflections(max_bounces=max_bounces, light_samples=light_samples,
                               background=list(background)), "Reflections")
    g.add_pass(P.PathTracer(mode="gbuffer", max_bounces=path_bounces, background=list(background)), "PathTracer")
    g.add_pass(P.Accumulate(), "Accumulate")
    g.add_pass(P.HybridComposite(), "Composite")
    g.add_pass(P.ToneMapper(operator=tonemap, exposure=exposure, auto_exposure=auto_exposure), "ToneMap")
    for lighting in ("Direct", "Shadows", "Reflections", "PathTracer"):
        for pin in GBUFFER_PINS:
            g.add_edge(f"GBuffer.{pin}", f"{lighting}.{pin}")
    g.add_edge("GBuffer.effect", "Compaction.effect")
    g.add_edge("Compaction.shadowPixels", "Shadows.pixels")
    g.add_edge("Compaction.reflectionPixels", "Reflections.pixels")
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

