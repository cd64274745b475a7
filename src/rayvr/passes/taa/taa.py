"""TAA pass: temporal anti-aliasing after Falcor's TAA.

Each frame blends its colour with the history reprojected by the G-buffer's motion vectors
(optional `motion` input, pixels, this frame - last frame; without it the history is read in
place), the history clamped first to the 3x3 neighbourhood's colour box in YCoCg (mean +- sigma
standard deviations) so disoccluded and changed pixels do not ghost. On a still frame (the views
and the scene are last frame's: rayvr.passes.history) a pixel that did not move keeps an exact
running mean of its frames instead, unclamped (property `converge`), so a still view converges to
the mean of its jittered frames, the pixel-filtered image; `still_frames` counts the frames of the
current still stretch. An edit of the lighting (materials, lights) drops the history. History is
per view (texture array layers) in two internal rgba32f pins used in turn (alpha: the frames the
pixel's mean stands for). TAA asks for sub-pixel camera jitter in
its reflection; the Renderer packs `halton_jitter(frame_index)` (rayvr.xr.jitter) into the views.
"""
from __future__ import annotations

from ...errors import OptionError
from ...gpu.program_resources import program_resources
from ...rendergraph.registry import register_pass
from ...rendergraph.render_pass import Reflection, RenderPass
from ..dispatch import groups_2d
from ..history import STILL_MAX_HISTORY, LightingWatch, still_frame

from ...xr.jitter import halton, halton_jitter  # noqa: F401  (rayvr.passes.taa.halton_jitter)


@register_pass
class TAA(RenderPass):
    """Temporal anti-aliasing: `color` (+ optional `motion`) -> `dst` (see the module docstring).

    Properties: `alpha` (weight of the new frame, 0..1], `sigma` (colour box half-size in
    standard deviations), `clamp` (neighbourhood clamping on/off), `converge` (a still view's
    pixels keep an exact running mean), `format` of `dst`."""

    COLOR, MOTION, DST = "color", "motion", "dst"
    HISTORY = ("history0", "history1")
    COUNTS_NONFINITE = True   # scrubs NaN/Inf samples (glsl/nonfinite.glsl)
    PROPERTIES = {"alpha": 0.1, "sigma": 1.0, "clamp": True, "converge": True, "format": "rgba16f"}
    FORMATS = ("rgba16f", "rgba32f")
    CHOICES = {"format": FORMATS}

    def __init__(self, props: dict | None = None, **kwargs):
        super().__init__(props, **kwargs)
        self._frames = 0
        self._lighting = LightingWatch()
        self.still_frames = 0   # frames of the current still stretch the output has averaged

    def validate_property(self, key, value):
        value = super().validate_property(key, value)
        if key == "alpha" and not 0.0 < value <= 1.0:
            raise OptionError(f"pass {self.name}: property 'alpha' must be in (0, 1] (weight of the new frame), "
                              f"got {value!r}")
        if key == "sigma" and value <= 0.0:
            raise OptionError(f"pass {self.name}: property 'sigma' must be > 0, got {value!r}")
        return value

    def reset(self) -> None:
        """Forget the history: the next frame is output as is."""
        self._frames = 0
        self.still_frames = 0

    def reflect(self, cd):
        r = Reflection()
        r.add_input(self.COLOR, "this frame's colour (linear)")
        r.add_input(self.MOTION, "motion vectors in pixels (GBuffer.motion)").format("rg16f").optional()
        r.add_output(self.DST, "anti-aliased colour").format(self.format)
        for name in self.HISTORY:
            r.add_internal(name, "history (used in turn)").format("rgba32f")
        r.request_jitter()   # sub-pixel camera jitter, resolved over frames
        return r

    def compile(self, ctx, cd):
        import moderngl

        self._has_motion = self.MOTION in cd.input_formats
        self._defines = {"TAA_HAS_MOTION": int(self._has_motion), "TAA_DST_FORMAT": self.format}
        self._prog = self.compute_program(ctx.gl, "taa.comp", self._defines)
        self._res = program_resources(self._prog)
        self._groups = groups_2d(cd.size, cd.views)
        self._sampler = self.own(ctx.gl.sampler(filter=(moderngl.LINEAR, moderngl.LINEAR), repeat_x=False,
                                                repeat_y=False))
        self._lighting.forget()
        self.reset()

    def defines(self) -> dict:
        return dict(getattr(self, "_defines", {}))

    def execute(self, ctx, data):
        if self._lighting.edited(ctx):
            self.reset()
        still = bool(self.converge) and still_frame(ctx) and self._frames > 0
        self.still_frames = self.still_frames + 1 if still else 1
        read, write = (self.HISTORY[self._frames % 2], self.HISTORY[(self._frames + 1) % 2])
        values = {"taa_alpha": float(self.alpha), "taa_sigma": float(self.sigma),
                  "taa_history_valid": self._frames > 0, "taa_clamp": bool(self.clamp),
                  "taa_still": still, "taa_still_max": STILL_MAX_HISTORY}
        res = self._res
        for key, value in values.items():
            res.set(key, value)
        res.texture("taa_color", data[self.COLOR])
        res.texture("taa_history", data[read], sampler=self._sampler)
        if self._has_motion:   # cd.input_formats names only bound inputs
            res.texture("taa_motion", data[self.MOTION])
        res.image("dst", data[self.DST])
        res.image("history_out", data[write])
        self._prog.run(*self._groups)
        res.clear_sampler("taa_history")
        self._frames += 1
