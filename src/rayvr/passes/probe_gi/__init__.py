"""ProbeGI: ray-traced irradiance probes shared by every view (DDGI), and how shading passes read them."""
from . import inputs, layout
from .probe_gi import ProbeGI

__all__ = ["ProbeGI", "inputs", "layout"]
