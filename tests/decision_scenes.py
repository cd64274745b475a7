"""What the trace decision's tests share: the Cornell box with every material SHADOWS, the raw
hybrid with the decision marked as an output, and the decision's kinds (glsl/trace_decision.glsl)."""
import rayvr as rv
from rayvr.scene import builtin

NONE, TRACE, REUSE, FILL = 0, 1, 2, 3
DECISION = "Decision.decision"


def lambert_cornell():
    scene = builtin.cornell_box()
    for name in scene.materials.names():
        scene.materials[name].effect = rv.Effect.SHADOWS
    return scene


def decision_graph(*marked, **kw):
    """rv.graphs.hybrid(preset='raw', **kw) with the decision (when there is one) and `marked` marked."""
    g = rv.graphs.hybrid(preset="raw", **kw)
    if "Decision" in g.passes:
        g.mark_output(DECISION)
    for pin in marked:
        g.mark_output(pin)
    return g
