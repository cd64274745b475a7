"""ReSTIRDI: ray-traced direct light by spatiotemporal reservoir resampling, in RTShadows' place."""
from .restir_di import ReSTIRDI

__all__ = ["ReSTIRDI"]
