"""Ready-made render graphs. `hybrid()` is rayvr's main job: the Ray-VR pipeline.

    hybrid(preset="raw"):
    GBuffer ─┬─> Direct ───────────────────────────────────────┐
             ├─> Compaction ─┬─> Shadows ──────────────────────┤
             │               ├─> Reflections ──────────────────┼─> Composite ─> ToneMap
             │               └─> PathTracer ─> Accumulate ─────┘
             └─(G-buffer pins to every lighting pass; effect ids to Compaction and Composite)
    gi="probes": + Probes (ProbeGI, once per frame) ─> Composite, Reflections
    taa=True: TAA between Composite and ToneMap, fed GBuffer.motion
    hybrid(): the "clean" preset, gi="probes" + denoise="svgf" (graph_options.PRESETS)
    direct="restir": Shadows is ReSTIRDI (spatiotemporal reservoir resampling) instead of
    RTShadows, with the same pins
    reuse="views" / foveation="fixed"|"gaze" (hybrid and path_traced): + Decision (TraceDecision,
    from the G-buffer) ─> Compaction, every ray pass and SVGF: which pixels trace this frame

    path_traced():  PathTracer ─> Accumulate ─> ToneMap      (progressive reference renders)
    hybrid_taa():   hybrid() with TAA on and its alpha and sigma

    denoise="svgf" (hybrid and path_traced): the light as two lobes (Composite or PathTracer
    `diffuse`/`specular`) ─> SVGF ─> TAA ─> ToneMap, with the G-buffer's surfaces and motion;
    the hybrid's PATH_TRACED pixels skip Accumulate (SVGF's history accumulates them), and
    path_traced() gets a ray-traced G-buffer registered with its primary rays.
    denoise="oidn": the HDR radiance ─> OIDNDenoise ("Denoise", albedo and normal from the
    G-buffer) ─> ToneMap; offline work, the `oidn` extra.

Passes that no material needs are pruned at compile time (see the compile report).
`BUILDERS` names these builders with the options each takes (rayvr.graph_options: the choices of
`gi=`, `denoise=` and `direct=`, what each needs, which fit a frame budget).
"""
from __future__ import annotations

from .errors import OptionError
from .graph_options import (DEFAULT_PRESET, DENOISE, DIRECT, FOVEATION, FROM_PRESET, GI, REUSE, TRACE_OPTIONS,
                            GraphBuilder, preset_options, trace_choice)
from .rendergraph.graph import RenderGraph

OUTPUT = "ToneMap.dst"        # display-referred rgba8, sRGB encoded
HDR_OUTPUT = "Composite.color"  # linear radiance (rgba16f), for EXR
PT_OUTPUT = "ToneMap.dst"          # path_traced(): display-referred rgba8, sRGB encoded
PT_HDR_OUTPUT = "Accumulate.dst"   # path_traced(): linear radiance, mean over the accumulated frames (rgba32f)
TAA_HDR_OUTPUT = "TAA.dst"         # hybrid_taa() and denoise="svgf": anti-aliased linear radiance (rgba16f)
DENOISED_OUTPUT = "Denoise.dst"    # denoise="oidn": the denoised linear radiance (rgba32f)
# A graph's linear-radiance output: the first of these it marks (hdr_output()).
HDR_OUTPUTS = (DENOISED_OUTPUT, TAA_HDR_OUTPUT, HDR_OUTPUT, PT_HDR_OUTPUT)


def denoiser(denoise) -> str | None:
    """`denoise` checked: None (or 'none') or one of DENOISE's values, what it needs installed
    ('oidn' needs pyoidn, the oidn extra)."""
    if denoise is None or denoise == "none":
        return None
    if denoise not in DENOISE.values:
        raise OptionError(f"denoise={denoise!r}: use None ('none'), {DENOISE.either()}")
    DENOISE[denoise].require(f"denoise={denoise!r}")
    return denoise


def hdr_output(graph) -> str:
    """The linear-radiance output of `graph`: the first of HDR_OUTPUTS it marks."""
    for pin in HDR_OUTPUTS:
        if pin in graph.outputs:
            return pin
    raise OptionError(f"graph '{graph.name}' marks none of {', '.join(HDR_OUTPUTS)} (its linear-radiance output)")


