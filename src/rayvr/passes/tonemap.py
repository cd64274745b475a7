"""ToneMapper: HDR radiance to display rgba8 (ACES, Reinhard or linear; exposure; auto exposure; sRGB)."""
from __future__ import annotations

import struct

from ..errors import OptionError
from ..gpu.bindings import BINDINGS
from ..rendergraph.render_pass import Reflection, RenderPass
from ._common import build_compute, groups_2d, register

OPERATORS = {"aces": 0, "reinhard": 1, "linear": 2}


@register
class ToneMapper(RenderPass):
    """`src` (linear radiance) -> `dst` (rgba8, sRGB-encoded unless `srgb` is false).

    `exposure` is in stops (x 2^exposure). With `auto_exposure` the frame's mean log luminance is
    mapped to `key` (0.18 = mid grey), adapting by `adaptation` per frame (1 = at once).
    """

    SRC, DST = "src", "dst"
    PROPERTIES = {"operator": "aces", "exposure": 0.0, "auto_exposure": False, "key": 0.18,
                  "adaptation": 1.0, "srgb": True}

    def validate_property(self, key, value):
        value = super().validate_property(key, value)
        if key == "operator":
            name = str(value).lower()
            if name not in OPERATORS:
                raise OptionError(f"pass {self.name}: property 'operator' is {value!r}; "
                                  f"use one of {', '.join(OPERATORS)}")
            return name
        return value

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
        self._size, self._views = cd.size, cd.views
        self._prog = build_compute(gl, "tonemap.comp", self.defines())
        if self.auto_exposure:
            self._lum_groups = groups_2d(cd.size, cd.views, (16, 16))   # luminance.comp's local size
            count = self._lum_groups[0] * self._lum_groups[1] * cd.views
            self._partials = gl.buffer(reserve=8 * count)
            self._exposure = gl.buffer(struct.pack("f", 0.0))
            self._lum = build_compute(gl, "luminance.comp")
            self._reduce = build_compute(gl, "exposure.comp")
            self._partial_count = count

    def execute(self, ctx, data):
        src, dst = data[self.SRC], data[self.DST]
        src.use(location=0)
        # Uniforms here, not in compile(): programs are cached and shared with other ToneMappers.
        self._prog["exposure_stops"] = float(self.exposure)
        if self.auto_exposure:
            self._reduce["partial_count"] = self._partial_count
            self._reduce["key"] = float(self.key)
            self._reduce["adaptation"] = float(self.adaptation)
            self._exposure.bind_to_storage_buffer(BINDINGS["RAYVR_PASS_SSBO_0"])
            self._partials.bind_to_storage_buffer(BINDINGS["RAYVR_PASS_SSBO_1"])
            self._lum.run(*self._lum_groups)
            ctx.gl.memory_barrier()
            self._reduce.run(1)
            ctx.gl.memory_barrier()
        dst.bind_to_image(0, read=False, write=True)
        self._prog.run(*groups_2d(data.size, data.views))
        ctx.gl.memory_barrier()

    def exposure_scale(self) -> float | None:
        """The auto exposure multiplier of the last frame (reads back; for tests and tools)."""
        if not self.auto_exposure:
            return None
        return struct.unpack("f", self._exposure.read())[0]
