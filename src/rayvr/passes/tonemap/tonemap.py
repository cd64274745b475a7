"""ToneMapper: HDR radiance to display rgba8 (ACES, Reinhard or linear; exposure; auto exposure; sRGB)."""
from __future__ import annotations

import struct

from ...gpu.program_resources import program_resources
from ...rendergraph.registry import register_pass
from ...rendergraph.render_pass import Access, Reflection, RenderPass
from ..dispatch import groups_2d

OPERATORS = {"aces": 0, "reinhard": 1, "linear": 2}


@register_pass
class ToneMapper(RenderPass):
    """`src` (linear radiance) -> `dst` (rgba8, sRGB-encoded unless `srgb` is false).

    `exposure` is in stops (x 2^exposure). With `auto_exposure` the frame's mean log luminance is
    mapped to `key` (0.18 = mid grey), adapting by `adaptation` per frame (1 = at once).
    """

    SRC, DST = "src", "dst"
    COUNTS_NONFINITE = True   # scrubs NaN/Inf samples (glsl/nonfinite.glsl)
    PROPERTIES = {"operator": "aces", "exposure": 0.0, "auto_exposure": False, "key": 0.18,
                  "adaptation": 1.0, "srgb": True}

    CHOICES = {"operator": tuple(OPERATORS)}

    def validate_property(self, key, value):
        if key == "operator" and isinstance(value, str):
            value = value.lower()
        return super().validate_property(key, value)

    def reflect(self, cd):
        r = Reflection()
        r.add_input(self.SRC, "linear HDR radiance")
        r.add_output(self.DST, "display-referred colour").format("rgba8")
        return r

    def defines(self) -> dict:
        return {"TONEMAP_OPERATOR": OPERATORS[self.operator], "AUTO_EXPOSURE": int(self.auto_exposure),
                "OUTPUT_SRGB": int(self.srgb)}

    def compile(self, ctx, cd):
        gl = ctx.gl
        self._tonemap = program_resources(self.compute_program(gl, "tonemap.comp", self.defines()))
        self._groups = groups_2d(cd.size, cd.views)
        if self.auto_exposure:
            self._lum_groups = groups_2d(cd.size, cd.views, (16, 16))   # luminance.comp's local size
            count = self._lum_groups[0] * self._lum_groups[1] * cd.views
            self._partials = self.own(gl.buffer(reserve=8 * count))
            self._exposure = self.own(gl.buffer(struct.pack("f", 0.0)))
            self._lum = program_resources(self.compute_program(gl, "luminance.comp"))
            self._reduce = program_resources(self.compute_program(gl, "exposure.comp"))
            self._partial_count = count

    def execute(self, ctx, data):
        # Uniforms here, not in compile(): programs are cached and shared with other ToneMappers.
        tm = self._tonemap
        tm.set("exposure_stops", float(self.exposure))
        if self.auto_exposure:
            lum, reduce = self._lum, self._reduce
            reduce.set("partial_count", self._partial_count)
            reduce.set("key", float(self.key))
            reduce.set("adaptation", float(self.adaptation))
            lum.texture("src", data[self.SRC])
            lum.buffer("Partials", self._partials)
            lum.prog.run(*self._lum_groups)
            ctx.barrier(Access.STORAGE)
            reduce.buffer("Exposure", self._exposure)
            reduce.buffer("Partials", self._partials)
            reduce.prog.run(1)
            ctx.barrier(Access.STORAGE)
            tm.buffer("Exposure", self._exposure)
        tm.texture("src", data[self.SRC])
        tm.image("dst", data[self.DST])
        tm.prog.run(*self._groups)

    def exposure_scale(self) -> float | None:
        """The auto exposure multiplier of the last frame (reads back; for tests and tools)."""
        if not self.auto_exposure:
            return None
        return struct.unpack("f", self._exposure.read())[0]