def _denoised(g: RenderGraph, denoise: str | None, color: str, lobes: tuple[str, str] | None = None) -> None:
    """Feed ToneMap from `color` (HDR radiance), through the denoiser: SVGF on `lobes` (diffuse,
    specular pins) then TAA, or OIDN on `color`; marks the denoised HDR output."""
    from . import passes as P
    from .passes.gbuffer import channels
    from .passes.svgf.svgf import GBUFFER

    if denoise == "svgf":
        g.add_pass(P.SVGF(), "SVGF")
        g.add_pass(P.TAA(), "TAA")
        channels.wire(g, "GBuffer", "SVGF", GBUFFER)
        g.add_edge(lobes[0], "SVGF.diffuse")
        g.add_edge(lobes[1], "SVGF.specular")
        g.add_edge("SVGF.color", "TAA.color")
        g.add_edge("GBuffer.motion", "TAA.motion")
        g.add_edge("TAA.dst", "ToneMap.src")
        g.mark_output(TAA_HDR_OUTPUT)
    elif denoise == "oidn":
        g.add_pass(P.OIDNDenoise(), "Denoise")
        channels.wire(g, "GBuffer", "Denoise")
        g.add_edge(color, "Denoise.color")
        g.add_edge("Denoise.dst", "ToneMap.src")
        g.mark_output(DENOISED_OUTPUT)
    else:
        g.add_edge(color, "ToneMap.src")


def _trace_decision(g: RenderGraph, reuse, foveation, decision: dict | None, where: str,
                    every_surface: bool = False, spread: bool = False) -> bool:
    """Add the trace decision (pass "Decision", rayvr.passes.TraceDecision) when `reuse` or
    `foveation` asks for it, fed by the G-buffer, with `decision` as its further properties and
    `spread` (SVGF, already in `g`, gives reusing pixels their source's filtered light; without
    reuse it has none to give, and its `spread` is turned off); False (and nothing added) when
    neither does."""
    from . import passes as P
    from .passes.gbuffer import channels

    reuse, foveation = trace_choice(REUSE, reuse, where), trace_choice(FOVEATION, foveation, where)
    if reuse is None and foveation is None:
        if decision:
            raise OptionError(f"{where}(decision=...): trace decision settings need reuse='views' or foveation="
                              f"'fixed' or 'gaze'")
        return False
    if "spread" in (decision or {}):
        raise OptionError(f"{where}(decision={{'spread': ...}}): 'spread' follows denoise='svgf'; leave it out")
    props = {"reuse": reuse == "views", "foveation": foveation or "none", "every_surface": every_surface,
             "spread": spread, **dict(decision or {})}
    g.add_pass(P.TraceDecision(props), "Decision")
    channels.wire(g, "GBuffer", "Decision")
    if spread and reuse != "views":   # foveation alone flags no pixel for SVGF to spread to
        g.update_pass("SVGF", {"spread": False})
    return True


def _read_decision(g: RenderGraph, readers, pin: str = "decision") -> None:
    """Decision.<pin> (its `decision`, or its `workTiles`) into each of `readers` (pass names) that
    the graph has and whose pass declares that input (another pass under one of these names may not
    read it)."""
    from .rendergraph.render_pass import CompileData

    for reader in readers:
        if reader in g.passes and pin in g.get_pass(reader).reflect(CompileData(views=2)).pins:
            g.add_edge(f"Decision.{pin}", f"{reader}.{pin}")


