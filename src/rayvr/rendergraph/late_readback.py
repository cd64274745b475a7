"""Small GPU results read back a frame late: a copy into a staging buffer behind a fence, taken
once the fence has signalled (polled, never waited on), so the frame loop never stalls on it.

The graph's per-pass non-finite counters (`nonfinite.py`) and per-view ray counters
(`ray_counters.py`) hand their counts to the profile this way: a frame or two old, as timer
queries are.
"""
from __future__ import annotations

import ctypes

GL_SYNC_GPU_COMMANDS_COMPLETE = 0x9117
GL_SYNC_FLUSH_COMMANDS_BIT = 0x1
SIGNALLED = (0x911A, 0x911C)   # GL_ALREADY_SIGNALED, GL_CONDITION_SATISFIED

_gl: dict = {}
_SIGNATURES = {
    "glBindBufferRange": (None, [ctypes.c_uint, ctypes.c_uint, ctypes.c_uint, ctypes.c_ssize_t, ctypes.c_ssize_t]),
    "glFenceSync": (ctypes.c_void_p, [ctypes.c_uint, ctypes.c_uint]),
    "glClientWaitSync": (ctypes.c_uint, [ctypes.c_void_p, ctypes.c_uint, ctypes.c_uint64]),
    "glDeleteSync": (None, [ctypes.c_void_p]),
    "glClearTexImage": (None, [ctypes.c_uint, ctypes.c_int, ctypes.c_uint, ctypes.c_uint, ctypes.c_void_p]),
}


def gl_proc(name: str):
    """An OpenGL entry point moderngl does not wrap (one of _SIGNATURES), looked up once."""
    fn = _gl.get(name)
    if fn is None:
        from ..gpu.rawgl import ProcLoader

        fn = _gl[name] = ProcLoader().proc(name, *_SIGNATURES[name])
    return fn


class LateReadback:
    """A staging buffer of `nbytes` and the fence of the copy into it that is in flight."""

    def __init__(self, gl, nbytes: int):
        self.staging = gl.buffer(reserve=max(4, int(nbytes)))
        self._fence = None

    @property
    def pending(self) -> bool:
        """A copy is in flight (its bytes not taken yet)."""
        return self._fence is not None

    def start(self, copy) -> None:
        """`copy(staging)` (GL commands that fill the staging buffer), then a fence behind them."""
        copy(self.staging)
        self._fence = gl_proc("glFenceSync")(GL_SYNC_GPU_COMMANDS_COMPLETE, 0)

    def take(self) -> bytes | None:
        """The staging bytes once the copy's fence has signalled (no wait); None while it has not,
        or when no copy is in flight."""
        if self._fence is None:
            return None
        if gl_proc("glClientWaitSync")(self._fence, GL_SYNC_FLUSH_COMMANDS_BIT, 0) not in SIGNALLED:
            return None
        self.drop()
        return self.staging.read()   # the copy is done: no stall

    def drop(self) -> None:
        """Forget the copy in flight (what it holds is stale)."""
        if self._fence is not None:
            gl_proc("glDeleteSync")(self._fence)
            self._fence = None

    def release(self) -> None:
        self.drop()
        self.staging.release()
