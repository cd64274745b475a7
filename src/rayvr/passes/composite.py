"""HybridComposite: each pixel's lighting chosen by its material's effect."""
from __future__ import annotations

from ..rendergraph.render_pass import Reflection, RenderPass
from ._common import build_compute, effect_defines, groups_2d, register


@register
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
        self._prog = build_compute(ctx.gl, "composite.comp",
                                   {**effect_defines(), **{d: int(pin in cd.input_formats) for d, pin in has.items()}})

    def execute(self, ctx, data):
        shadowed, reflection, path = data.get(self.SHADOWED), data.get(self.REFLECTION), data.get(self.PATH_TRACED)
        data[self.EFFECT].use(location=0)
        data[self.DIRECT].use(location=1)
        if shadowed is not None:
            shadowed.use(location=2)
        if reflection is not None:
            reflection.use(location=3)
        if path is not None:
            path.use(location=4)
        data[self.COLOR].bind_to_image(0, read=False, write=True)
        self._prog.run(*groups_2d(data.size, data.views))
        ctx.gl.memory_barrier()
