"""Textures start as zeros: GL leaves a new texture's memory undefined (NVIDIA hands out whatever
was there, NaN bit patterns included; Mesa zero-fills), so a texel no pass has written yet, such
as a history the first frame has not reached, would read as garbage."""
from __future__ import annotations

import ctypes

_FORMATS = {False: (0x1903, 0x8227, 0x1907, 0x1908),    # GL_RED, GL_RG, GL_RGB, GL_RGBA
            True: (0x8D94, 0x8228, 0x8D98, 0x8D99)}     # the *_INTEGER forms
_TYPES = {"f1": 0x1401, "f2": 0x1406, "f4": 0x1406,     # GL_UNSIGNED_BYTE, GL_FLOAT
          "u1": 0x1401, "u2": 0x1403, "u4": 0x1405, "i1": 0x1400, "i2": 0x1402, "i4": 0x1404}
_clear = None


def zero_texture(tex) -> None:
    """Clear every level-0 texel of a moderngl texture to 0 on the GPU (glClearTexImage, GL 4.4)."""
    from .rawgl import ProcLoader

    global _clear
    if _clear is None:
        _clear = ProcLoader().proc("glClearTexImage", None,
                                   [ctypes.c_uint, ctypes.c_int, ctypes.c_uint, ctypes.c_uint, ctypes.c_void_p])
    integer = tex.dtype[0] in "ui"
    _clear(tex.glo, 0, _FORMATS[integer][tex.components - 1], _TYPES[tex.dtype], None)