def hybrid(max_bounces: int = 1, tonemap: str = "aces", exposure: float = 0.0,
           auto_exposure: bool = False, light_samples: int = 1,
           multiview: str = "auto", path_bounces: int = 4, name: str = "Hybrid",
           gbuffer: str = "auto", denoise=FROM_PRESET, gi=FROM_PRESET, taa=FROM_PRESET,
           probes: dict | None = None, reflection_max_roughness: float | None = None,
           direct: str | None = None, restir: dict | None = None, preset: str = DEFAULT_PRESET,
           reuse=None, foveation=None, decision: dict | None = None) -> RenderGraph:
    """The hybrid raster + ray-traced graph: multiview G-buffer, direct light for every pixel,
    ray-traced shadows and reflections only for the pixels whose material's effect asks for them,
    path tracing (rayvr.passes.PathTracer in G-buffer mode) for PATH_TRACED materials, composite
    and tone map. `preset`: 'clean' (the default: probe GI, SVGF and TAA, so the frame is
    denoised and a still view converges) or 'raw' (the bare pipeline: no GI, no denoiser, nothing
    carried across frames); `gi`, `denoise` and `taa` given explicitly override the preset's
    (rayvr.graph_options.PRESETS). `gbuffer`: 'raster', 'rt' (ray-traced, rayvr.passes.GBufferRT) or 'auto' (raster
    unless the GPU's raster is weak against its compute: Capabilities.weak_raster, chosen at compile
    and named in the compile report); the pass is "GBuffer" either way. `denoise`: None, 'svgf'
    (the composite's diffuse and specular light through SVGF and TAA: shadows, reflections and
    path-traced pixels converge over frames) or 'oidn' (offline; see the module docstring).
    `taa`: TAA after the composite (before OIDN; SVGF brings its own): jittered frames averaged
    along the motion vectors, exactly while the view is still (rayvr.passes.TAA).
    `gi="probes"` adds indirect light to RASTER, SHADOWS and REFLECTIONS materials from a volume of
    irradiance probes ray traced once per frame for every view (rayvr.passes.ProbeGI, pass
    "Probes", with `probes` as its properties); PATH_TRACED materials trace their own.
    `reflection_max_roughness`: REFLECTIONS surfaces rougher than this (and not transmissive) are
    shaded as SHADOWS, their specular light from the probes (the G-buffer's property of that name,
    rayvr.passes.gbuffer.reflection_cutoff); None: 0.6 with probe GI, 1 (every one traced) without.
    `direct="restir"`: the "Shadows" pass is rayvr.passes.ReSTIRDI (with `restir` as its
    properties) instead of RTShadows with `light_samples`; None: RTShadows.
    `reuse`: 'views' (rough surfaces, and glossy ones whose lobe is wide against the eyes'
    parallax, take the shaded light of the same surface in a nearby source view; disocclusions,
    narrower lobes and mirrors are traced per view) and `foveation`: 'fixed' or
    'gaze' (fewer rays away from each view's centre or the eye tracker's gaze) add the trace
    decision (rayvr.passes.TraceDecision, pass "Decision", with `decision` as its properties, e.g.
    {"foveal_radius_deg": 5, "periphery_share": 0.25}): the ray passes trace only the pixels it
    leaves their rays and fill the others from their sources; SVGF follows its ray budget, and
    with several views filters the source views only: a reused pixel takes its source's filtered
    light from SVGF (the fills and the composite leave it).
    Outputs: `ToneMap.dst` (rgba8 sRGB) and `Composite.color` (HDR), with TAA or a denoiser then
    its HDR output (`TAA.dst` or `Denoise.dst`; `hdr_output(graph)` names a graph's)."""
    from . import passes as P
    from .errors import OptionError
    from .passes.gbuffer import channels, reflection_cutoff
    from .passes.probe_gi import inputs as probe_inputs

    chosen = preset_options(preset, "hybrid", gi=gi, denoise=denoise, taa=taa)
    gi, denoise, taa = chosen["gi"], chosen["denoise"], bool(chosen["taa"])
    if gi not in (None, "none", *GI.values):
        raise OptionError(f"hybrid(gi={gi!r}): unknown global illumination; use one of {', '.join(GI.values)} "
                          f"or None")
    if probes and gi != "probes":
        raise OptionError("hybrid(probes=...): probe settings need gi='probes'")
    if direct not in (None, "none", *DIRECT.values):
        raise OptionError(f"hybrid(direct={direct!r}): use None ('none') or {DIRECT.either()}")
    if restir and direct != "restir":
        raise OptionError("hybrid(restir=...): ReSTIR settings need direct='restir'")
    denoise = denoiser(denoise)
    svgf = denoise == "svgf"
    g = RenderGraph(name)
    if reflection_max_roughness is None:
        reflection_max_roughness = reflection_cutoff.HYBRID_GI_MAX_ROUGHNESS if gi == "probes" else 1.0
    g.add_pass(P.GBufferAuto(mode=gbuffer, multiview=multiview, reflection_max_roughness=reflection_max_roughness),
               "GBuffer")
    g.add_pass(P.DirectLighting(light_samples=light_samples, raster_only=True),
               "Direct")
    g.add_pass(P.EffectCompaction(path_list=True), "Compaction")
    if direct == "restir":
        g.add_pass(P.ReSTIRDI(dict(restir or {})), "Shadows")
    else:
        # with reuse, other views' glossy pixels shade over the source's light samples
        shares = reuse == "views" and bool({**P.TraceDecision.PROPERTIES, **(decision or {})}["share_light_samples"])
        g.add_pass(P.RTShadows(light_samples=light_samples, share_light_samples=shares), "Shadows")
    g.add_pass(P.RTReflections(max_bounces=max_bounces, light_samples=light_samples), "Reflections")
    g.add_pass(P.PathTracer(mode="gbuffer", max_bounces=path_bounces, lobes=svgf), "PathTracer")
    if not svgf:
        g.add_pass(P.Accumulate(), "Accumulate")
    g.add_pass(P.HybridComposite(lobes=svgf), "Composite")
    g.add_pass(P.ToneMapper(operator=tonemap, exposure=exposure, auto_exposure=auto_exposure), "ToneMap")
    for lighting in ("Direct", "Shadows", "Reflections", "PathTracer"):
        channels.wire(g, "GBuffer", lighting, channels.read_by(g.passes[lighting]))
    g.add_edge("GBuffer.effect", "Compaction.effect")
    g.add_edge("Compaction.shadowPixels", "Shadows.pixels")
    g.add_edge("Compaction.reflectionPixels", "Reflections.pixels")
    g.add_edge("Compaction.pathPixels", "PathTracer.pixels")
    if svgf:
        g.add_edge("PathTracer.color", "Composite.pathTraced")
        g.add_edge("PathTracer.diffuse", "Composite.pathDiffuse")
        g.add_edge("PathTracer.specular", "Composite.pathSpecular")
        g.add_edge("GBuffer.emissive", "Composite.emissive")
    else:
        g.add_edge("PathTracer.color", "Accumulate.src")
        g.add_edge("Accumulate.dst", "Composite.pathTraced")
    g.add_edge("GBuffer.effect", "Composite.effect")
    g.add_edge("Direct.direct", "Composite.direct")
    g.add_edge("Shadows.shadowed", "Composite.shadowed")
    g.add_edge("Reflections.reflection", "Composite.reflection")
    if gi == "probes":
        g.add_pass(P.ProbeGI(dict(probes or {})), "Probes")
        # the primary surfaces' lookup in the composite (no rays there), the reflected hits' in
        # Reflections
        for reader in ("Composite", "Reflections"):
            probe_inputs.wire(g, "Probes", reader)
        channels.wire(g, "GBuffer", "Composite", [n for n in channels.LIGHTING if n not in ("effect", "emissive")])
        if not svgf:
            g.add_edge("GBuffer.emissive", "Composite.emissive")
    g.mark_output(OUTPUT)
    g.mark_output(HDR_OUTPUT)
    _denoised(g, denoise, HDR_OUTPUT, ("Composite.diffuse", "Composite.specular"))
    if taa and not svgf:
        _add_taa(g)
    if _trace_decision(g, reuse, foveation, decision, "hybrid", spread=svgf):
        # the composite reads it only to leave the pixels SVGF spreads to, which only reuse flags
        spreads = svgf and reuse == "views"
        _read_decision(g, ("Compaction", "Shadows", "Reflections", "PathTracer", *(("Composite",) * spreads), "SVGF"))
        if spreads:   # the tiles with light of their own, for the passes whose workgroup is one
            from .passes.trace_decision.work_tiles import WORK_TILES
            _read_decision(g, ("Shadows", "Reflections", "Composite"), WORK_TILES)
    return g


