"""Texture formats by name: components, moderngl dtype, bytes per texel, GLSL image format."""
from __future__ import annotations

import dataclasses

import numpy as np

from ..errors import OptionError, did_you_mean


@dataclasses.dataclass(frozen=True)
class Format:
    """A texture format a pin may declare, by its GLSL name."""

    name: str
    components: int
    dtype: str          # moderngl dtype
    bytes_per_texel: int
    glsl: str           # image format qualifier for image load/store ('' when not storable)


FORMATS = {f.name: f for f in [
    Format("rgba32f", 4, "f4", 16, "rgba32f"),
    Format("rgba16f", 4, "f2", 8, "rgba16f"),
    Format("rg32f", 2, "f4", 8, "rg32f"),
    Format("rg16f", 2, "f2", 4, "rg16f"),
    Format("r32f", 1, "f4", 4, "r32f"),
    Format("r16f", 1, "f2", 2, "r16f"),
    Format("rgba8", 4, "f1", 4, "rgba8"),
    Format("r32ui", 1, "u4", 4, "r32ui"),
    Format("rg32ui", 2, "u4", 8, "rg32ui"),
    Format("rgba32ui", 4, "u4", 16, "rgba32ui"),
    Format("r8", 1, "f1", 1, "r8"),
    Format("depth32f", 1, "f4", 4, ""),
]}

# moderngl dtype -> numpy dtype, for reading textures back
NUMPY_DTYPES = {"f1": np.uint8, "f2": np.float16, "f4": np.float32, "u4": np.uint32, "i4": np.int32}


def get_format(name: str, where: str = "format") -> Format:
    """The Format called `name`; OptionError naming `where` and the known formats otherwise."""
    try:
        return FORMATS[name]
    except KeyError:
        raise OptionError(f"{where}: unknown format {name!r}{did_you_mean(name, FORMATS)}; "
                          f"known: {', '.join(FORMATS)}") from None
