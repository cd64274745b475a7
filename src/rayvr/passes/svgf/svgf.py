"""SVGF pass: spatiotemporal variance-guided filtering (Schied et al. 2017, "Spatiotemporal
Variance-Guided Filtering: Real-Time Reconstruction for Path-Traced Global Illumination"), every
view of a frame in each dispatch, each view with its own history (layer z is view z).

Four stages, one compute shader each, run as dispatches of this one pass:
    reproject   demodulate `diffuse` and `specular` by the BSDF's directional albedos
                (glsl/bsdf.glsl bsdf_albedo) at the G-buffer surface; fetch last frame's history
                where the G-buffer's motion vector points, over the taps that pass the
                disocclusion test (depth against the view's previous view-projection, normal,
                effect word); blend colour and luminance moments; count the history length
    variance    per-pixel variance from the moments; a 7x7 spatial estimate while the history
                is shorter than 4 frames (in place: only those pixels write); and the depth
                gradient of every pixel (`gradient`: it depends on this frame's key only, so
                the a-trous iterations fetch it, one texel, instead of four keys each)
    a-trous     `iterations` passes of the edge-stopping wavelet filter, `kernel` 3x3 (the
                default, 9 taps) or 5x5 (the paper's B3 spline, 25 taps), taps 1, 2, 4, ...
                pixels apart; depth, normal and variance-scaled luminance weights
    modulate    filtered illumination x albedo + emission: in the last a-trous iteration (its
                program built with SVGF_FINAL), or with 0 iterations a dispatch of its own
The a-trous stage is bound by texture fetches, so what it reads per tap is small: the filter
key (`key0/1`, rg32ui: linear depth, 0 where nothing was drawn, and octahedral normal) and one
texel holding both lobes' illumination and variance (`filter0/1`, rgba32ui float16 pairs; rgba16f
without `specular`). The effect word and history length only the reprojection compares
(`surface0/1`). (A workgroup tile in shared memory, loaded once per iteration, fetches fewer
texels but measured 1.7x slower: benchmarks/RESULTS.md.)
The colour history is the output of a-trous iteration `feedback_tap` as in the paper (0: the
first), or with `feedback_tap` -1 (the default) the unfiltered temporal mean. Fed back, the
filter's blur compounds frame after frame: on the Cornell box at 32x32 and 1 spp, 16 still
frames end at relMSE 0.0125 with the first iteration fed back and 0.0041 without (raw 16-frame
accumulation: 0.011). For the same reason the variance that scales the luminance weights is the
variance of the temporal mean (one frame's, from the moments, over the frames averaged), so the
filter backs off as a still view's history grows and the image converges.
The stages are one pass, not four, because the paper's temporal stage reads last frame's
*filtered* illumination: the a-trous stage writes the history the reprojection reads, a loop
that separate graph passes could only express as a cycle (Falcor's SVGFPass and Tauray's svgf
stage are one unit for the same reason). TAA follows in the graphs (rayvr.graphs).

With the optional `decision` input (TraceDecision) the reprojection reads each pixel's ray budget
b, the share of frames its own rays are traced (foveation): the new frame weighs b times as much,
the history may grow 1 / b times as long, and the variance is that of b x history samples, so a
sparsely traced pixel keeps a longer history and a wider filter (svgf_reproject.comp). With
several views, a pixel whose light the decision takes from another view (a view reusing a source
view's shading) is not filtered at all: a last dispatch (svgf_spread.comp) gives it the source's
filtered illumination, remodulated by its own albedos, so the denoising of reused light is done
once, in the source view. Its history is the source's, not copied: it keeps its decision texel
(`spreadSource`), through which the next reprojection reads the source's history should the pixel
trace its own light then.
There the reprojection also lists the pixels it filters (`filterPixels`, with `filter_list`), and
the variance and a-trous stages run over that list, indirectly: a view that reuses most of its
light has a few pixels to filter, scattered over its image, and 8x8 tiles of the image would hold
warps of mostly idle lanes.

History resets on the first frame, on `reset()` and on scene edits that change the lighting
(materials or lights: `GpuScene.version` moved and one of them differs). Camera motion never
resets it (reprojection follows the head), nor do moved instances: their pixels fail the
disocclusion test where the surface behind them changed.
"""
from __future__ import annotations

