"""Render passes. The hybrid pipeline's passes are here; the simple ones (Clear, Blit,
ImageLoader, ...) in `rayvr.passes.basic`, re-exported below."""
from .compaction import EffectCompaction
from .composite import HybridComposite
from .gbuffer import GBufferRaster
from .lighting import DirectLighting, RTReflections, RTShadows
from .tonemap import ToneMapper

__all__ = ["GBufferRaster", "DirectLighting", "EffectCompaction", "RTShadows", "RTReflections",
           "HybridComposite", "ToneMapper"]

# The path-tracing passes (PathTracer, Accumulate, TAA) live in their own modules here.
for _module, _names in (("path_tracer", ("PathTracer",)), ("accumulate", ("Accumulate",)), ("taa", ("TAA",))):
    try:
        _mod = __import__(f"{__name__}.{_module}", fromlist=list(_names))
    except ImportError:   # still being written
        continue
    for _name in _names:
        if hasattr(_mod, _name):
            globals()[_name] = getattr(_mod, _name)
            __all__.append(_name)

try:
    from . import basic as _basic
except ImportError:  # the basic passes land separately
    _basic = None
else:
    for _name in getattr(_basic, "__all__", []):
        globals()[_name] = getattr(_basic, _name)
        __all__.append(_name)
