"""Blit: copy a texture array into another, rescaled and/or converted to another format."""
from __future__ import annotations

import moderngl

from ...errors import OptionError
from ...rendergraph.formats import get_format
from ...rendergraph.registry import register_pass
from ...rendergraph.render_pass import RenderPass, Reflection
from .compute import program, run_over, storable_format

FILTERS = {"linear": (moderngl.LINEAR, moderngl.LINEAR), "nearest": (moderngl.NEAREST, moderngl.NEAREST)}


@register_pass
class Blit(RenderPass):
    """`dst` = `src` resampled to `scale` x the graph's output size, in `format` ('' = src's).

    Layer z of dst reads layer min(z, src layers - 1), so a one-layer source fills every view.
    """

    SRC, DST = "src", "dst"
    PROPERTIES = {"format": "", "scale": 1.0, "filter": "linear"}
    CHOICES = {"filter": tuple(FILTERS)}

    def validate_property(self, key, value):
        if key == "format" and value != "":
            return storable_format(self.name, key, value)
        value = super().validate_property(key, value)
        if key == "scale" and value <= 0:
            raise OptionError(f"pass {self.name}: property 'scale' must be > 0, got {value!r}")
        return value

    def out_format(self, cd) -> str:
        return self.format or cd.input_formats.get(self.SRC) or "rgba16f"

    def reflect(self, cd):
        src_fmt = cd.input_formats.get(self.SRC)
        if src_fmt and get_format(src_fmt).dtype == "u4":
            raise OptionError(f"pass {self.name}: input 'src' is {src_fmt}, an integer format Blit cannot "
                              f"filter; connect a float or normalised format")
        r = Reflection()
        r.add_input(self.SRC, "image to copy")
        out = r.add_output(self.DST, "the copy").format(self.out_format(cd))
        if self.scale != 1.0:
            out.scaled(self.scale)
        return r

    def compile(self, ctx, cd):
        self._prog = program(ctx.gl, "blit.comp", self.out_format(cd))
        self._sampler = self.own(ctx.gl.sampler(filter=FILTERS[self.filter], repeat_x=False, repeat_y=False))

    def execute(self, ctx, data):
        run_over(self._prog, data[self.DST], data[self.SRC], self._sampler)
