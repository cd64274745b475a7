"""Accumulate: the progressive mean of its input over frames."""
from .accumulate import Accumulate

__all__ = ["Accumulate"]
