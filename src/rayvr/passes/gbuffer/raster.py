"""GBufferRaster: every view in one draw into 2D texture arrays.

OVR multiview (gl_ViewID_OVR) where the driver has GL_OVR_multiview2; elsewhere layered instanced
rendering, each instance drawn once per view with gl_Layer set in the vertex shader.
"""
from __future__ import annotations

from ...errors import GpuError, ShaderError
from ...rendergraph.registry import register_pass
from ...rendergraph.render_pass import Access, Reflection, RenderPass
from ..effects import effect_defines, scene_defines
from . import channels, reflection_cutoff
from .layered_target import LayeredTarget, max_multiview_views

MULTIVIEW_MODES = ("auto", "on", "off")


def gbuffer_reflection(access: Access = Access.IMAGE) -> Reflection:
    """The G-buffer's output pins, one per channel (GBufferRaster, GBufferRT and GBufferAuto
    declare the same), written as `access` says."""
    r = Reflection()
    channels.add_outputs(r)
    for pin in r.outputs():
        pin.accessed(access)
    return r


@register_pass
class GBufferRaster(RenderPass):
    """Rasterises the scene for all views in one draw call (see the module docstring)."""

    PROPERTIES = {"multiview": "auto", "cull_back_faces": False, reflection_cutoff.PROPERTY: 1.0}
    CHOICES = {"multiview": MULTIVIEW_MODES}
    USES_SCENE = True

    def validate_property(self, key, value):
        value = super().validate_property(key, value)
        if key == reflection_cutoff.PROPERTY:
            return reflection_cutoff.validate(self.name, value)
        return value

    def reflect(self, cd):
        return gbuffer_reflection(Access.FRAMEBUFFER)

    def uses_multiview(self, caps, views: int = 2) -> bool:
        """OVR multiview when asked for (or 'auto') and the driver can draw `views` views at once."""
        if self.multiview == "off":
            return False
        has = bool(caps is not None and caps.multiview)
        limit = max_multiview_views() if has else 0
        if self.multiview == "on" and not (has and views <= limit):
            raise GpuError(f"pass {self.name}: multiview='on' but the driver has no GL_OVR_multiview2 for "
                           f"{views} views (GL_MAX_VIEWS_OVR {limit}); use multiview='auto' (layered rendering)")
        return has and views <= limit

    def compile(self, ctx, cd):
        self._multiview = self.uses_multiview(ctx.caps, cd.views)
        if not self._multiview and not ctx.caps.vertex_layer:
            raise GpuError(f"pass {self.name}: the driver has neither GL_OVR_multiview2 nor "
                           f"GL_ARB_shader_viewport_layer_array; one draw cannot reach every view")
        self._views = cd.views
        self.multiview_fallback = None
        self.release()
        try:
            self._build_program(ctx)
        except ShaderError as exc:
            if not (self._multiview and self.multiview == "auto"):
                raise
            self._fall_back_to_layered(ctx, f"multiview shader failed: {exc}")

    def release(self) -> None:
        """Free the framebuffer and depth array this pass made (it remakes them when needed)."""
        super().release()
        target = self.__dict__.get("_target")
        if target is not None:
            target.release()
        self._target = None
        self._target_key = None

    def _build_program(self, ctx) -> None:
        self._defines = {**scene_defines(ctx), **effect_defines(), "VIEW_COUNT": self._views,
                         "RAYVR_MULTIVIEW": int(self._multiview),
                         **reflection_cutoff.defines(self.reflection_max_roughness)}
        self._prog = self.raster_program(ctx.gl, "gbuffer.vert", "gbuffer.frag", self._defines)

    def _fall_back_to_layered(self, ctx, reason: str) -> None:
        """multiview='auto' on a driver whose multiview path fails: render layered instead."""
        if not ctx.caps.vertex_layer:
            raise GpuError(f"pass {self.name}: {reason}; and no GL_ARB_shader_viewport_layer_array to fall back on")
        self._multiview = False
        self.multiview_fallback = reason
        self._build_program(ctx)

    def defines(self) -> dict:
        return dict(getattr(self, "_defines", {}))

    def _ensure_target(self, ctx, data):
        colors = [data[c.name] for c in channels.CHANNELS]
        key = tuple(c.glo for c in colors)
        if key != self._target_key:   # first frame, or the graph re-allocated its textures
            if self._target is not None:
                self._target.release()
            try:
                self._target = LayeredTarget(ctx.gl, colors, data.size, data.views, self._multiview)
            except GpuError as exc:
                if not (self._multiview and self.multiview == "auto"):
                    raise
                self._fall_back_to_layered(ctx, f"multiview framebuffer failed: {exc}")
                self._target = LayeredTarget(ctx.gl, colors, data.size, data.views, False)
            self._target.set_clear_values([("uint", *c.clear) if c.is_uint else (*c.clear, *(0.0,) * (4 - len(c.clear)))
                                           for c in channels.CHANNELS])
            self._target_key = key
        return self._target

    def execute(self, ctx, data):
        import moderngl

        target = self._ensure_target(ctx, data)
        gl = ctx.gl
        target.use_and_clear()
        gl.enable(moderngl.DEPTH_TEST)
        if self.cull_back_faces:
            gl.enable(moderngl.CULL_FACE)
        ctx.scene.draw(self._prog, 1 if self._multiview else data.views)
        gl.disable(moderngl.DEPTH_TEST | moderngl.CULL_FACE)
