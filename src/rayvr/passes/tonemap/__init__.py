"""ToneMapper: HDR radiance to the display's sRGB rgba8."""
from .tonemap import OPERATORS, ToneMapper

__all__ = ["ToneMapper", "OPERATORS"]
