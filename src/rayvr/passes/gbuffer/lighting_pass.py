"""The anatomy the G-buffer lighting passes share (DirectLighting, RTShadows, RTReflections): the
G-buffer channels as inputs, one rgba16f radiance output, and for the ray passes either the
compaction's pixel list (indirect dispatch) or the whole image in small tiles (property
`dispatch_mode`). The optional probe inputs (rayvr.passes.probe_gi.inputs), when connected, compile
PROBE_GI in: the shader adds the probes' indirect diffuse light (glsl/probe_gi.glsl)."""
from __future__ import annotations

from ...gpu.program_resources import program_resources
from ...gpu.rng_salts import RNG_SALTS
from ...materials.effect import Effect
from ...rendergraph.render_pass import Reflection, RenderPass
from ..compaction.pixel_list import DISPATCH_OFFSET, pixel_list_bytes
from ..dispatch import (COMPUTE_GROUP, DITHERED_TRACE, GATHER_TILES, VIEW_GROUP, check_shape, decision_view_group,
                        groups_2d, ray_group, ray_group_defines, view_order)
from ..effects import effect_defines, effects_used, scene_defines
from ..probe_gi import inputs as probe_inputs
from ..trace_decision import work_tiles
from ..trace_decision.fill import DecisionFill
from . import channels

# The ray passes' `dispatch_mode` property: "image" runs over the whole image in `tile`-sized
# workgroups, where the pixels whose effect needs no such rays leave at once; "list" runs over the
# compaction's pixel list (indirect dispatch); "auto" takes the image unless a material is PATH_TRACED. Same
# pixels, same random numbers, same image. Neighbouring pixels in one warp trace alike rays; the
# list's tiles come in random order and a warp often straddles two of them. Under a trace decision
# (TraceDecision) too the image wins though fewer of its lanes trace: with view reuse on tauray's
# stereo pair (2 x 1440x1600, the second eye's rays 0.075x the first's) RTShadows took 1.04 ms
# over the image against 1.57 over the list, and the compaction's 0.13 ms went with it
# (benchmarks/RESULTS.md has the measurement).
DISPATCHES = {"auto": "the whole image unless a material is PATH_TRACED", "image": "",
              "list": "the compaction's pixels"}
TILE = [8, 4]   # one warp (ray_group spreads it over views)
MAX_LIGHT_SAMPLES = 256   # `light_samples` (and `rayvr render --light-samples`)


def ray_properties(view_group: int = VIEW_GROUP) -> dict:
    """The properties of a lighting pass with a pixel list: its dispatch and workgroup shape."""
    return {"dispatch_mode": "auto", "tile": list(TILE), "view_group": view_group}


