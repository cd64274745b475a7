"""OpenGL entry points that moderngl does not wrap, looked up with ctypes through the window-system
API that owns the current context: EGL (rayvr's headless default), else GLX (a desktop window)."""
from __future__ import annotations

import ctypes
import ctypes.util

from ..errors import GpuError

_P = ctypes.c_void_p


def load_library(names):
    """The first of `names` (short names or sonames) that loads, or None."""
    for n in names:
        try:
            return ctypes.CDLL(ctypes.util.find_library(n) or n)
        except OSError:
            continue
    return None


class ProcLoader:
    """Finds the API of the current GL context (`kind`: 'egl', 'glx' or None) and its entry points."""

    def __init__(self):
        self.kind = None
        self._egl = load_library(["EGL", "libEGL.so.1"])
        self._glx = None
        if self._egl is not None:
            self._egl.eglGetCurrentContext.restype = _P
            self._egl.eglGetCurrentDisplay.restype = _P
            self._egl.eglGetProcAddress.restype = _P
            self._egl.eglGetProcAddress.argtypes = [ctypes.c_char_p]
            if self._egl.eglGetCurrentContext():
                self.kind = "egl"
        if self.kind is None:
            self._glx = load_library(["GL", "libGL.so.1"])
            if self._glx is not None:
                self._glx.glXGetCurrentContext.restype = _P
                self._glx.glXGetProcAddressARB.restype = _P
                self._glx.glXGetProcAddressARB.argtypes = [ctypes.c_char_p]
                if self._glx.glXGetCurrentContext():
                    self.kind = "glx"
        self._procs: dict[str, object] = {}

    def proc(self, name: str, restype, argtypes):
        """The entry point `name` as a ctypes function (cached); GpuError when the driver lacks it."""
        fn = self._procs.get(name)
        if fn is None:
            if self.kind == "glx":
                addr = self._glx.glXGetProcAddressARB(name.encode())
            elif self._egl is not None:
                addr = self._egl.eglGetProcAddress(name.encode())
            else:
                raise GpuError(f"cannot look up OpenGL entry point {name}: no libEGL; install libegl1")
            if not addr:
                raise GpuError(f"OpenGL entry point {name} is missing from this driver")
            fn = ctypes.CFUNCTYPE(restype, *argtypes)(addr)
            self._procs[name] = fn
        return fn
