"""TraceDecision: which pixels trace rays this frame (view reuse and foveation), and the fill that
reconstructs the others in each ray pass."""
from .fill import DECISION, DecisionFill
from .trace_decision import TraceDecision

__all__ = ["TraceDecision", "DecisionFill", "DECISION"]
