"""Counting the live OpenGL objects of the current context, for leak tests and soak benchmarks.

moderngl keeps no registry of what it created, so this asks the driver: for each object type a
fresh name is generated (drivers hand out names above every live one), every smaller name is
tested with glIs*, and the probe is deleted again.
"""
from __future__ import annotations

import ctypes

_U = ctypes.c_uint
# type -> (glGen*, glIs*, glDelete*); programs are created and deleted by their own calls
_KINDS = {
    "buffers": ("glGenBuffers", "glIsBuffer", "glDeleteBuffers"),
    "textures": ("glGenTextures", "glIsTexture", "glDeleteTextures"),
    "framebuffers": ("glGenFramebuffers", "glIsFramebuffer", "glDeleteFramebuffers"),
    "renderbuffers": ("glGenRenderbuffers", "glIsRenderbuffer", "glDeleteRenderbuffers"),
    "samplers": ("glGenSamplers", "glIsSampler", "glDeleteSamplers"),
    "vertex_arrays": ("glGenVertexArrays", "glIsVertexArray", "glDeleteVertexArrays"),
    "queries": ("glGenQueries", "glIsQuery", "glDeleteQueries"),
}


def live_gl_objects() -> dict[str, int]:
    """{object type: live count} for buffers, textures, framebuffers, renderbuffers, samplers,
    vertex arrays, queries and programs of the current GL context."""
    from .rawgl import ProcLoader

    loader = ProcLoader()
    counts = {}
    for kind, (gen, is_, delete) in _KINDS.items():
        gen_fn = loader.proc(gen, None, [ctypes.c_int, ctypes.POINTER(_U)])
        is_fn = loader.proc(is_, ctypes.c_ubyte, [_U])
        del_fn = loader.proc(delete, None, [ctypes.c_int, ctypes.POINTER(_U)])
        probe = _U()
        gen_fn(1, ctypes.byref(probe))
        counts[kind] = sum(1 for name in range(1, probe.value) if is_fn(name))
        del_fn(1, ctypes.byref(probe))
    create = loader.proc("glCreateProgram", _U, [])
    is_program = loader.proc("glIsProgram", ctypes.c_ubyte, [_U])
    delete_program = loader.proc("glDeleteProgram", None, [_U])
    probe = create()
    # shaders and programs share one name space
    counts["programs"] = sum(1 for name in range(1, probe) if is_program(name))
    delete_program(probe)
    return counts
