"""Which EGL device a process should render on: the one that is its CUDA device.

`CUDA_VISIBLE_DEVICES` (which Ray sets per actor) reorders and hides CUDA devices but not EGL
devices, so EGL device 0 is not the actor's GPU. EGL_EXT_device_enumeration lists the devices
(in the order glcontext's `device_index` counts them) and EGL_NV_device_cuda tells each one's
CUDA device (`EGL_CUDA_DEVICE_NV`). Without NVIDIA's driver (Mesa llvmpipe) no device answers;
then the default display is used.

NVIDIA's driver answers with the CUDA ordinal as this process sees it (CUDA_VISIBLE_DEVICES
applied: only the visible GPUs answer, numbered from 0). Should a driver answer with physical
indices instead (every GPU answers, more than are visible), the physical id is matched.
"""
from __future__ import annotations

import ctypes
import dataclasses
import os

from .rawgl import load_library

EGL_EXTENSIONS = 0x3055
EGL_CUDA_DEVICE_NV = 0x323A
EGL_DRM_DEVICE_FILE_EXT = 0x3233
MAX_DEVICES = 64


@dataclasses.dataclass(frozen=True)
class EglDevice:
    """One EGL device: its index (glcontext's `device_index`), extensions, CUDA device, DRM file."""

    index: int
    extensions: str = ""
    cuda_device: int | None = None
    drm_file: str | None = None

    @property
    def software(self) -> bool:
        return "EGL_MESA_device_software" in self.extensions


def list_devices() -> list[EglDevice]:
    """The EGL devices in enumeration order; [] without libEGL or EGL_EXT_device_enumeration."""
    egl = load_library(["EGL", "libEGL.so.1"])
    if egl is None:
        return []
    egl.eglGetProcAddress.restype = ctypes.c_void_p
    egl.eglGetProcAddress.argtypes = [ctypes.c_char_p]
    egl.eglQueryString.restype = ctypes.c_char_p
    egl.eglQueryString.argtypes = [ctypes.c_void_p, ctypes.c_int]
    client = (egl.eglQueryString(None, EGL_EXTENSIONS) or b"").decode()
    if "EGL_EXT_device_enumeration" not in client and "EGL_EXT_device_base" not in client:
        return []

    def proc(name, restype, *argtypes):
        addr = egl.eglGetProcAddress(name.encode())
        return ctypes.CFUNCTYPE(restype, *argtypes)(addr) if addr else None

    query_devices = proc("eglQueryDevicesEXT", ctypes.c_uint, ctypes.c_int, ctypes.POINTER(ctypes.c_void_p),
                         ctypes.POINTER(ctypes.c_int))
    query_string = proc("eglQueryDeviceStringEXT", ctypes.c_char_p, ctypes.c_void_p, ctypes.c_int)
    query_attrib = proc("eglQueryDeviceAttribEXT", ctypes.c_uint, ctypes.c_void_p, ctypes.c_int,
                        ctypes.POINTER(ctypes.c_ssize_t))
    if query_devices is None:
        return []
    handles = (ctypes.c_void_p * MAX_DEVICES)()
    count = ctypes.c_int(0)
    if not query_devices(MAX_DEVICES, handles, ctypes.byref(count)):
        return []
    devices = []
    for i in range(count.value):
        ext = (query_string(handles[i], EGL_EXTENSIONS) or b"").decode() if query_string else ""
        cuda = None
        if query_attrib is not None and "EGL_NV_device_cuda" in ext:
            value = ctypes.c_ssize_t(-1)
            if query_attrib(handles[i], EGL_CUDA_DEVICE_NV, ctypes.byref(value)) and value.value >= 0:
                cuda = int(value.value)
        drm = None
        if query_string is not None and "EGL_EXT_device_drm" in ext:
            raw = query_string(handles[i], EGL_DRM_DEVICE_FILE_EXT)
            drm = raw.decode() if raw else None
        devices.append(EglDevice(i, ext, cuda, drm))
    return devices


def visible_cuda_devices(env=None) -> list[str] | None:
    """CUDA_VISIBLE_DEVICES as a list (None when unset: every GPU is visible)."""
    value = (os.environ if env is None else env).get("CUDA_VISIBLE_DEVICES")
    if value is None:
        return None
    return [s.strip() for s in value.split(",") if s.strip()]


def select_device(cuda_ordinal: int = 0, visible: list[str] | None = None,
                  devices: list[EglDevice] | None = None) -> tuple[int | None, str]:
    """(EGL device index, why) for this process's CUDA device `cuda_ordinal` (0: the first
    visible one, an actor's GPU); (None, why) means the default display (no CUDA device answers:
    llvmpipe, or no NVIDIA EGL). `visible` defaults to CUDA_VISIBLE_DEVICES, `devices` to
    `list_devices()` (tests pass fakes)."""
    devices = list_devices() if devices is None else devices
    visible = visible_cuda_devices() if visible is None else visible
    answering = [d for d in devices if d.cuda_device is not None]
    if not answering:
        return None, f"{len(devices)} EGL device(s), none with EGL_NV_device_cuda: the default display"
    target, kind = cuda_ordinal, "CUDA ordinal"
    if visible is not None and len(answering) > len(visible) and cuda_ordinal < len(visible):
        # Every GPU answers although only some are visible: the driver numbers them physically.
        try:
            target, kind = int(visible[cuda_ordinal]), "physical CUDA device"
        except ValueError:   # GPU UUIDs in CUDA_VISIBLE_DEVICES: keep the ordinal
            pass
    for d in answering:
        if d.cuda_device == target:
            return d.index, f"EGL device {d.index} is {kind} {target} (EGL_CUDA_DEVICE_NV)"
    return None, (f"no EGL device reports {kind} {target} (devices report "
                  f"{[d.cuda_device for d in answering]}): the default display")
