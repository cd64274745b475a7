"""TAA pass: temporal anti-aliasing after Falcor's TAA.

Each frame blends its colour with the history reprojected by the G-buffer's motion vectors
(optional `motion` input, pixels, this frame - last frame; without it the history is read in
place), the history clamped first to the 3x3 neighbourhood's colour box in YCoCg (mean +- sigma
standard deviations) so disoccluded and changed pixels do not ghost. History is per view (texture
array layers) in two internal rgba32f pins used in turn. Sub-pixel camera jitter comes from
`halton_jitter(frame_index)`, packed into the views SSBO by `ViewSet.pack(jitter=...)`.
"""
from __future__ import annotations

from ..errors import OptionError
from ..rendergraph.render_pass import Reflection, RenderPass
from ._common import build_compute, groups_2d, register

JITTER_SEQUENCE_LENGTH = 16


def halton(index: int, base: int) -> float:
    """The radical inverse of `index` in `base`: the Halton sequence's value in [0, 1)."""
    result, f = 0.0, 1.0
    while index > 0:
        f /= base
        result += f * (index % base)
        index //= base
    return result


def halton_jitter(frame_index: int, length: int = JITTER_SEQUENCE_LENGTH) -> tuple[float, float]:
    """Sub-pixel jitter in pixels, in [-0.5, 0.5)^2, from the Halton (2, 3) sequence (cycle of
    `length` frames; the sequence starts at index 1 so frame 0 is not the pixel corner)."""
    i = frame_index % max(int(length), 1) + 1
    return halton(i, 2) - 0.5, halton(i, 3) - 0.5


@register
class TAA(RenderPass):
    """Temporal anti-aliasing: `color` (+ optional `motion`) -> `dst` (see the module docstring).

    Properties: `alpha` (weight of the new frame, 0..1], `sigma` (colour box half-size in
    standard deviations), `clamp` (neighbourhood clamping on/off), `format` of `dst`."""

    COLOR, MOTION, DST = "color", "motion", "dst"
    HISTORY = ("history0", "history1")
    PROPERTIES = {"alpha": 0.1, "sigma": 1.0, "clamp": True, "format": "rgba16f"}
    FORMATS = ("rgba16f", "rgba32f")

    def __init__(self, props: dict | None = None, **kwargs):
        super().__init__(props, **kwargs)
        self._frames = 0

    def validate_property(self, key, value):
        value = super().validate_property(key, value)
        if key == "alpha" and not 0.0 < value <= 1.0:
            raise OptionError(f"pass {self.name}: property 'alpha' must be in (0, 1] (weight of the new frame), "
                              f"got {value!r}")
        if key == "sigma" and value <= 0.0:
            raise OptionError(f"pass {self.name}: property 'sigma' must be > 0, got {value!r}")
        if key == "format" and value not in self.FORMATS:
            raise OptionError(f"pass {self.name}: property 'format' is {value!r}; use one of {', '.join(self.FORMATS)}")
        return value

    def reset(self) -> None:
        """Forget the history: the next frame is output as is."""
        self._frames = 0

    def reflect(self, cd):
        r = Reflection()
        r.add_input(self.COLOR, "this frame's colour (linear)")
        r.add_input(self.MOTION, "motion vectors in pixels (GBuffer.motion)").format("rg16f").optional()
        r.add_output(self.DST, "anti-aliased colour").format(self.format)
        for name in self.HISTORY:
            r.add_internal(name, "history (used in turn)").format("rgba32f")
        return r

    def compile(self, ctx, cd):
        import moderngl

        self._has_motion = self.MOTION in cd.input_formats
        self._defines = {"TAA_HAS_MOTION": int(self._has_motion), "TAA_DST_FORMAT": self.format}
        self._prog = build_compute(ctx.gl, "pt/taa.comp", self._defines)
        self._sampler = ctx.gl.sampler(filter=(moderngl.LINEAR, moderngl.LINEAR), repeat_x=False, repeat_y=False)
        self.reset()

    def defines(self) -> dict:
        return dict(getattr(self, "_defines", {}))

    def execute(self, ctx, data):
        read, write = (self.HISTORY[self._frames % 2], self.HISTORY[(self._frames + 1) % 2])
        values = {"taa_alpha": float(self.alpha), "taa_sigma": float(self.sigma),
                  "taa_history_valid": self._frames > 0, "taa_clamp": bool(self.clamp)}
        for key, value in values.items():
            if key in self._prog:
                self._prog[key].value = value
        data[self.COLOR].use(location=0)
        data[read].use(location=1)
        self._sampler.use(location=1)
        if self._has_motion:   # cd.input_formats names only bound inputs
            data[self.MOTION].use(location=2)
        data[self.DST].bind_to_image(0, read=False, write=True)
        data[write].bind_to_image(1, read=False, write=True)
        self._prog.run(*groups_2d(data.size, data.views))
        ctx.gl.memory_barrier()
        self._sampler.clear(location=1)
        self._frames += 1
