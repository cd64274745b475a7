"""The few OpenGL calls moderngl does not wrap, through the EGL/GL loader with ctypes:
a layered depth texture array, a framebuffer over texture arrays (all layers, or OVR multiview),
and integer clears of single attachments.
"""
from __future__ import annotations

import ctypes

from ...errors import GpuError
from ...gpu.rawgl import ProcLoader

GL_TEXTURE_2D_ARRAY = 0x8C1A
GL_DEPTH_COMPONENT32F = 0x8CAC
GL_DEPTH_ATTACHMENT = 0x8D00
GL_COLOR_ATTACHMENT0 = 0x8CE0
GL_DRAW_FRAMEBUFFER = 0x8CA9
GL_FRAMEBUFFER_COMPLETE = 0x8CD5
GL_COLOR = 0x1800
GL_DEPTH = 0x1801

_U, _I, _F = ctypes.c_uint, ctypes.c_int, ctypes.c_float
_SIGNATURES = {
    "glCreateTextures": (None, [_U, _I, ctypes.POINTER(_U)]),
    "glTextureStorage3D": (None, [_U, _I, _U, _I, _I, _I]),
    "glDeleteTextures": (None, [_I, ctypes.POINTER(_U)]),
    "glCreateFramebuffers": (None, [_I, ctypes.POINTER(_U)]),
    "glDeleteFramebuffers": (None, [_I, ctypes.POINTER(_U)]),
    "glNamedFramebufferTexture": (None, [_U, _U, _U, _I]),
    "glNamedFramebufferDrawBuffers": (None, [_U, _I, ctypes.POINTER(_U)]),
    "glCheckNamedFramebufferStatus": (_U, [_U, _U]),
    "glClearNamedFramebufferfv": (None, [_U, _U, _I, ctypes.POINTER(_F)]),
    "glClearNamedFramebufferuiv": (None, [_U, _U, _I, ctypes.POINTER(_U)]),
    "glBindFramebuffer": (None, [_U, _U]),
    "glFramebufferTextureMultiviewOVR": (None, [_U, _U, _U, _I, _I, _I]),
    "glGetIntegerv": (None, [_U, ctypes.POINTER(_I)]),
}
GL_MAX_VIEWS_OVR = 0x9631


class RawGL:
    """Function pointers of the current context's GL, by name, with the signatures above."""

    def __init__(self):
        self._loader = ProcLoader()

    def __getattr__(self, name):
        if name.startswith("_"):
            raise AttributeError(name)
        return self._loader.proc(name, *_SIGNATURES[name])


_raw: RawGL | None = None


def raw() -> RawGL:
    global _raw
    if _raw is None:
        _raw = RawGL()
    return _raw


def max_multiview_views() -> int:
    """GL_MAX_VIEWS_OVR of the current context (0 when the query fails)."""
    value = _I(0)
    try:
        raw().glGetIntegerv(GL_MAX_VIEWS_OVR, ctypes.byref(value))
    except GpuError:
        return 0
    return int(value.value)


class LayeredTarget:
    """A framebuffer whose colour attachments are whole texture arrays plus a depth texture array.

    `multiview` attaches them with glFramebufferTextureMultiviewOVR (all `layers` views in one
    draw through gl_ViewID_OVR); otherwise layered (the vertex shader picks gl_Layer).
    """

    def __init__(self, gl, colors, size, layers: int, multiview: bool = False):
        g = raw()
        self.gl = gl
        self.size = size
        self.layers = layers
        self.multiview = multiview
        tex = _U()
        g.glCreateTextures(GL_TEXTURE_2D_ARRAY, 1, ctypes.byref(tex))
        g.glTextureStorage3D(tex.value, 1, GL_DEPTH_COMPONENT32F, size[0], size[1], layers)
        self.depth = tex.value
        fbo = _U()
        g.glCreateFramebuffers(1, ctypes.byref(fbo))
        self.fbo = fbo.value
        if multiview:
            g.glBindFramebuffer(GL_DRAW_FRAMEBUFFER, self.fbo)
            for i, c in enumerate(colors):
                g.glFramebufferTextureMultiviewOVR(GL_DRAW_FRAMEBUFFER, GL_COLOR_ATTACHMENT0 + i, c.glo, 0, 0, layers)
            g.glFramebufferTextureMultiviewOVR(GL_DRAW_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, self.depth, 0, 0, layers)
            g.glBindFramebuffer(GL_DRAW_FRAMEBUFFER, 0)
        else:
            for i, c in enumerate(colors):
                g.glNamedFramebufferTexture(self.fbo, GL_COLOR_ATTACHMENT0 + i, c.glo, 0)
            g.glNamedFramebufferTexture(self.fbo, GL_DEPTH_ATTACHMENT, self.depth, 0)
        bufs = (_U * len(colors))(*[GL_COLOR_ATTACHMENT0 + i for i in range(len(colors))])
        g.glNamedFramebufferDrawBuffers(self.fbo, len(colors), bufs)
        status = g.glCheckNamedFramebufferStatus(self.fbo, GL_DRAW_FRAMEBUFFER)
        if status != GL_FRAMEBUFFER_COMPLETE:
            raise GpuError(f"G-buffer framebuffer incomplete (status 0x{status:x}, "
                           f"{'multiview' if multiview else 'layered'}); try multiview='off'")
        try:
            self.framebuffer = gl.detect_framebuffer(self.fbo)
        except Exception as exc:  # moderngl.Error with the driver's words
            raise GpuError(f"G-buffer framebuffer: moderngl cannot wrap it ({exc})") from exc
        self.framebuffer.viewport = (0, 0, size[0], size[1])
        self._clear_values = []

    def set_clear_values(self, values) -> None:
        """Per colour attachment: a float 4-tuple, or ('uint', v) for integer attachments."""
        self._clear_values = []
        for i, v in enumerate(values):
            if isinstance(v, tuple) and v and v[0] == "uint":
                self._clear_values.append((True, i, (_U * 4)(v[1], v[1], v[1], v[1])))
            else:
                self._clear_values.append((False, i, (_F * 4)(*v)))
        self._depth_one = (_F * 1)(1.0)

    def use_and_clear(self) -> None:
        self.framebuffer.use()
        g = raw()
        for is_uint, i, val in self._clear_values:
            if is_uint:
                g.glClearNamedFramebufferuiv(self.fbo, GL_COLOR, i, val)
            else:
                g.glClearNamedFramebufferfv(self.fbo, GL_COLOR, i, val)
        g.glClearNamedFramebufferfv(self.fbo, GL_DEPTH, 0, self._depth_one)

    def release(self) -> None:
        g = raw()
        if self.fbo:
            g.glDeleteFramebuffers(1, ctypes.byref(_U(self.fbo)))
            g.glDeleteTextures(1, ctypes.byref(_U(self.depth)))
            self.fbo = self.depth = 0
