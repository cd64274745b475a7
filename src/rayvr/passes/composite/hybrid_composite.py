"""HybridComposite: each pixel's lighting chosen by its material's effect."""
from __future__ import annotations

from ...gpu.program_resources import program_resources
from ...rendergraph.registry import register_pass
from ...rendergraph.render_pass import Reflection, RenderPass
from ..dispatch import groups_2d
from ..effects import effect_defines

# input pin -> the sampler uniform composite.comp reads it through
SAMPLERS = {"effect": "gbuf_effect", "direct": "direct_tex", "shadowed": "shadowed_tex",
            "reflection": "reflection_tex", "pathTraced": "path_tex"}


@register_pass
class HybridComposite(RenderPass):
    """`direct` for RASTER pixels, `shadowed` (optional) for SHADOWS and above, plus `reflection`
    (optional) for REFLECTIONS and above, `pathTraced` (optional) instead of all of them for
    PATH_TRACED pixels -> `color` (rgba16f radiance). A missing optional input
    (its pass pruned because no material needs it) compiles its code out."""

    EFFECT, DIRECT, SHADOWED, REFLECTION, PATH_TRACED = "effect", "direct", "shadowed", "reflection", "pathTraced"
    COLOR = "color"
    PROPERTIES = {}

    def reflect(self, cd):
        r = Reflection()
        r.add_input(self.EFFECT, "effect id per pixel").format("r32ui")
        r.add_input(self.DIRECT, "unshadowed direct light + emission + background")
        r.add_input(self.SHADOWED, "ray-traced shadowed direct light").optional()
        r.add_input(self.REFLECTION, "ray-traced reflected radiance").optional()
        r.add_input(self.PATH_TRACED, "path-traced radiance for PATH_TRACED pixels").optional()
        r.add_output(self.COLOR, "composited HDR radiance").format("rgba16f")
        return r

    def compile(self, ctx, cd):
        # cd.input_formats holds only the inputs that will be bound: one variant is all it needs.
        has = {"HAS_SHADOWS": self.SHADOWED, "HAS_REFLECTIONS": self.REFLECTION, "HAS_PATHS": self.PATH_TRACED}
        self._prog = self.compute_program(ctx.gl, "composite.comp",
                                          {**effect_defines(), **{d: int(pin in cd.input_formats) for d, pin in has.items()}})
        self._res = program_resources(self._prog)
        self._groups = groups_2d(cd.size, cd.views)

    def execute(self, ctx, data):
        for pin, sampler in SAMPLERS.items():
            tex = data.get(pin)
            if tex is not None:
                self._res.texture(sampler, tex)
        self._res.image("dst", data[self.COLOR])
        self._prog.run(*self._groups)
