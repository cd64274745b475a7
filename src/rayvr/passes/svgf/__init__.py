"""SVGF: spatiotemporal variance-guided filtering of demodulated diffuse and specular light."""
from .svgf import SVGF

__all__ = ["SVGF"]
