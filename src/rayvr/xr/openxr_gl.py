"""OpenGL side of the OpenXR sink: the current context's EGL or GLX handles for the graphics
binding, swapchain format choice, and the GPU copy of rendered views into swapchain images.

GL entry points moderngl does not wrap (glCopyImageSubData) are looked up with ctypes through
eglGetProcAddress or glXGetProcAddressARB, whichever API owns the current context.
"""
from __future__ import annotations

import ctypes
import ctypes.util
from pathlib import Path

from ..errors import GpuError, XrError
from ..gpu.rawgl import ProcLoader
from ..gpu.shaders import compute_program
from .quilt import RGBA_IMAGE_FORMATS

GL_TEXTURE_2D = 0x0DE1
GL_TEXTURE_2D_ARRAY = 0x8C1A
GL_SRGB8_ALPHA8 = 0x8C43
GL_RGBA8 = 0x8058
GL_RGBA16F = 0x881A
GL_RGBA32F = 0x8814
GL_DEPTH_COMPONENT16 = 0x81A5
GL_DEPTH_COMPONENT24 = 0x81A6
GL_DEPTH_COMPONENT32F = 0x8CAC
GL_DEPTH24_STENCIL8 = 0x88F0

FORMAT_NAMES = {GL_SRGB8_ALPHA8: "GL_SRGB8_ALPHA8", GL_RGBA8: "GL_RGBA8", GL_RGBA16F: "GL_RGBA16F",
                GL_RGBA32F: "GL_RGBA32F", GL_DEPTH_COMPONENT16: "GL_DEPTH_COMPONENT16",
                GL_DEPTH_COMPONENT24: "GL_DEPTH_COMPONENT24", GL_DEPTH_COMPONENT32F: "GL_DEPTH_COMPONENT32F",
                GL_DEPTH24_STENCIL8: "GL_DEPTH24_STENCIL8"}
# Colour formats in order of preference: sRGB first, so the compositor linearises what we encode
# (the OpenXR spec: an sRGB swapchain's values are sRGB-encoded, any other is linear).
COLOR_PREFERENCE = (GL_SRGB8_ALPHA8, GL_RGBA16F, GL_RGBA8)
DEPTH_PREFERENCE = (GL_DEPTH_COMPONENT32F, GL_DEPTH_COMPONENT24, GL_DEPTH24_STENCIL8, GL_DEPTH_COMPONENT16)
_DEPTH_OF_DTYPE = {"f4": GL_DEPTH_COMPONENT32F, "f3": GL_DEPTH_COMPONENT24, "f2": GL_DEPTH_COMPONENT16}

EGL_CONFIG_ID = 0x3028
EGL_NONE = 0x3038
GLX_FBCONFIG_ID = 0x8013
GLX_SCREEN = 0x800C
GLX_VISUAL_ID = 0x800B
GLX_NONE = 0x8000
_P, _I, _U = ctypes.c_void_p, ctypes.c_int, ctypes.c_uint


def choose_format(runtime_formats, preference) -> int:
    """The first of `preference` the runtime offers (its list is in its own order of preference)."""
    offered = [int(f) for f in runtime_formats]
    for f in preference:
        if f in offered:
            return f
    names = ", ".join(FORMAT_NAMES.get(f, hex(f)) for f in offered)
    wanted = ", ".join(FORMAT_NAMES[f] for f in preference)
    raise XrError(f"OpenXR runtime offers swapchain formats [{names}], none of {wanted}; "
                  f"rayvr cannot present to it")


