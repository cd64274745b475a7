"""The G-buffer: its channel table and the passes that write it, rasterised (GBufferRaster),
ray-traced (GBufferRT) or either as the driver suits (GBufferAuto)."""
from . import channels
from .auto import GBufferAuto
from .raster import GBufferRaster
from .rt import GBufferRT

__all__ = ["GBufferAuto", "GBufferRaster", "GBufferRT", "channels"]
