"""Basic passes: fill, test pattern, copy/convert, image file. Each registers by class name."""
from .blit import Blit
from .checkerboard import Checkerboard
from .clear import Clear
from .image_loader import ImageLoader

__all__ = ["Blit", "Checkerboard", "Clear", "ImageLoader"]
