"""Clear: fill an output with one colour, or one colour per view layer."""
from __future__ import annotations

import numpy as np

from ...errors import OptionError
from ...gpu.bindings import BINDINGS
from ...rendergraph.registry import register_pass
from ...rendergraph.render_pass import RenderPass, Reflection
from .compute import program, rgba, run_over, storable_format

_ZEROS = bytes(16 * BINDINGS["RAYVR_MAX_VIEWS"])   # clear.comp's `colors`, all 0 (zero_image)


@register_pass
class Clear(RenderPass):
    """Fill `dst` with `color`; with `view_colors`, layer i gets view_colors[min(i, n - 1)]."""

    DST = "dst"
    PROPERTIES = {"color": [0.0, 0.0, 0.0, 1.0], "view_colors": [], "format": "rgba16f"}

    def validate_property(self, key, value):
        if key == "color":
            return list(rgba(value, self.name, key))
        if key == "view_colors":
            if not isinstance(value, (list, tuple)) or len(value) > BINDINGS["RAYVR_MAX_VIEWS"]:
                raise OptionError(f"pass {self.name}: property 'view_colors' must be a list of at most "
                                  f"{BINDINGS['RAYVR_MAX_VIEWS']} colours, got {value!r}")
            return [list(rgba(c, self.name, f"view_colors[{i}]")) for i, c in enumerate(value)]
        if key == "format":
            return storable_format(self.name, key, value)
        return super().validate_property(key, value)

    def on_properties_changed(self) -> None:
        colors = self.view_colors or [self.color]
        packed = np.zeros((BINDINGS["RAYVR_MAX_VIEWS"], 4), np.float32)
        packed[:len(colors)] = colors
        self._colors, self._count = packed.tobytes(), len(colors)

    def reflect(self, cd):
        r = Reflection()
        r.add_output(self.DST, "the cleared image").format(self.format)
        return r

    def compile(self, ctx, cd):
        self._prog = program(ctx.gl, "clear.comp", self.format)

    def execute(self, ctx, data):
        clear_over(self._prog, data[self.DST], self._colors, self._count)


def clear_over(prog, dst, colors: bytes, count: int) -> None:
    """Run clear.comp `prog` over texture array `dst` with `count` of the packed `colors`."""
    # The program is shared by every clear of its format, so its uniforms are set each time.
    prog["colors"].write(colors)
    prog["color_count"].value = count
    run_over(prog, dst)


def zero_program(gl, fmt: str):
    """The program zero_image runs over images of format `fmt` (build it in compile())."""
    return program(gl, "clear.comp", fmt)


def zero_image(prog, dst) -> None:
    """Write 0 in every texel of texture array `dst` with zero_program's `prog`: a compute dispatch
    that costs a write of the image, where glClearTexImage over the many layers of a half-float
    image took milliseconds on one driver (benchmarks/RESULTS.md, 2026-12-07 ninth)."""
    clear_over(prog, dst, _ZEROS, 1)