class GLPlatform(ProcLoader):
    """The window-system API owning the current GL context: 'egl' or 'glx', its handles and GL procs."""

    def __init__(self):
        super().__init__()
        if self.kind is None:
            raise XrError("OpenXRSink: no current EGL or GLX OpenGL context; open the sink with rayvr's GPU "
                          "context (rayvr.gpu.get_context()) on this thread")

    def proc(self, name: str, restype, argtypes):
        try:
            return super().proc(name, restype, argtypes)
        except GpuError:
            raise XrError(f"OpenGL entry point {name} is missing; OpenXRSink needs OpenGL 4.3+") from None

    def egl_binding(self, xr):
        """XrGraphicsBindingEGLMNDX for the current EGL context (fields cast to the struct's types)."""
        egl = self._egl
        display, context = egl.eglGetCurrentDisplay(), egl.eglGetCurrentContext()
        egl.eglQueryContext.argtypes = [_P, _P, _I, ctypes.POINTER(_I)]
        config_id = _I(0)
        egl.eglQueryContext(display, context, EGL_CONFIG_ID, ctypes.byref(config_id))
        attribs = (_I * 3)(EGL_CONFIG_ID, config_id.value, EGL_NONE)
        config, count = _P(), _I(0)
        egl.eglChooseConfig.argtypes = [_P, ctypes.POINTER(_I), ctypes.POINTER(_P), _I, ctypes.POINTER(_I)]
        if not egl.eglChooseConfig(display, attribs, ctypes.byref(config), 1, ctypes.byref(count)) or count.value < 1:
            raise XrError("OpenXRSink: eglChooseConfig found no EGLConfig for rayvr's context; "
                          "create the context through EGL (RAYVR_GL_BACKEND=egl)")
        fields = dict(xr.GraphicsBindingEGLMNDX._fields_)
        get_proc = xr.PFN_xrEglGetProcAddressMNDX(ctypes.cast(egl.eglGetProcAddress, _P).value)
        return xr.GraphicsBindingEGLMNDX(
            get_proc_address=get_proc,
            display=ctypes.cast(_P(display), fields["display"]),
            config=ctypes.cast(config, fields["config"]),
            context=ctypes.cast(_P(context), fields["context"]))

    def xlib_binding(self, xr):
        """XrGraphicsBindingOpenGLXlibKHR for the current GLX context."""
        glx = self._glx
        for name in ("glXGetCurrentDisplay", "glXGetCurrentDrawable"):
            getattr(glx, name).restype = _P if name == "glXGetCurrentDisplay" else ctypes.c_ulong
        display, context, drawable = glx.glXGetCurrentDisplay(), glx.glXGetCurrentContext(), glx.glXGetCurrentDrawable()
        glx.glXQueryContext.argtypes = [_P, _P, _I, ctypes.POINTER(_I)]
        fb_id, screen = _I(0), _I(0)
        glx.glXQueryContext(display, context, GLX_FBCONFIG_ID, ctypes.byref(fb_id))
        glx.glXQueryContext(display, context, GLX_SCREEN, ctypes.byref(screen))
        # Find the context's GLXFBConfig by id among the screen's configs (Mesa's glXChooseFBConfig
        # does not match on GLX_FBCONFIG_ID alone).
        glx.glXGetFBConfigs.restype = ctypes.POINTER(_P)
        glx.glXGetFBConfigs.argtypes = [_P, _I, ctypes.POINTER(_I)]
        glx.glXGetFBConfigAttrib.argtypes = [_P, _P, _I, ctypes.POINTER(_I)]
        n, value = _I(0), _I(0)
        configs = glx.glXGetFBConfigs(display, screen.value, ctypes.byref(n))
        fbconfig = None
        for i in range(n.value if configs else 0):
            glx.glXGetFBConfigAttrib(display, configs[i], GLX_FBCONFIG_ID, ctypes.byref(value))
            if value.value == fb_id.value:
                fbconfig = configs[i]
                break
        if fbconfig is None:
            raise XrError(f"OpenXRSink: no GLXFBConfig with id {fb_id.value} for rayvr's GLX context")
        visual = _I(0)
        glx.glXGetFBConfigAttrib(display, fbconfig, GLX_VISUAL_ID, ctypes.byref(visual))
        if not visual.value:
            raise XrError("OpenXRSink: rayvr's GLX context has no X visual (a pbuffer-only GLXFBConfig, as "
                          "glcontext's standalone context makes); XR_KHR_opengl_enable on Xlib needs a "
                          "window-capable context. Use the EGL context (RAYVR_GL_BACKEND=egl) with a runtime "
                          "that has XR_MNDX_egl_enable (Monado), or create rayvr's context from a window")
        visualid = visual.value
        fields = dict(xr.GraphicsBindingOpenGLXlibKHR._fields_)
        return xr.GraphicsBindingOpenGLXlibKHR(
            x_display=ctypes.cast(_P(display), fields["x_display"]), visualid=visualid,
            glx_fbconfig=ctypes.cast(_P(fbconfig), fields["glx_fbconfig"]), glx_drawable=drawable,
            glx_context=ctypes.cast(_P(context), fields["glx_context"]))


