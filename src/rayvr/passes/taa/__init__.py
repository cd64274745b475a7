"""TAA: temporal anti-aliasing with reprojected, clamped history."""
from .taa import TAA, halton, halton_jitter

__all__ = ["TAA", "halton", "halton_jitter"]
