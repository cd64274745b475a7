"""OIDNDenoise: Intel Open Image Denoise (pyoidn, the `oidn` extra) for offline and reference renders."""
from .oidn import OIDNDenoise, require_pyoidn

__all__ = ["OIDNDenoise", "require_pyoidn"]