def _add_taa(g: RenderGraph) -> None:
    """TAA on the composited radiance (motion vectors from the G-buffer) in front of its reader
    (ToneMap, or Denoise with OIDN); marks TAA.dst."""
    from .passes import TAA

    reader = next(e.dst for e in g.edges if e.src == HDR_OUTPUT and e.dst_pass in ("ToneMap", "Denoise"))
    g.add_pass(TAA(), "TAA")
    g.remove_edge(HDR_OUTPUT, reader)
    g.add_edge("Composite.color", "TAA.color")
    g.add_edge("GBuffer.motion", "TAA.motion")
    g.add_edge("TAA.dst", reader)
    g.mark_output(TAA_HDR_OUTPUT)


def path_traced(samples_per_pixel: int = 1, max_bounces: int = 4, rr_start: int = 3, clamp: float = 0.0,
                max_frames: int = 0, tonemap: str = "aces",
                exposure: float = 0.0, auto_exposure: bool = False, name: str = "PathTraced",
                denoise: str | None = None, reuse=None, foveation=None, decision: dict | None = None) -> RenderGraph:
    """Every pixel path traced from the camera (PathTracer in "full" mode), averaged over frames
    by Accumulate (restarts when the views or the scene change; `max_frames` > 0 stops it), tone
    mapped. Outputs: `ToneMap.dst` (rgba8 sRGB) and `Accumulate.dst` (HDR mean, rgba32f).
    `denoise`: 'svgf' (no Accumulate: a ray-traced G-buffer, the path tracer's lobes at pixel
    centres plus the views' jitter, SVGF and TAA; HDR output `TAA.dst`) or 'oidn' (the mean
    denoised with a ray-traced G-buffer's albedo and normal; HDR output `Denoise.dst`, marked
    after `Accumulate.dst`). `reuse`, `foveation`, `decision`: the trace decision as in hybrid(),
    over every pixel's primary hit (a ray-traced G-buffer registers with the camera rays; an
    EffectCompaction lists the pixels that trace)."""
    from . import passes as P

    denoise = denoiser(denoise)
    g = RenderGraph(name)
    decided = any(trace_choice(o, v, "path_traced") for o, v in ((REUSE, reuse), (FOVEATION, foveation)))
    if denoise or decided:
        g.add_pass(P.GBufferAuto(mode="rt"), "GBuffer")   # the path tracer's own primary rays
    g.add_pass(P.PathTracer(mode="full", samples_per_pixel=samples_per_pixel, max_bounces=max_bounces,
                            rr_start=rr_start, clamp=clamp,
                            **({"lobes": True, "pixel_jitter": False} if denoise == "svgf" else {})), "PathTracer")
    if denoise != "svgf":
        g.add_pass(P.Accumulate(max_frames=max_frames), "Accumulate")
        g.add_edge("PathTracer.color", "Accumulate.src")
    g.add_pass(P.ToneMapper(operator=tonemap, exposure=exposure, auto_exposure=auto_exposure), "ToneMap")
    g.mark_output(PT_OUTPUT)
    if denoise != "svgf":
        g.mark_output(PT_HDR_OUTPUT)
    _denoised(g, denoise, PT_HDR_OUTPUT, ("PathTracer.diffuse", "PathTracer.specular"))
    if _trace_decision(g, reuse, foveation, decision, "path_traced", every_surface=True,
                       spread=denoise == "svgf"):
        from .passes.gbuffer import channels

        g.add_pass(P.EffectCompaction(path_list=True, every_surface=True), "Compaction")
        g.add_edge("GBuffer.effect", "Compaction.effect")
        g.add_edge("Compaction.pathPixels", "PathTracer.pixels")
        channels.wire(g, "GBuffer", "PathTracer")   # the fill's albedos
        _read_decision(g, ("Compaction", "PathTracer", "SVGF"))
    return g


