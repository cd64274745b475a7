"""What a ray pass adds to read a trace decision: its optional `decision` input, and a last
dispatch (fill.comp) that gives every pixel it did not trace the light its source traced.

A pass keeps one `DecisionFill` naming its output images and the lobe each holds; it declares the
input in reflect() (`add_input`), compiles the fill when the decision is bound (`compile`), binds
the decision to its own programs (`bind`: their `ray_pass_pixel` or kernels skip reconstructed
pixels) and runs the fill after its own dispatches (`run`).
"""
from __future__ import annotations

from pathlib import Path

from ...gpu.program_resources import program_resources
from ...gpu.shaders import compute_program
from ...rendergraph.render_pass import Access
from ..dispatch import groups_2d
from ..effects import effect_defines, scene_defines
from ..gbuffer import channels

DECISION = "decision"   # the input pin, the sampler `trace_decision` (glsl/trace_decision.glsl)
# RenderContext.dictionary's key (TraceDecision's): False when the decision leaves no pixel to the
# fills, as when SVGF spreads every pixel whose light is another view's and nothing is foveated
DECISION_FILLS = "decision_fills"
LOBES = {"whole": 0, "diffuse": 1, "specular": 2}
FORMATS = ("rgba16f", "rgba32f")
SHADER = Path(__file__).resolve().parent / "fill.comp"


class DecisionFill:
    """The fill of a pass's `images`: (output pin, format, lobe) each, lobe 'whole' (emission and
    both lobes), 'diffuse' or 'specular'; `min_effect`: the lowest effect of the pixels the pass
    lights; `color_from_lobes`: the first image is the emission plus the other two."""

    def __init__(self, images, min_effect: int = 0, color_from_lobes: bool = False):
        self.images = list(images)
        self.min_effect = int(min_effect)
        self.color_from_lobes = bool(color_from_lobes)
        self.bound = False
        self._res = None

    @staticmethod
    def add_input(r) -> None:
        """Declare the optional `decision` input (TraceDecision.decision, rg32ui)."""
        r.add_input(DECISION, "which pixels trace this frame and the others' sources (TraceDecision)"
                    ).format("rg32ui").optional()

    @staticmethod
    def connected(cd) -> bool:
        return DECISION in cd.input_formats

    def defines(self) -> dict:
        """The define of the pass's own programs: TRACE_DECISION when the decision is bound."""
        return {"TRACE_DECISION": 1} if self.bound else {}

    def compile(self, ctx, cd, images=None) -> None:
        """Build the fill when the decision is bound (`images`: the ones this compile writes,
        default all)."""
        self.bound = self.connected(cd)
        self._res = None
        self.left_out = self.bound and not ctx.dictionary.get(DECISION_FILLS, True)
        if not self.bound or self.left_out:
            return
        self._images = list(images if images is not None else self.images)
        defines = {**scene_defines(ctx), **effect_defines(), "FILL_IMAGES": len(self._images),
                   "FILL_MIN_EFFECT": self.min_effect, "FILL_COLOR_FROM_LOBES": int(self.color_from_lobes)}
        for i, (_, fmt, lobe) in enumerate(self._images):
            defines[f"FILL{i}_FORMAT"] = fmt
            defines[f"FILL{i}_LOBE"] = LOBES[lobe]
        self._res = program_resources(compute_program(ctx.gl, SHADER, defines))
        self._groups = groups_2d(cd.size, cd.views)

    def report(self) -> dict:
        """For the pass's compile report: the fill when it is left out."""
        if getattr(self, "left_out", False):
            return {"decision_fill": "left out: the decision leaves no pixel to it (SVGF spreads the reused ones)"}
        return {}

    def bind(self, res, data) -> None:
        """Bind the decision to program `res` (one of the pass's own)."""
        if self.bound:
            res.texture("trace_decision", data[DECISION])

    def run(self, ctx, data) -> None:
        """After the pass's dispatches: the pixels it did not trace, from their sources."""
        if self._res is None:
            return
        ctx.barrier(Access.IMAGE)
        res = self._res
        channels.bind_inputs(res, data)
        res.texture("trace_decision", data[DECISION])
        for i, (pin, _, _) in enumerate(self._images):
            res.image(f"fill{i}", data[pin], read=True, write=True)
        res.prog.run(*self._groups)