class SwapchainCopier:
    """Copies a rendered TEXTURE_2D_ARRAY into swapchain images, GPU-side.

    A raw glCopyImageSubData when the bytes already mean what the swapchain format says (rgba8
    sRGB-encoded -> GL_SRGB8_ALPHA8, rgba8 linear -> GL_RGBA8, rgba16f -> GL_RGBA16F); otherwise
    one compute pass re-encodes into a staging array first.
    """

    _SHADER = Path(__file__).with_name("openxr_copy.comp")

    def __init__(self, gl, platform: GLPlatform, swapchain_format: int):
        self.gl = gl
        self.platform = platform
        self.format = swapchain_format
        # The staging array holds what the swapchain format means: 8-bit sRGB/linear, or half/full float.
        self._staging_dtype = {GL_RGBA16F: "f2", GL_RGBA32F: "f4"}.get(swapchain_format, "f1")
        self._staging = None
        self._program = None   # built on the first re-encode; compute_program re-reads its file per call
        self._copy = platform.proc("glCopyImageSubData", None, [_U, _U, _I, _I, _I, _I, _U, _U, _I, _I, _I, _I, _I, _I, _I])
        self._flush = platform.proc("glFlush", None, [])

    def plan(self, texture_array, source_srgb: bool) -> tuple[bool, bool, bool]:
        """(raw copy?, decode sRGB?, encode sRGB?) for this source and the swapchain format."""
        dest_srgb = self.format == GL_SRGB8_ALPHA8
        raw = texture_array.components == 4 and (
            (texture_array.dtype == "f1" and self.format in (GL_SRGB8_ALPHA8, GL_RGBA8) and source_srgb == dest_srgb)
            or (texture_array.dtype == "f2" and self.format == GL_RGBA16F and not source_srgb)
            or (texture_array.dtype == "f4" and self.format == GL_RGBA32F and not source_srgb))
        return raw, source_srgb and not dest_srgb, dest_srgb and not source_srgb

    def _restage(self, texture_array, decode: bool, encode: bool):
        w, h, n = texture_array.width, texture_array.height, texture_array.layers
        if self._staging is None or self._staging.size != (w, h, n):
            self._staging = self.gl.texture_array((w, h, n), 4, dtype=self._staging_dtype)
        if self._program is None:
            self._program = compute_program(self.gl, self._SHADER,
                                            {"STAGING_FORMAT": RGBA_IMAGE_FORMATS[self._staging_dtype]})
        prog = self._program
        prog["decode_srgb"] = int(decode)
        prog["encode_srgb"] = int(encode)
        texture_array.use(0)
        self._staging.bind_to_image(0, read=False, write=True)
        prog.run((w + 7) // 8, (h + 7) // 8, n)
        self.gl.memory_barrier()
        return self._staging

    def copy(self, texture_array, source_srgb: bool, targets) -> None:
        """`targets`: [(gl image name, GL target, first layer in the image, view index, count)]."""
        raw, decode, encode = self.plan(texture_array, source_srgb)
        self._copy_layers(texture_array if raw else self._restage(texture_array, decode, encode), targets)

    def copy_depth(self, depth_array, targets) -> None:
        """Raw copy of a depth texture array whose internal format equals the swapchain's."""
        self._copy_layers(depth_array, targets)

    def _copy_layers(self, src, targets) -> None:
        w, h = src.width, src.height
        for image, target, dst_layer, view, count in targets:
            self._copy(src.glo, GL_TEXTURE_2D_ARRAY, 0, 0, 0, view, image, target, 0, 0, 0, dst_layer, w, h, count)
        self._flush()
