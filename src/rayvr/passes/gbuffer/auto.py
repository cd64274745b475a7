"""GBufferAuto: GBufferRaster or GBufferRT, chosen when the graph compiles (the driver is known).

Raster unless the GPU's fragment work is weak against its compute (Capabilities.weak_raster:
datacenter compute GPUs); llvmpipe and desktop GPUs rasterise. `mode` forces either. `tile` and
`view_group` are GBufferRT's workgroup shape (the raster G-buffer has none).
"""
from __future__ import annotations

from ...rendergraph.registry import register_pass
from ...rendergraph.render_pass import Access, RenderPass
from ..dispatch import check_shape
from . import reflection_cutoff
from .raster import MULTIVIEW_MODES, GBufferRaster, gbuffer_reflection
from .rt import GBufferRT

MODES = ("auto", "raster", "rt")


def choose_gbuffer(mode: str, caps, cull_back_faces: bool = False) -> tuple[str, str]:
    """('raster' | 'rt', why) for `mode` on a driver with capabilities `caps`."""
    if mode != "auto":
        return mode, f"gbuffer='{mode}' asked for"
    if caps is not None and getattr(caps, "weak_raster", False):
        if cull_back_faces:
            return "raster", "cull_back_faces needs the raster G-buffer (the ray queries hit both faces)"
        return "rt", f"weak raster on {caps.renderer} (few graphics-capable units): ray-traced G-buffer"
    renderer = getattr(caps, "renderer", "no driver")
    return "raster", f"raster is fast enough on {renderer}"


@register_pass
class GBufferAuto(RenderPass):
    """The G-buffer through GBufferRaster or GBufferRT (see the module docstring). After compile,
    `chosen` is 'raster' or 'rt' and `why` says why; defines() shows both in the compile report."""

    PROPERTIES = {"mode": "auto", "multiview": "auto", "cull_back_faces": False, reflection_cutoff.PROPERTY: 1.0,
                  "tile": GBufferRT.PROPERTIES["tile"], "view_group": GBufferRT.PROPERTIES["view_group"]}
    CHOICES = {"mode": MODES, "multiview": MULTIVIEW_MODES}
    USES_SCENE = True

    def validate_property(self, key, value):
        value = super().validate_property(key, value)
        if key == reflection_cutoff.PROPERTY:
            return reflection_cutoff.validate(self.name, value)
        return check_shape(self.name, key, value)

    def reflect(self, cd):
        chosen, _ = choose_gbuffer(self.mode, cd.caps, self.cull_back_faces)
        return gbuffer_reflection(Access.FRAMEBUFFER if chosen == "raster" else Access.IMAGE)

    def compile(self, ctx, cd):
        self.chosen, self.why = choose_gbuffer(self.mode, ctx.caps, self.cull_back_faces)
        self.release()
        if self.chosen == "rt":
            self.impl = GBufferRT(reflection_max_roughness=self.reflection_max_roughness, tile=self.tile,
                                  view_group=self.view_group)
        else:
            self.impl = GBufferRaster(multiview=self.multiview, cull_back_faces=self.cull_back_faces,
                                      reflection_max_roughness=self.reflection_max_roughness)
        self.impl.name = self.name
        self.impl.compile(ctx, cd)

    def release(self) -> None:
        """Free what the chosen implementation made."""
        super().release()
        impl = self.__dict__.get("impl")
        if impl is not None and hasattr(impl, "release"):
            impl.release()

    def defines(self) -> dict:
        impl = self.__dict__.get("impl")
        if impl is None:
            return {}
        return {"GBUFFER": f"{type(impl).__name__} ({self.why})", **impl.defines()}

    def execute(self, ctx, data):
        self.impl.execute(ctx, data)
