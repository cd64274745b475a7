"""HybridComposite: each pixel's lighting chosen by its material's effect."""
from .hybrid_composite import HybridComposite

__all__ = ["HybridComposite"]