from ...errors import OptionError
from ...gpu.program_resources import program_resources
from ...rendergraph.registry import register_pass
from ...rendergraph.render_pass import Access, Reflection, RenderPass
from ..compaction.pixel_list import dispatch_list, empty_lists, pixel_list_bytes
from ..dispatch import groups_2d
from ..effects import effect_defines, scene_defines
from ..gbuffer import channels
from ..history import HistoryOwner, LightingHistory, still_frame
from ..trace_decision.fill import DECISION, DecisionFill

GBUFFER = tuple(c.name for c in channels.CHANNELS)   # every channel: the surface, material and motion
MAX_ITERATIONS = 8   # taps up to 2 x 2^7 = 256 pixels apart
KERNELS = (3, 5)     # a-trous kernel widths: 3x3 (1/2, 1/4 per axis), 5x5 (B3 spline 3/8, 1/4, 1/16)


@register_pass
class SVGF(HistoryOwner, RenderPass):
    """Denoises `diffuse` (+ optional `specular`) first-vertex radiance into `color` (rgba16f);
    see the module docstring.

    Properties: `iterations` (a-trous passes, 0-8; 0 = temporal accumulation only), `kernel`
    (the a-trous kernel's width: 3, the default, a 3x3 kernel of 9 taps, or 5, the paper's 5x5
    B3 spline),
    `feedback_tap` (the iteration whose output becomes the colour history; -1: the unfiltered
    temporal mean), `alpha` and
    `moments_alpha` (weights of the new frame's colour and moments, at least 1 / history length),
    `max_history` (frames the history length counts to while the view moves), `still_max_history`
    (the same on a still frame, where a pixel that did not move keeps an exact running mean:
    rayvr.passes.history; the float16 colour history bounds it), `phi_color`, `phi_normal`, `phi_depth`
    (the edge-stopping sigmas of luminance, normal and depth), `spread` (True: with a decision bound
    over several views, leave the pixels it flags DECISION_SPREAD to a last dispatch that gives them
    their sources' filtered light; the graphs set it False when the decision reuses no view, as
    with foveation alone, whose decision flags none), `filter_list` (True: with `spread` in effect, the
    variance and a-trous stages run over the list of pixels left to filter instead of the image)."""

    DIFFUSE, SPECULAR, COLOR = "diffuse", "specular", "color"
    HISTORY_DIFFUSE, HISTORY_SPECULAR = "historyDiffuse", "historySpecular"
    MOMENTS = ("moments0", "moments1")
    KEY = ("key0", "key1")
    SURFACE = ("surface0", "surface1")
    FILTER = ("filter0", "filter1")
    GRADIENT = "gradient"
    FILTER_PIXELS = "filterPixels"
    SPREAD_SOURCE = "spreadSource"
    COUNTS_NONFINITE = True   # scrubs NaN/Inf samples (glsl/nonfinite.glsl)
    PROPERTIES = {"iterations": 5, "kernel": 3, "feedback_tap": -1, "alpha": 0.05, "moments_alpha": 0.2,
                  "max_history": 32, "still_max_history": 256, "phi_color": 4.0, "phi_normal": 128.0, "phi_depth": 1.0,
                  "spread": True, "filter_list": True}
    WHOLE = {"iterations": (0, MAX_ITERATIONS, "a-trous passes"),
             "feedback_tap": (-1, None, "the iteration fed back; -1: the temporal mean"),
             "max_history": (1, None, "frames"), "still_max_history": (1, None, "frames")}
    USES_SCENE = True

    def __init__(self, props: dict | None = None, **kwargs):
        super().__init__(props, **kwargs)
        self._history = LightingHistory()

    def validate_property(self, key, value):
        value = super().validate_property(key, value)
        if key == "kernel" and value not in KERNELS:
            raise OptionError(f"pass {self.name}: property 'kernel' must be 3 (a 3x3 a-trous kernel, 9 taps) or 5 "
                              f"(the 5x5 B3 spline, 25 taps), got {value!r}")
        if key in ("alpha", "moments_alpha") and not 0.0 < value <= 1.0:
            raise OptionError(f"pass {self.name}: property '{key}' must be in (0, 1] (weight of the new "
                              f"frame), got {value!r}")
        if key in ("phi_color", "phi_depth") and not value > 0.0:
            raise OptionError(f"pass {self.name}: property '{key}' must be > 0, got {value!r}")
        if key == "phi_normal" and not value >= 0.0:
            raise OptionError(f"pass {self.name}: property 'phi_normal' must be >= 0, got {value!r}")
        return int(value) if key == "kernel" else value

    def reflect(self, cd):
        r = Reflection()
        channels.add_inputs(r, GBUFFER)
        r.add_input(self.DIFFUSE, "radiance the first vertex's diffuse lobe reflects, emission excluded "
                                  "(the background where nothing was hit)")
        r.add_input(self.SPECULAR, "radiance its specular lobe reflects").optional()
        DecisionFill.add_input(r)
        r.add_output(self.COLOR, "denoised radiance (remodulated, with emission)").format("rgba16f")
        if self._lists(cd):
            r.add_output(self.FILTER_PIXELS, "the pixels the variance and a-trous stages filter (scratch: the "
                                             "reprojection lists them)").buffer(pixel_list_bytes(cd.size, cd.views))
        specular = self.SPECULAR in cd.input_formats
        lobes = [(self.HISTORY_DIFFUSE, "diffuse")] + [(self.HISTORY_SPECULAR, "specular")] * specular
        for history, lobe in lobes:
            r.add_internal(history, f"filtered {lobe} illumination of last frame (the colour history)"
                           ).format("rgba16f")
        for name in self.FILTER:   # transients: they alias with other passes' textures
            r.add_output(name, "both lobes' illumination + variance between the stages (scratch): float16 "
                               "pairs (diffuse rg) (diffuse b, variance) (specular rg) (specular b, variance)"
                         if specular else "diffuse illumination + variance between the stages (scratch)"
                         ).format("rgba32ui" if specular else "rgba16f")
        r.add_output(self.GRADIENT, "depth gradient per pixel, from this frame's filter key (scratch: the "
                                    "variance stage writes it, the a-trous iterations read it)").format("rg16f")
        for name in self.MOMENTS:
            r.add_internal(name, "luminance moments: diffuse m1 m2, specular m1 m2 (used in turn)").format("rgba32f")
        for name in self.KEY:
            r.add_internal(name, "filter key: linear depth (0: no geometry), octahedral normal (used in turn)"
                           ).format("rg32ui")
        for name in self.SURFACE:
            r.add_internal(name, "effect word, history length (used in turn)").format("rg32ui")
        if self._spreads(cd):
            r.add_internal(self.SPREAD_SOURCE, "last frame's decision texel of each pixel whose light, and "
                                               "history, were another view's").format("rg32ui")
        return r

    def _spreads(self, cd) -> bool:
        """Whether views take other views' filtered light (a decision over several views, `spread`)."""
        return DecisionFill.connected(cd) and cd.views > 1 and bool(self.spread)

    def _lists(self, cd) -> bool:
        """Whether the variance and a-trous stages run over the reprojection's list of pixels."""
        return self._spreads(cd) and bool(self.filter_list)

    def compile(self, ctx, cd):
        self._specular = self.SPECULAR in cd.input_formats
        self._defines = {**scene_defines(ctx), **effect_defines(), "SVGF_SPECULAR": int(self._specular)}
        self._density = DecisionFill.connected(cd)
        # with several views a decision may hand pixels another view's light: they take its filtered light
        self._shared = self._spreads(cd)
        self._listed = self._lists(cd)
        if self._shared:
            self._defines["SVGF_SHARED"] = 1
        if self._listed:
            self._defines["SVGF_FILTER_LIST"] = 1
        reproject = {**self._defines, "TRACE_DECISION": int(self._density)}
        self._gl = ctx.gl
        # the modulate stage's own program only when 0 iterations ask for it (_modulate_program)
        self._res = {"reproject": program_resources(self.compute_program(ctx.gl, "svgf_reproject.comp", reproject)),
                     "variance": program_resources(self.compute_program(ctx.gl, "svgf_variance.comp", self._defines))}
        if self._shared:
            self._res["spread"] = program_resources(self.compute_program(
                ctx.gl, "svgf_spread.comp", {**self._defines, "TRACE_DECISION": 1}))
        self._atrous = {}
        self._atrous_program()
        self._atrous_program(final=True)
        self._groups = groups_2d(cd.size, cd.views)
        self._history.restart()

    def _atrous_program(self, final: bool = False):
        """The a-trous stage's program for the current `kernel`, the last iteration's (which also
        remodulates) with `final` (both built in compile(); a kernel set after it is built on its
        first frame)."""
        key = (int(self.kernel), bool(final))
        if key not in self._atrous:
            self._atrous[key] = program_resources(self.compute_program(
                self._gl, "svgf_atrous.comp", {**self._defines, "SVGF_KERNEL": key[0], "SVGF_FINAL": int(final)}))
        return self._atrous[key]

    def defines(self) -> dict:
        if not hasattr(self, "_defines"):
            return {}
        density = {"TRACE_DECISION": 1} if self._density else {}   # the reprojection's
        return {**self._defines, "SVGF_KERNEL": int(self.kernel), **density}   # the a-trous stage's kernel

    def _histories(self, res, data) -> None:
        """Bind the colour histories as the images `history_diffuse` (and `_specular`) of `res`."""
        res.image("history_diffuse", data[self.HISTORY_DIFFUSE])
        if self._specular:
            res.image("history_specular", data[self.HISTORY_SPECULAR])

    def _modulate_program(self):
        """The modulate stage's own program (0 iterations: otherwise the last remodulates)."""
        if "modulate" not in self._res:
            self._res["modulate"] = program_resources(self.compute_program(self._gl, "svgf_modulate.comp",
                                                                           self._defines))
        return self._res["modulate"]

    def _bind_modulate(self, res, data) -> None:
        """Bind what remodulation reads and writes: the G-buffer, the input (the background) and
        the output colour."""
        channels.bind_inputs(res, data, GBUFFER)
        res.texture("svgf_diffuse_in", data[self.DIFFUSE])
        res.image("dst", data[self.COLOR])

    def _set_common(self, res) -> None:
        res.set("svgf_phi_depth", float(self.phi_depth))
        res.set("svgf_phi_normal", float(self.phi_normal))
        res.set("svgf_phi_color", float(self.phi_color))

    def execute(self, ctx, data):
        prev, cur = self._history.begin_frame(ctx)
        scratch = [data[name] for name in self.FILTER]
        iterations = int(self.iterations)
        tap = min(int(self.feedback_tap), iterations - 1)   # < 0: the unfiltered temporal mean
        between = (Access.SAMPLED, Access.IMAGE)

        res = self._res["reproject"]
        channels.bind_inputs(res, data, GBUFFER)
        res.texture("svgf_diffuse_in", data[self.DIFFUSE])
        res.texture("history_diffuse", data[self.HISTORY_DIFFUSE])
        if self._specular:
            res.texture("svgf_specular_in", data[self.SPECULAR])
            res.texture("history_specular", data[self.HISTORY_SPECULAR])
        res.texture("moments_prev", data[self.MOMENTS[prev]])
        res.texture("key_prev", data[self.KEY[prev]])
        res.texture("surface_prev", data[self.SURFACE[prev]])
        if self._density:
            res.texture("trace_decision", data[DECISION])
        if self._shared:
            res.texture("spread_source", data[self.SPREAD_SOURCE])
        pixels = data[self.FILTER_PIXELS] if self._listed else None
        if pixels is not None:
            empty_lists(ctx, pixels)
            res.buffer("AppendList", pixels)
        res.image("out_illum", scratch[0])
        if not self._shared:   # the no-surface pixels' 0 in both (svgf_reproject.comp)
            res.image("out_illum_other", scratch[1])
        res.image("moments_out", data[self.MOMENTS[cur]])
        res.image("key_out", data[self.KEY[cur]])
        res.image("surface_out", data[self.SURFACE[cur]])
        res.set("svgf_alpha", float(self.alpha))
        res.set("svgf_moments_alpha", float(self.moments_alpha))
        res.set("svgf_max_history", float(self.max_history))
        res.set("svgf_still_max_history", float(max(self.still_max_history, self.max_history)))
        res.set("svgf_still", still_frame(ctx))
        res.set("svgf_history_valid", self._history.valid)
        res.prog.run(*self._groups)
        ctx.barrier(*between, *((Access.INDIRECT,) if pixels is not None else ()))

        res = self._res["variance"]   # in place in scratch[0]
        self._set_common(res)
        res.image("illum", scratch[0], read=True, write=True)
        self._histories(res, data)
        res.texture("moments_cur", data[self.MOMENTS[cur]])
        res.texture("key_cur", data[self.KEY[cur]])
        res.texture("surface_cur", data[self.SURFACE[cur]])
        res.image("gradient_out", data[self.GRADIENT])
        res.set("svgf_write_history", tap < 0)
        self._run_filter(res, pixels)
        ctx.barrier(*between)

        src = 0
        for i in range(iterations):
            final = i == iterations - 1
            res = self._atrous_program(final)
            self._set_common(res)
            res.texture("key_cur", data[self.KEY[cur]])
            res.texture("gradient_cur", data[self.GRADIENT])
            self._histories(res, data)
            res.texture("src_illum", scratch[src])
            if final:
                self._bind_modulate(res, data)
                if self._shared:
                    res.texture("trace_decision", data[DECISION])
            if not final or self._shared:
                res.image("dst_illum", scratch[1 - src])
            res.set("svgf_step", 1 << i)
            res.set("svgf_write_history", i == tap)
            self._run_filter(res, pixels)
            if not final:
                ctx.barrier(*between)
            src = 1 - src

        if iterations == 0:
            res = self._modulate_program()
            self._bind_modulate(res, data)
            res.texture("src_illum", scratch[src])
            res.prog.run(*self._groups)
        if self._shared:
            self._spread(ctx, data, scratch[src], cur)
        self._history.end_frame()

    def _run_filter(self, res, pixels) -> None:
        """Dispatch a variance or a-trous program over the image, or over the list `pixels`."""
        if pixels is None:
            res.prog.run(*self._groups)
        else:
            dispatch_list(res, "PixelList", pixels)

    def _spread(self, ctx, data, illum, cur) -> None:
        """The pixels whose light is another view's take its filtered light `illum`, and keep their
        decision texel, through which the next reprojection reads their sources' history
        (svgf_spread.comp)."""
        ctx.barrier(Access.SAMPLED, Access.IMAGE)
        res = self._res["spread"]
        channels.bind_inputs(res, data, GBUFFER)
        res.texture("trace_decision", data[DECISION])
        res.texture("src_illum", illum)
        res.texture("svgf_diffuse_in", data[self.DIFFUSE])   # the background (with the list)
        res.image("dst", data[self.COLOR])
        res.image("key_cur", data[self.KEY[cur]])
        res.image("surface_cur", data[self.SURFACE[cur]])
        res.image("spread_source", data[self.SPREAD_SOURCE])
        res.prog.run(*self._groups)
