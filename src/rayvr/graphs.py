"""Ready-made render graphs. `hybrid()` is rayvr's main job: the Ray-VR pipeline.

    hybrid():
    GBuffer ─┬─> Direct ───────────────────────────────────────┐
             ├─> Compaction ─┬─> Shadows ──────────────────────┤
             │               ├─> Reflections ──────────────────┼─> Composite ─> ToneMap
             │               └─> PathTracer ─> Accumulate ─────┘
             └─(G-buffer pins to every lighting pass; effect ids to Compaction and Composite)
    hybrid(gi="probes"): + Probes (ProbeGI, once per frame) ─> Direct, Shadows, Reflections

    path_traced():  PathTracer ─> Accumulate ─> ToneMap      (progressive reference renders)
    hybrid_taa():   hybrid() with TAA between Composite and ToneMap, fed GBuffer.motion

Passes that no material needs are pruned at compile time (see the compile report).
"""
from __future__ import annotations

from .rendergraph.graph import RenderGraph

OUTPUT = "ToneMap.dst"        # display-referred rgba8, sRGB encoded
GI_MODES = ("probes",)        # hybrid(gi=...): indirect light for RASTER, SHADOWS and REFLECTIONS materials
HDR_OUTPUT = "Composite.color"  # linear radiance (rgba16f), for EXR
PT_OUTPUT = "ToneMap.dst"          # path_traced(): display-referred rgba8, sRGB encoded
PT_HDR_OUTPUT = "Accumulate.dst"   # path_traced(): linear radiance, mean over the accumulated frames (rgba32f)
TAA_HDR_OUTPUT = "TAA.dst"         # hybrid_taa(): anti-aliased linear radiance (rgba16f)


def hybrid(max_bounces: int = 1, tonemap: str = "aces", exposure: float = 0.0,
           auto_exposure: bool = False, light_samples: int = 1, background=(0.0, 0.0, 0.0),
           multiview: str = "auto", path_bounces: int = 4, name: str = "Hybrid",
           gbuffer: str = "auto", gi: str | None = None, probes: dict | None = None) -> RenderGraph:
    """The hybrid raster + ray-traced graph: multiview G-buffer, direct light for every pixel,
    ray-traced shadows and reflections only for the pixels whose material's effect asks for them,
    path tracing (rayvr.passes.PathTracer in G-buffer mode) for PATH_TRACED materials, composite
    and tone map. `gbuffer`: 'raster', 'rt' (ray-traced, rayvr.passes.GBufferRT) or 'auto' (raster
    unless the GPU's raster is weak against its compute: Capabilities.weak_raster, chosen at compile
    and named in the compile report); the pass is "GBuffer" either way.
    `gi="probes"` adds indirect light to RASTER, SHADOWS and REFLECTIONS materials from a volume of
    irradiance probes ray traced once per frame for every view (rayvr.passes.ProbeGI, pass
    "Probes", with `probes` as its properties); PATH_TRACED materials trace their own.
    Outputs: `ToneMap.dst` (rgba8 sRGB) and `Composite.color` (HDR)."""
    from . import passes as P
    from .errors import OptionError
    from .passes.gbuffer import channels
    from .passes.probe_gi import inputs as probe_inputs

    if gi not in (None, "none", *GI_MODES):
        raise OptionError(f"hybrid(gi={gi!r}): unknown global illumination; use one of {', '.join(GI_MODES)} "
                          f"or None")
    if probes and gi != "probes":
        raise OptionError("hybrid(probes=...): probe settings need gi='probes'")
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
        channels.wire(g, "GBuffer", lighting)
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
    if gi == "probes":
        g.add_pass(P.ProbeGI(dict(probes or {})), "Probes")
        for lighting in ("Direct", "Shadows", "Reflections"):
            probe_inputs.wire(g, "Probes", lighting)
    g.mark_output(OUTPUT)
    g.mark_output(HDR_OUTPUT)
    return g


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
    TAA asks for sub-pixel camera jitter in its reflection; the Renderer packs
    `rayvr.passes.taa.halton_jitter(frame)` into the views and the G-buffer applies it."""
    from .passes import TAA

    g = hybrid(name=name, **hybrid_kw)
    g.add_pass(TAA(alpha=alpha, sigma=sigma), "TAA")
    g.remove_edge("Composite.color", "ToneMap.src")
    g.add_edge("Composite.color", "TAA.color")
    g.add_edge("GBuffer.motion", "TAA.motion")
    g.add_edge("TAA.dst", "ToneMap.src")
    g.mark_output(TAA_HDR_OUTPUT)
    return g
