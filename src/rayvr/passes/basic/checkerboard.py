"""Checkerboard: a test pattern of two colours, shifted by one cell per view layer."""
from __future__ import annotations

from ...rendergraph.registry import register_pass
from ...rendergraph.render_pass import RenderPass, Reflection
from .compute import program, rgba, run_over, storable_format


@register_pass
class Checkerboard(RenderPass):
    """Texel (x, y) of layer z is `color_a` when (x // cell + y // cell + z) is even, else `color_b`."""

    DST = "dst"
    PROPERTIES = {"cell": 8, "color_a": [1.0, 1.0, 1.0, 1.0], "color_b": [0.0, 0.0, 0.0, 1.0],
                  "format": "rgba8"}
    WHOLE = {"cell": (1, None, "pixels a side")}

    def validate_property(self, key, value):
        if key in ("color_a", "color_b"):
            return list(rgba(value, self.name, key))
        if key == "format":
            return storable_format(self.name, key, value)
        return super().validate_property(key, value)

    def reflect(self, cd):
        r = Reflection()
        r.add_output(self.DST, "the pattern").format(self.format)
        return r

    def compile(self, ctx, cd):
        self._prog = program(ctx.gl, "checkerboard.comp", self.format)

    def execute(self, ctx, data):
        self._prog["color_a"].value = tuple(self.color_a)
        self._prog["color_b"].value = tuple(self.color_b)
        self._prog["cell"].value = self.cell
        run_over(self._prog, data[self.DST])
