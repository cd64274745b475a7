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
        self._programs = {}
        for s in (0, 1):
            for refl in (0, 1):
                for path in (0, 1):
                    self._programs[(s, refl, path)] = build_compute(
                        ctx.gl, "composite.comp",
                        {**effect_defines(), "HAS_SHADOWS": s, "HAS_REFLECTIONS": refl, "HAS_PATHS": path})

    def execute(self, ctx, data):
        shadowed, reflection, path = data.get(self.SHADOWED), data.get(self.REFLECTION), data.get(self.PATH_TRACED)
        prog = self._programs[(int(shadowed is not None), int(reflection is not None), int(path is not None))]
        data[self.EFFECT].use(location=0)
        data[self.DIRECT].use(location=1)
        if shadowed is not None:
            shadowed.use(location=2)
        if reflection is not None:
            reflection.use(location=3)
        if path is not None:
            path.use(location=4)
        data[self.COLOR].bind_to_image(0, read=False, write=True)
        prog.run(*groups_2d(data.size, data.views))
        ctx.gl.memory_barrier()
