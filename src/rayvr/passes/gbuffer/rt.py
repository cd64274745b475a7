"""GBufferRT: the G-buffer by ray tracing, in one compute dispatch for every view.

The same pins, formats and encoding as GBufferRaster (glsl/gbuffer.glsl gbuf_encode), so either can
feed the hybrid lighting passes. It pays off where fragment work is slow against compute (NVIDIA
datacenter GPUs with few graphics-capable TPCs: Capabilities.weak_raster); GBufferAuto chooses.
Like the raster path, only surfaces between the views' near and far planes are seen. Differences:
textures are read at mip 0 (no screen-space derivatives), and silhouettes and sub-pixel triangles
may land on other pixels (a ray samples the pixel centre exactly, raster follows its fill rules).
"""
from __future__ import annotations

from ...gpu.program_resources import program_resources
from ...rendergraph.registry import register_pass
from ...rendergraph.render_pass import RenderPass
from ..dispatch import check_shape, groups_2d, ray_group, ray_group_defines
from ..effects import effect_defines, scene_defines
from . import channels, reflection_cutoff
from .raster import gbuffer_reflection


@register_pass
class GBufferRT(RenderPass):
    """Traces one primary ray per pixel and view (pixel centre + the view's jitter) and writes the
    G-buffer targets (see the module docstring)."""

    # `tile`, `view_group`: a workgroup of one warp, a 4x8 tile, in a camera grid 4x4 pixels of 2
    # views (workgroups of 64 invocations take about twice as long: benchmarks/RESULTS.md, "views a
    # ray pass's workgroup spans").
    PROPERTIES = {reflection_cutoff.PROPERTY: 1.0, "tile": [4, 8], "view_group": 2}
    USES_SCENE = True

    def validate_property(self, key, value):
        value = super().validate_property(key, value)
        value = check_shape(self.name, key, value)
        return reflection_cutoff.validate(self.name, value) if key == reflection_cutoff.PROPERTY else value

    def reflect(self, cd):
        return gbuffer_reflection()

    def compile(self, ctx, cd):
        self._group = ray_group(cd.views, tuple(self.tile), self.view_group)
        self._defines = {**scene_defines(ctx), **effect_defines(), **ray_group_defines(self._group),
                         **reflection_cutoff.defines(self.reflection_max_roughness)}
        self._prog = self.compute_program(ctx.gl, "gbuffer_rt.comp", self._defines)
        self._res = program_resources(self._prog)
        self._groups = groups_2d(cd.size, cd.views, self._group)

    def defines(self) -> dict:
        return dict(getattr(self, "_defines", {}))

    def execute(self, ctx, data):
        channels.bind_outputs(self._res, data)
        self._prog.run(*self._groups)
