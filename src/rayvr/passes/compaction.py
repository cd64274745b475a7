"""EffectCompaction: the per-effect pixel lists the ray passes dispatch over (indirectly)."""
from __future__ import annotations

import numpy as np

from ..gpu.bindings import BINDINGS
from ..materials.effect import Effect
from ..rendergraph.render_pass import Reflection, RenderPass
from ._common import (
    build_compute,
    effect_defines,
    effects_used,
    groups_2d,
    register,
    unused_effect_reason,
)

HEADER_BYTES = 16  # count + indirect dispatch args (glsl/pixel_list.glsl)
PASS_SSBOS = tuple(BINDINGS[f"RAYVR_PASS_SSBO_{i}"] for i in range(3))
DISPATCH_OFFSET = 4


def pixel_list_bytes(size: tuple[int, int], views: int) -> int:
    """Bytes of a pixel list that can hold every pixel of every view."""
    return HEADER_BYTES + 4 * size[0] * size[1] * views


def read_pixel_list(buffer) -> tuple[int, np.ndarray]:
    """(count, (n, 3) x/y/view) of a pixel-list buffer; a readback for tests and tools."""
    head = np.frombuffer(buffer.read(HEADER_BYTES), dtype=np.uint32)
    n = int(head[0])
    items = np.frombuffer(buffer.read(4 * n, offset=HEADER_BYTES), dtype=np.uint32) if n else np.zeros(0, np.uint32)
    xyz = np.stack([items & 0x1FFF, (items >> 13) & 0x1FFF, items >> 26], axis=1)
    return n, xyz


@register
class EffectCompaction(RenderPass):
    """Reads the G-buffer's effect ids and appends each pixel to the lists of the ray work it needs:
    `shadowPixels` (effect >= SHADOWS) and `reflectionPixels` (effect >= REFLECTIONS), each with
    its own indirect dispatch arguments. With `path_list` PATH_TRACED pixels go to `pathPixels`
    only (for a PathTracer); without, they count as REFLECTIONS. All views in one dispatch."""

    EFFECT = "effect"
    SHADOW_PIXELS, REFLECTION_PIXELS, PATH_PIXELS = "shadowPixels", "reflectionPixels", "pathPixels"
    PROPERTIES = {"path_list": False}

    def reflect(self, cd):
        r = Reflection()
        r.add_input(self.EFFECT, "effect id per pixel (r32ui)").format("r32ui")
        n = pixel_list_bytes(cd.size, cd.views)
        r.add_output(self.SHADOW_PIXELS, "pixels needing shadow rays").buffer(n)
        r.add_output(self.REFLECTION_PIXELS, "pixels needing reflection rays").buffer(n)
        r.add_output(self.PATH_PIXELS, "PATH_TRACED pixels (with path_list)").buffer(n if self.path_list else HEADER_BYTES)
        return r

    def skip_reason(self, cd):
        if unused_effect_reason(cd, Effect.SHADOWS):
            return "every material is RASTER: no pixel needs rays"
        return None

    def defines(self) -> dict:
        return dict(getattr(self, "_defines", {}))

    def compile(self, ctx, cd):
        used = effects_used(cd)
        paths = bool(self.path_list) and (used is None or Effect.PATH_TRACED in used)
        reflections = used is None or any(e >= Effect.REFLECTIONS and not (paths and e == Effect.PATH_TRACED)
                                          for e in used)
        self._defines = {"COMPACT_REFLECTIONS": int(reflections), "COMPACT_PATHS": int(paths)}
        self._reset = build_compute(ctx.gl, "compact_reset.comp")
        self._prog = build_compute(ctx.gl, "compact.comp", {**effect_defines(), **self._defines})

    def execute(self, ctx, data):
        for pin, binding in zip((self.SHADOW_PIXELS, self.REFLECTION_PIXELS, self.PATH_PIXELS), PASS_SSBOS):
            data[pin].bind_to_storage_buffer(binding)
        self._reset.run(1)
        ctx.gl.memory_barrier()
        data[self.EFFECT].use(location=0)
        self._prog.run(*groups_2d(data.size, data.views))
        ctx.gl.memory_barrier()
