"""Render passes: the hybrid pipeline (G-buffer, lighting, ray-traced effects, composite, tone
mapping), path tracing with accumulation and TAA, and the simple ones in `rayvr.passes.basic`."""
from .accumulate import Accumulate
from .basic import *  # noqa: F403  (Clear, Checkerboard, Blit, ImageLoader)
from .basic import __all__ as _basic_all
from .compaction import EffectCompaction
from .composite import HybridComposite
from .gbuffer import GBufferRaster
from .gbuffer_auto import GBufferAuto
from .gbuffer_rt import GBufferRT
from .lighting import DirectLighting, RTReflections, RTShadows
from .path_tracer import PathTracer
from .taa import TAA
from .tonemap import ToneMapper

__all__ = ["GBufferRaster", "GBufferRT", "GBufferAuto", "DirectLighting", "EffectCompaction", "RTShadows", "RTReflections",
           "HybridComposite", "ToneMapper", "PathTracer", "Accumulate", "TAA", *_basic_all]
