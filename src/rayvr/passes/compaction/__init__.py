"""EffectCompaction and the per-effect pixel lists it builds for the ray passes."""
from .effect_compaction import EffectCompaction
from .pixel_list import DISPATCH_OFFSET, HEADER_BYTES, pixel_list_bytes, read_pixel_list

__all__ = ["EffectCompaction", "DISPATCH_OFFSET", "HEADER_BYTES", "pixel_list_bytes", "read_pixel_list"]