def hybrid_taa(alpha: float = 0.1, sigma: float = 1.0, name: str = "HybridTAA", taa: bool = True,
               **hybrid_kw) -> RenderGraph:
    """`rayvr.graphs.hybrid(**hybrid_kw)` with TAA on (whatever the preset) and its `alpha` and
    `sigma`: on the composited radiance (motion vectors from the G-buffer) before tone mapping (and
    before OIDN with denoise='oidn'; with 'svgf' the hybrid's own TAA after SVGF). Outputs:
    `ToneMap.dst`, `Composite.color` and `TAA.dst`. TAA asks for sub-pixel camera jitter in its
    reflection; the Renderer packs `rayvr.passes.taa.halton_jitter(frame)` into the views and the
    G-buffer applies it."""
    if not taa:
        raise OptionError("hybrid_taa(taa=False): this graph is the hybrid with TAA; use rv.graphs.hybrid(taa=False)")
    g = hybrid(name=name, taa=True, **hybrid_kw)
    g.update_pass("TAA", {"alpha": alpha, "sigma": sigma})
    return g


# The ready-made graphs by name, with the options each takes (rayvr.graph_options).
BUILDERS = {b.name: b for b in (
    GraphBuilder("hybrid", hybrid, (GI, DENOISE, DIRECT, *TRACE_OPTIONS), "per-material effects; default"),
    GraphBuilder("hybrid_taa", hybrid_taa, (GI, DENOISE, DIRECT, *TRACE_OPTIONS), "hybrid with TAA before tone mapping",
                 command_line=False, extends=hybrid),
    GraphBuilder("path_traced", path_traced, (DENOISE, *TRACE_OPTIONS), "every pixel, accumulated: reference renders"),
)}
COMMAND_LINE_GRAPHS = tuple(name for name, b in BUILDERS.items() if b.command_line)   # --graph NAME
