"""HybridComposite: each pixel's lighting chosen by its material's effect."""
from __future__ import annotations

from ...gpu.program_resources import program_resources
from ...rendergraph.registry import register_pass
from ...rendergraph.render_pass import Access, Reflection, RenderPass
from ..basic.clear import zero_image, zero_program
from ..dispatch import (COMPUTE_GROUP, check_shape, decision_view_group, groups_2d, ray_group, ray_group_defines,
                        view_order)
from ..effects import effect_defines, scene_defines
from ..gbuffer import channels
from ..probe_gi import inputs as probe_inputs
from ..trace_decision import work_tiles
from ..trace_decision.fill import DECISION, DecisionFill

# input pin -> the sampler uniform composite.comp reads it through (the G-buffer's: channels.bind_inputs)
SAMPLERS = {"direct": "direct_tex", "shadowed": "shadowed_tex", "reflection": "reflection_tex", "pathTraced": "path_tex",
            "pathDiffuse": "path_diffuse_tex", "pathSpecular": "path_specular_tex"}


@register_pass
class HybridComposite(RenderPass):
    """`direct` for RASTER pixels, `shadowed` (optional) for SHADOWS and above, plus `reflection`
    (optional) for REFLECTIONS and above, `pathTraced` (optional) instead of all of them for
    PATH_TRACED pixels -> `color` (rgba16f radiance). A missing optional input
    (its pass pruned because no material needs it) compiles its code out. With the probe inputs
    and the G-buffer's lighting channels connected (rayvr.passes.probe_gi.inputs), the probes'
    indirect diffuse light is added to RASTER, SHADOWS and REFLECTIONS pixels here.

    With `lobes` the pass also writes the light as a denoiser demodulates it (rayvr.passes.SVGF):
    `diffuse` (direct or shadowed light minus the G-buffer's `emissive`, or the path tracer's
    `pathDiffuse`; the background where nothing was drawn) and `specular` (reflections, or
    `pathSpecular`). With the optional `decision` (TraceDecision) a pixel it flags for SVGF to
    spread another view's filtered light to (`spread`) is 0 in every output."""

    EFFECT, DIRECT, SHADOWED, REFLECTION, PATH_TRACED = "effect", "direct", "shadowed", "reflection", "pathTraced"
    EMISSIVE, PATH_DIFFUSE, PATH_SPECULAR = "emissive", "pathDiffuse", "pathSpecular"
    COLOR, DIFFUSE, SPECULAR = "color", "diffuse", "specular"
    # `probe_tile`, `probe_view_group`: with the probe lookups, one-warp workgroups spanning 4 views
    # of a camera grid (passes.dispatch.ray_group), because neighbouring views' lookups share probes
    # (8x8 tiles of one view cost them a fifth more); without probes, 8x8 tiles of one view, which
    # take half the time of 8x4 ones (benchmarks/RESULTS.md has the measurements). Under view reuse over
    # a camera grid one view a workgroup (TraceDecision `one_view_tiles`): 1.30 against 1.40 ms at 64 views.
    PROPERTIES = {"lobes": False, "probe_tile": [8, 4], "probe_view_group": 4}

    def validate_property(self, key, value):
        return check_shape(self.name, key, super().validate_property(key, value))

    def reflect(self, cd):
        r = Reflection()
        r.add_input(self.EFFECT, "effect id per pixel").format("r32ui")
        r.add_input(self.DIRECT, "unshadowed direct light + emission + background")
        r.add_input(self.SHADOWED, "ray-traced shadowed direct light").optional()
        r.add_input(self.REFLECTION, "ray-traced reflected radiance").optional()
        r.add_input(self.PATH_TRACED, "path-traced radiance for PATH_TRACED pixels").optional()
        r.add_output(self.COLOR, "composited HDR radiance").format("rgba16f")
        probe_inputs.add_inputs(r)
        for name in channels.LIGHTING:   # the surface for the probe lookup (emissive: also the lobes')
            if name != self.EFFECT:
                c = channels.channel(name)
                pin = r.add_input(c.name, f"G-buffer {c.name}: {c.meaning}").format(c.format)
                if not (self.lobes and name == self.EMISSIVE):
                    pin.optional()
        if self.lobes:
            r.add_input(self.PATH_DIFFUSE, "the path tracer's diffuse lobe (PathTracer lobes)").optional()
            r.add_input(self.PATH_SPECULAR, "the path tracer's specular lobe").optional()
            r.add_output(self.DIFFUSE, "diffuse light, emission excluded (background where nothing was drawn)"
                         ).format("rgba16f")
            r.add_output(self.SPECULAR, "specular light").format("rgba16f")
        DecisionFill.add_input(r)
        work_tiles.add_input(r, cd)
        return r

    def compile(self, ctx, cd):
        # cd.input_formats holds only the inputs that will be bound: one variant is all it needs.
        has = {"HAS_SHADOWS": self.SHADOWED, "HAS_REFLECTIONS": self.REFLECTION, "HAS_PATHS": self.PATH_TRACED,
               "HAS_PATH_LOBES": self.PATH_DIFFUSE}
        defines = {d: int(pin in cd.input_formats) for d, pin in has.items()}
        decided = DecisionFill.connected(cd)
        if decided:
            defines["TRACE_DECISION"] = 1
        self._probes = probe_inputs.bound(cd) and all(n in cd.input_formats for n in channels.LIGHTING)
        if self._probes:
            import moderngl

            defines["PROBE_GI"] = 1
            self._probe_sampler = self.own(ctx.gl.sampler(filter=(moderngl.LINEAR, moderngl.LINEAR),
                                                          repeat_x=False, repeat_y=False))
        view_group = decision_view_group(ctx, self.probe_view_group) if decided else self.probe_view_group
        self._group = ray_group(cd.views, tuple(self.probe_tile), view_group) if self._probes else (*COMPUTE_GROUP, 1)
        order = view_order(ctx, cd.views, self._group) if decided else None
        # over the decision's work tiles when its workgroup is one: the colour is cleared first, so that
        # the spread pixels of the tiles left out hold 0 as the others do
        self._tiles = work_tiles.usable(ctx, cd, self._group)
        if self._tiles:
            defines["WORK_TILES_INPUT"] = 1
            self._clear = zero_program(ctx.gl, "rgba16f")
        self._defines = {**defines, "SPLIT_LOBES": int(bool(self.lobes)), **ray_group_defines(self._group, order)}
        # the scene's features: the probe lookup shades the G-buffer surface with its whole material
        self._prog = self.compute_program(ctx.gl, "composite.comp",
                                          {**scene_defines(ctx), **effect_defines(), **self._defines})
        self._res = program_resources(self._prog)
        self._groups = groups_2d(cd.size, cd.views, self._group)

    def defines(self) -> dict:
        return dict(getattr(self, "_defines", {}))

    def execute(self, ctx, data):
        channels.bind_inputs(self._res, data)   # those connected: effect, emissive, the probe lookup's surface
        for pin, sampler in SAMPLERS.items():
            tex = data.get(pin)
            if tex is not None:
                self._res.texture(sampler, tex)
        if DECISION in data:
            self._res.texture("trace_decision", data[DECISION])
        self._res.image("dst", data[self.COLOR])
        if self.lobes:
            self._res.image("dst_diffuse", data[self.DIFFUSE])
            self._res.image("dst_specular", data[self.SPECULAR])
        if self._probes:
            probe_inputs.bind(self._res, data, self._probe_sampler)
        if self._tiles:
            zero_image(self._clear, data[self.COLOR])
            ctx.barrier(Access.IMAGE)   # the zeros land before the tiles' stores
            work_tiles.run(self._res, data[work_tiles.WORK_TILES])
        else:
            self._prog.run(*self._groups)
        if self._probes:
            probe_inputs.unbind(self._res)
