"""Ready-made graphs around path tracing and temporal filtering (re-exported by rayvr.graphs).

    path_traced():  PathTracer ─> Accumulate ─> ToneMap      (progressive reference renders)
    hybrid_taa():   hybrid() with TAA between Composite and ToneMap, fed GBuffer.motion
"""
from __future__ import annotations

from .rendergraph.graph import RenderGraph

PT_OUTPUT = "ToneMap.dst"          # display-referred rgba8, sRGB encoded
PT_HDR_OUTPUT = "Accumulate.dst"   # linear radiance, mean over the accumulated frames (rgba32f)
TAA_HDR_OUTPUT = "TAA.dst"         # anti-aliased linear radiance (rgba16f)


def path_traced(samples_per_pixel: int = 1, max_bounces: int = 4, rr_start: int = 3, clamp: float = 0.0,
                background=(0.0, 0.0, 0.0), max_frames: int = 0, tonemap: str = "aces",
                exposure: float = 0.0, auto_exposure: bool = False, name: str = "PathTraced") -> RenderGraph:
    """Every pixel path traced from the camera (PathTracer in "full" mode), averaged over frames
    by Accumulate (restarts when the views or the scene change; `max_frames` > 0 stops it), tone
    mapped. Outputs: `ToneMap.dst` (rgba8 sRGB) and `Accumulate.dst` (HDR mean, rgba32f)."""
    from . import passes as P

    g = RenderGraph(name)
    g.add_pass(P.PathTracer(mode="full", samples_per_pixel=samples_per_pixel, max_bounces=max_bounces,
                            rr_start=rr_start, clamp=clamp, background=list(background)), "PathTracer")
    g.add_pass(P.Accumulate(max_frames=max_frames), "Accumulate")
    g.add_pass(P.ToneMapper(operator=tonemap, exposure=exposure, auto_exposure=auto_exposure), "ToneMap")
    g.add_edge("PathTracer.color", "Accumulate.src")
    g.add_edge("Accumulate.dst", "ToneMap.src")
    g.mark_output(PT_OUTPUT)
    g.mark_output(PT_HDR_OUTPUT)
    return g


def hybrid_taa(alpha: float = 0.1, sigma: float = 1.0, name: str = "HybridTAA", **hybrid_kw) -> RenderGraph:
    """`rayvr.graphs.hybrid(**hybrid_kw)` with TAA on the composited radiance (motion vectors from
    the G-buffer) before tone mapping. Outputs: `ToneMap.dst`, `Composite.color` and `TAA.dst`.
    Sub-pixel jitter needs the renderer to pack `rayvr.passes.taa.halton_jitter(frame)` into
    the views and the G-buffer to apply it; without jitter TAA still filters temporal noise."""
    from .graphs import hybrid
    from .passes.taa import TAA

    g = hybrid(name=name, **hybrid_kw)
    g.add_pass(TAA(alpha=alpha, sigma=sigma), "TAA")
    g.remove_edge("Composite.color", "ToneMap.src")
    g.add_edge("Composite.color", "TAA.color")
    g.add_edge("GBuffer.motion", "TAA.motion")
    g.add_edge("TAA.dst", "ToneMap.src")
    g.mark_output(TAA_HDR_OUTPUT)
    return g


__all__ = ["path_traced", "hybrid_taa"]
