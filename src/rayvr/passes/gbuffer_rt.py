"""GBufferRT: the G-buffer by ray tracing, in one compute dispatch for every view.

The same pins, formats and encoding as GBufferRaster (glsl/gbuffer.glsl gbuf_encode), so either can
feed the hybrid lighting passes. It pays off where fragment work is slow against compute (NVIDIA
datacenter GPUs with few graphics-capable TPCs: Capabilities.weak_raster); GBufferAuto chooses.
Like the raster path, only surfaces between the views' near and far planes are seen. Differences:
textures are read at mip 0 (no screen-space derivatives), and silhouettes and sub-pixel triangles
may land on other pixels (a ray samples the pixel centre exactly, raster follows its fill rules).
"""
from __future__ import annotations

from ..rendergraph.render_pass import RenderPass
from ._common import (
    bind_scene,
    build_compute,
    effect_defines,
    groups_2d,
    ray_group,
    ray_group_defines,
    register,
    require_scene,
    scene_defines,
)
from .gbuffer import OUTPUTS, gbuffer_reflection


@register
class GBufferRT(RenderPass):
    """Traces one primary ray per pixel and view (pixel centre + the view's jitter) and writes the
    G-buffer targets (see the module docstring)."""

    def reflect(self, cd):
        return gbuffer_reflection()

    # Views a workgroup spans in a camera grid (passes._common.VIEW_GROUP): primary rays gain from 2
    # and lose from more (H100, tauray, 64 views: 2.71 ms against 2.87 for 1 and 3.04 for 4).
    VIEW_GROUP = 2

    def compile(self, ctx, cd):
        require_scene(ctx, self)
        self._group = ray_group(cd.views, view_group=self.VIEW_GROUP)
        self._defines = {**scene_defines(ctx), **effect_defines(), **ray_group_defines(self._group)}
        self._prog = build_compute(ctx.gl, "gbuffer_rt.comp", self._defines)

    def defines(self) -> dict:
        return dict(getattr(self, "_defines", {}))

    def execute(self, ctx, data):
        bind_scene(ctx)
        for unit, pin in enumerate(OUTPUTS):
            data[pin].bind_to_image(unit, read=False, write=True)
        self._prog.run(*groups_2d(data.size, data.views, self._group))
        ctx.gl.memory_barrier()
