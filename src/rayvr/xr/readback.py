"""Reading rendered texture arrays back as 8-bit images (the display side, never the render loop)."""
from __future__ import annotations

import numpy as np

from ..images import srgb_encode
from ..rendergraph.formats import NUMPY_DTYPES


def to_uint8(pixels: np.ndarray, encode_srgb: bool = False) -> np.ndarray:
    """8-bit pixels from uint8 or float data (floats clipped to [0, 1]; optionally sRGB-encoded)."""
    if pixels.dtype == np.uint8:
        return pixels
    x = pixels.astype(np.float32)
    x = srgb_encode(x) if encode_srgb else np.clip(x, 0.0, 1.0)
    return (x * 255.0 + 0.5).astype(np.uint8)


def read_raw(texture) -> np.ndarray:
    """A moderngl Texture or TextureArray as (layers, height, width, components), GL row order."""
    if texture.dtype not in ("f1", "f2", "f4"):
        from ..errors import XrError

        raise XrError(f"cannot read back a texture of dtype '{texture.dtype}'; use f1, f2 or f4")
    dtype = NUMPY_DTYPES[texture.dtype]
    layers = getattr(texture, "layers", 1)
    data = np.frombuffer(texture.read(), dtype=dtype)
    return data.reshape(layers, texture.height, texture.width, texture.components)


def read_layers(texture, encode_srgb: bool = False) -> np.ndarray:
    """uint8 (layers, height, width, components), top row first (image order, not GL's)."""
    return to_uint8(read_raw(texture)[:, ::-1], encode_srgb)


def side_by_side(layers: np.ndarray) -> np.ndarray:
    """Views placed left to right in one image (view 0 on the left)."""
    return np.concatenate(list(layers), axis=1)