class GBufferLightingPass(RenderPass):
    """A pass that lights G-buffer pixels into one rgba16f output (see the module docstring)."""

    COUNTS_NONFINITE = True   # scrubs NaN/Inf samples (glsl/nonfinite.glsl)
    USES_SCENE = True
    SHADER = ""
    OUTPUT = "color"
    OUTPUT_DESC = ""
    PIXEL_LIST: str | None = None   # input pin of the pixel list, for indirect dispatch
    SALT = RNG_SALTS["lighting"]   # its random stream (subclasses name their own)
    LOWEST_EFFECT = Effect.RASTER   # the pixels it lights: this effect and above
    COMPACTS = False   # its shader runs in batches (pixel_list.glsl ray_pass_batches): `compact_tiles` applies
    FILL_LOBE = "whole"   # what its output holds, for the trace decision's fill (trace_decision.fill)
    CHOICES = {"dispatch_mode": DISPATCHES}
    WHOLE = {"light_samples": (1, MAX_LIGHT_SAMPLES, "light samples per pixel")}

    def validate_property(self, key, value):
        return check_shape(self.name, key, super().validate_property(key, value))

    def reflect(self, cd):
        r = Reflection()
        channels.add_inputs(r, self.gbuffer_channels())
        if self.PIXEL_LIST:
            pin = r.add_input(self.PIXEL_LIST, "pixels to work on (EffectCompaction)").buffer(
                pixel_list_bytes(cd.size, cd.views)).indirect()
            if self._dispatch_2d(cd):
                pin.unused("runs over the whole image: no material is PATH_TRACED")
            DecisionFill.add_input(r)
            work_tiles.add_input(r, cd)
        r.add_output(self.OUTPUT, self.OUTPUT_DESC).format("rgba16f")
        probe_inputs.add_inputs(r, self.probes_unused(cd))
        return r

    def gbuffer_channels(self) -> tuple[str, ...]:
        """The G-buffer channels the pass reads (graphs wire them: channels.wire)."""
        return channels.LIGHTING

    def lit_effects(self) -> set:
        """The effects of the pixels this pass lights."""
        return {e for e in Effect if e >= self.LOWEST_EFFECT}

    def probes_unused(self, cd) -> str | None:
        """Why the probes' light would reach no pixel of this pass (None: it may)."""
        used = effects_used(cd)
        if used is None or used & self.lit_effects():
            return None
        return "no material has an effect this pass lights"

    def shader_defines(self) -> dict:
        return {}

    def probe_defines(self, cd) -> dict:
        """The defines of the pass's program when the probe inputs are bound: the lookups in it
        (PROBE_GI), unless the pass defers them to a dispatch of its own (RTReflections)."""
        return {"PROBE_GI": 1}

    def compile(self, ctx, cd):
        self._fill = DecisionFill([(self.OUTPUT, "rgba16f", self.FILL_LOBE)], self.LOWEST_EFFECT)
        if self.PIXEL_LIST:
            self._fill.compile(ctx, cd)
        self._pixels_2d = bool(self.PIXEL_LIST) and self._dispatch_2d(cd)
        if self.PIXEL_LIST:   # the ray passes: the shape is theirs to set
            view_group = decision_view_group(ctx, self.view_group) if self._fill.bound else self.view_group
            self._group = ray_group(cd.views, tuple(self.tile), view_group)
        else:
            self._group = ray_group(cd.views, tuple(TILE))
        order = view_order(ctx, cd.views, self._group) if self._fill.bound else None
        self._defines = {**scene_defines(ctx), **effect_defines(), "RNG_SALT": self.SALT, **self.shader_defines(),
                         "PIXELS_2D": int(self._pixels_2d), **ray_group_defines(self._group, order),
                         **self._fill.defines()}
        if self.PIXEL_LIST and not self._pixels_2d:
            self._defines["PIXEL_LIST_INPUT"] = 1
        # under a trace decision a workgroup gathers the pixels of `compact_tiles` tiles (glsl/pixel_list.glsl
        # RAY_PASS_COMPACT), else over the decision's work tiles when its workgroup is one (glsl/work_tiles.glsl)
        self._compact = self._compact_tiles(ctx, self._group) if self._pixels_2d and self._fill.bound else 1
        if self._compact > 1:
            self._defines["RAY_PASS_COMPACT"] = self._compact
        self._tiles = self._pixels_2d and self._compact == 1 and work_tiles.usable(ctx, cd, self._group)
        if self._tiles:
            self._defines["WORK_TILES_INPUT"] = 1
        self._probes = probe_inputs.bound(cd)
        if self._probes:
            import moderngl

            self._defines.update(self.probe_defines(cd))
            self._probe_sampler = self.own(ctx.gl.sampler(filter=(moderngl.LINEAR, moderngl.LINEAR),
                                                          repeat_x=False, repeat_y=False))
        self._prog = self.compute_program(ctx.gl, self.SHADER, self._defines)
        self._res = program_resources(self._prog)
        # whole-image dispatches: ray passes in ray_group tiles (`_compact` side by side), DirectLighting in
        # 8x8 tiles of one view
        gx, gy, gz = groups_2d(cd.size, cd.views, self._group if self._pixels_2d else COMPUTE_GROUP)
        self._groups = (-(-gx // self._compact), gy, gz)

    def _compact_tiles(self, ctx, group) -> int:
        """The tiles a workgroup gathers its pixels from (1: its own tile only): the pass's `compact_tiles`
        (0: GATHER_TILES where the decision's foveation dithers the traced pixels, else 1) where its shader
        runs in batches and the workgroup has at most 32 invocations (a mask word)."""
        if not self.COMPACTS or group[0] * group[1] * group[2] > 32:
            return 1
        tiles = int(self.compact_tiles)
        return tiles if tiles else (GATHER_TILES if ctx.dictionary.get(DITHERED_TRACE) else 1)

    def _dispatch_2d(self, cd) -> bool:
        if self.dispatch_mode != "auto":
            return self.dispatch_mode == "image"
        # A PATH_TRACED pixel may be on the path tracer's list instead of this one: only the list knows.
        used = effects_used(cd)
        return used is not None and Effect.PATH_TRACED not in used

    def set_uniforms(self, res) -> None:
        """Properties that are uniforms; set in execute() because programs are cached and shared
        between passes with the same defines."""

    def defines(self) -> dict:
        fill = self._fill.report() if hasattr(self, "_fill") else {}
        return {**(getattr(self, "_defines", {}) or self.shader_defines()), **fill}

    def execute(self, ctx, data):
        self.run_program(self._res, data)
        self._fill.run(ctx, data)

    def run_program(self, res, data) -> None:
        """Bind what program `res` of the pass reads (uniforms, its pixels and their surfaces, the
        probes) and its output `dst`, then dispatch it over the pass's pixels."""
        self.set_uniforms(res)
        self.bind_pixels(res, data)
        res.image("dst", data[self.OUTPUT])
        if self._probes:
            probe_inputs.bind(res, data, self._probe_sampler)
        self.dispatch(res, data)
        if self._probes:
            probe_inputs.unbind(res)

    def bind_pixels(self, res, data) -> None:
        """Bind what a program of the pass needs to find its pixels and their surfaces: the G-buffer
        channels and, when it reads one, the pixel list."""
        channels.bind_inputs(res, data, self.gbuffer_channels())
        self._fill.bind(res, data)
        if self.PIXEL_LIST and not self._pixels_2d:
            res.buffer("PixelList", data[self.PIXEL_LIST])

    def dispatch(self, res, data) -> None:
        """Run program `res` over the pass's pixels: the list's indirect dispatch, the decision's
        work tiles, or the whole image."""
        if self.PIXEL_LIST and not self._pixels_2d:
            res.prog.run_indirect(data[self.PIXEL_LIST], DISPATCH_OFFSET)
        elif self._tiles:
            work_tiles.run(res, data[work_tiles.WORK_TILES])
        else:   # the shader declares no list (the compaction pass was pruned)
            res.prog.run(*self._groups)

