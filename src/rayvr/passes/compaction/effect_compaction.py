"""EffectCompaction: the per-effect pixel lists the ray passes dispatch over (indirectly)."""
from __future__ import annotations

from ...gpu.program_resources import program_resources
from ...materials.effect import Effect
from ...rendergraph.registry import register_pass
from ...rendergraph.render_pass import Reflection, RenderPass
from ..dispatch import groups_2d
from ..effects import effect_defines, effects_used, unused_effect_reason
from ..trace_decision.fill import DECISION, DecisionFill
from .pixel_list import HEADER_BYTES, empty_lists, pixel_list_bytes

LISTS = {"shadowPixels": "ShadowList", "reflectionPixels": "ReflectionList", "pathPixels": "PathList"}   # pin -> GLSL block


@register_pass
class EffectCompaction(RenderPass):
    """Reads the G-buffer's effect ids and appends each pixel to the lists of the ray work it needs:
    `shadowPixels` (effect >= SHADOWS) and `reflectionPixels` (effect >= REFLECTIONS), each with
    its own indirect dispatch arguments. With `path_list` PATH_TRACED pixels go to `pathPixels`
    only (for a PathTracer); without, they count as REFLECTIONS. All views in one dispatch.
    With the optional `decision` input (TraceDecision) the pixels it reconstructs are left out of
    every list: only the pixels that trace this frame are dispatched. `every_surface` (with
    `path_list`): every pixel, drawn or not, goes to `pathPixels` (a path tracer from the camera)."""

    EFFECT = "effect"
    SHADOW_PIXELS, REFLECTION_PIXELS, PATH_PIXELS = "shadowPixels", "reflectionPixels", "pathPixels"
    PROPERTIES = {"path_list": False, "every_surface": False}

    def reflect(self, cd):
        r = Reflection()
        r.add_input(self.EFFECT, "effect id per pixel (r32ui)").format("r32ui")
        DecisionFill.add_input(r)
        n = pixel_list_bytes(cd.size, cd.views)
        r.add_output(self.SHADOW_PIXELS, "pixels needing shadow rays").buffer(n)
        r.add_output(self.REFLECTION_PIXELS, "pixels needing reflection rays").buffer(n)
        r.add_output(self.PATH_PIXELS, "PATH_TRACED pixels (with path_list)").buffer(n if self.path_list else HEADER_BYTES)
        return r

    def skip_reason(self, cd):
        if unused_effect_reason(cd, Effect.SHADOWS) and not self.every_surface:
            return "every material is RASTER: no pixel needs rays"
        return None

    def defines(self) -> dict:
        return dict(getattr(self, "_defines", {}))

    def compile(self, ctx, cd):
        used = effects_used(cd)
        every = bool(self.every_surface and self.path_list)
        paths = bool(self.path_list) and (every or used is None or Effect.PATH_TRACED in used)
        reflections = not every and (used is None or any(
            e >= Effect.REFLECTIONS and not (paths and e == Effect.PATH_TRACED) for e in used))
        self._defines = {"COMPACT_REFLECTIONS": int(reflections), "COMPACT_PATHS": int(paths),
                         "COMPACT_EVERY_SURFACE": int(every),
                         "TRACE_DECISION": int(DecisionFill.connected(cd))}
        self._compact = program_resources(self.compute_program(ctx.gl, "compact.comp",
                                                               {**effect_defines(), **self._defines}))
        self._groups = groups_2d(cd.size, cd.views)

    def execute(self, ctx, data):
        empty_lists(ctx, *(data[pin] for pin in LISTS))
        for pin, block in LISTS.items():
            self._compact.buffer(block, data[pin])
        self._compact.texture("gbuf_effect", data[self.EFFECT])
        if self._defines["TRACE_DECISION"]:
            self._compact.texture("trace_decision", data[DECISION])
        self._compact.prog.run(*self._groups)
