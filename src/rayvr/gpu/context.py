"""The moderngl context rayvr renders with, and what the driver can do.

Headless EGL is the default: Mesa llvmpipe without a GPU, the vendor driver with one.
One context is shared per process (`get_context()`), as every GPU resource belongs to it.
"""
from __future__ import annotations

import contextlib
import dataclasses
import os
import re

import moderngl

from ..errors import GpuError

_INSTALL_HINT = (
    "install the EGL loader and Mesa's drivers (Debian/Ubuntu: "
    "'apt-get install libegl1 libgl1-mesa-dri libgles2'), or on a GPU machine the vendor's EGL driver"
)


@dataclasses.dataclass(frozen=True)
class Capabilities:
    """What the OpenGL driver offers that rayvr's passes can choose between."""

    renderer: str
    vendor: str
    version: str
    gl_version: int
    multiview: bool          # GL_OVR_multiview2: one draw to all views
    vertex_layer: bool       # gl_Layer from the vertex shader (layered instanced fallback)
    bindless_textures: bool  # GL_ARB_bindless_texture
    subgroups: bool          # GL_KHR_shader_subgroup or GL_ARB_shader_ballot
    int64: bool              # GL_ARB_gpu_shader_int64
    timer_queries: bool      # GL_ARB_timer_query whose results can be trusted
    max_texture_layers: int
    max_compute_work_group_invocations: int
    is_software: bool        # llvmpipe / softpipe: ~1e4 times slower than a GPU
    weak_raster: bool = False  # rasterising is slow against compute: see is_weak_raster()

    def as_dict(self) -> dict:
        return dataclasses.asdict(self)


# NVIDIA datacenter compute GPUs: graphics runs on only a few of their TPCs, so fragment work is
# ~30x slower than compute there (the raster G-buffer takes several times the ray-traced one's
# time). A heuristic on the renderer string: the A, H and B series' 100, 200, 800 and 20 parts,
# with the G- and GB- superchips, as the pattern below spells them.
_WEAK_RASTER = re.compile(r"\b(G?[AHB](?:100|200|800|20)[A-Z]?)\b")


def is_weak_raster(renderer: str) -> bool:
    """True for NVIDIA datacenter compute GPUs without full graphics (a heuristic on the renderer
    string: the vendor, then a model the pattern above matches); then a ray-traced G-buffer beats
    raster."""
    if "nvidia" not in renderer.lower():
        return False
    return _WEAK_RASTER.search(renderer.upper()) is not None


def probe(ctx: moderngl.Context) -> Capabilities:
    """Read the driver's capabilities from a live context."""
    ext = ctx.extensions
    renderer = ctx.info.get("GL_RENDERER", "?")
    software = any(s in renderer.lower() for s in ("llvmpipe", "softpipe", "swrast"))
    return Capabilities(
        renderer=renderer,
        vendor=ctx.info.get("GL_VENDOR", "?"),
        version=ctx.info.get("GL_VERSION", "?"),
        gl_version=ctx.version_code,
        multiview="GL_OVR_multiview2" in ext,
        vertex_layer="GL_ARB_shader_viewport_layer_array" in ext or "GL_AMD_vertex_shader_layer" in ext,
        bindless_textures="GL_ARB_bindless_texture" in ext,
        subgroups="GL_KHR_shader_subgroup" in ext or "GL_ARB_shader_ballot" in ext,
        int64="GL_ARB_gpu_shader_int64" in ext,
        # llvmpipe answers timer queries with placeholder values: time it with finish + wall clock.
        timer_queries="GL_ARB_timer_query" in ext and not software,
        max_texture_layers=int(ctx.info.get("GL_MAX_ARRAY_TEXTURE_LAYERS", 256)),
        max_compute_work_group_invocations=int(ctx.info.get("GL_MAX_COMPUTE_WORK_GROUP_INVOCATIONS", 1024)),
        is_software=software,
        weak_raster=is_weak_raster(renderer),
    )


class GpuContext:
    """A moderngl context with its probed capabilities."""

    def __init__(self, gl: moderngl.Context):
        self.gl = gl
        self.caps = probe(gl)

    def __repr__(self) -> str:
        return f"GpuContext({self.caps.renderer!r}, GL {self.caps.gl_version})"


_default: GpuContext | None = None


def create_context(backend: str | None = None, device_index: int | None = None) -> GpuContext:
    """Create a new headless context (EGL unless RAYVR_GL_BACKEND or `backend` says otherwise).
    `device_index`: the EGL device to render on (rayvr.gpu.egl_devices.select_device picks the
    one of a CUDA device); None is the default display."""
    backend = backend or os.environ.get("RAYVR_GL_BACKEND", "egl")
    try:
        kwargs = {"standalone": True, "require": 450}
        if backend != "default":
            kwargs["backend"] = backend
        if device_index is not None:
            kwargs["device_index"] = int(device_index)
        gl = moderngl.create_context(**kwargs)
    except Exception as exc:  # glcontext raises plain Exceptions with the loader's words
        where = f" on EGL device {device_index}" if device_index is not None else ""
        raise GpuError(f"no OpenGL 4.5 context through {backend}{where}: {exc}; {_INSTALL_HINT}") from exc
    return GpuContext(gl)


def get_context() -> GpuContext:
    """The process-wide shared context, created on first use."""
    global _default
    if _default is None:
        _default = create_context()
    return _default


def set_context(gpu: GpuContext) -> None:
    """Make `gpu` the process-wide context that `get_context()` returns (a cluster worker
    creates its context on its own device first)."""
    global _default
    _default = gpu


def attach_context() -> GpuContext:
    """Wrap the OpenGL context current on this thread (a window's, made current by its toolkit,
    e.g. glfw) as a GpuContext; it must be OpenGL 4.5. moderngl can attach to GLX contexts only
    (glcontext's EGL backend has no attach mode), so on Linux the window's context is GLX."""
    try:
        gl = moderngl.create_context(require=450)
    except Exception as exc:  # glcontext and moderngl raise plain Exceptions
        raise GpuError(f"cannot use the window's OpenGL context: {exc}; rayvr needs OpenGL 4.5 "
                       f"(core profile) through GLX") from exc
    return GpuContext(gl)


@contextlib.contextmanager
def use_context(gpu: GpuContext):
    """Make `gpu` the process-wide default (what `get_context()` returns) inside the block, so code
    that asks for the shared context renders into a window's context instead of making a headless one."""
    global _default
    previous, _default = _default, gpu
    try:
        yield gpu
    finally:
        _default = previous
