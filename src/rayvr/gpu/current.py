"""Which OpenGL context is current on this thread, and stepping a headless one aside for a window.

With GLVND (every Linux OpenGL driver today) a thread can have one current context across EGL
and GLX: making a window's GLX context current while rayvr's headless EGL context is current
fails with BadAccess. `egl_stepped_aside()` releases the EGL context for the duration of a block
(a viewer window's life) and makes it current again afterwards, so headless rendering continues.
"""
from __future__ import annotations

import contextlib
import ctypes

from .rawgl import load_library

_P = ctypes.c_void_p
_EGL_DRAW, _EGL_READ = 0x3059, 0x305A


def _egl():
    egl = load_library(["EGL", "libEGL.so.1"])
    if egl is None:
        return None
    for name in ("eglGetCurrentDisplay", "eglGetCurrentContext", "eglGetCurrentSurface"):
        getattr(egl, name).restype = _P
    egl.eglGetCurrentSurface.argtypes = [ctypes.c_int]
    egl.eglMakeCurrent.argtypes = [_P, _P, _P, _P]
    egl.eglMakeCurrent.restype = ctypes.c_uint
    return egl


@contextlib.contextmanager
def egl_stepped_aside():
    """Inside the block no EGL context is current on this thread; the one that was (if any) is
    current again after it."""
    egl = _egl()
    saved = None
    if egl is not None and egl.eglGetCurrentContext():
        saved = (egl.eglGetCurrentDisplay(), egl.eglGetCurrentSurface(_EGL_DRAW),
                 egl.eglGetCurrentSurface(_EGL_READ), egl.eglGetCurrentContext())
        egl.eglMakeCurrent(saved[0], None, None, None)
    try:
        yield
    finally:
        if saved is not None:
            egl.eglMakeCurrent(*saved)
