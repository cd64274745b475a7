"""A window-sized offscreen framebuffer in place of a window: the viewer's frame loop (render,
display, UI) on a machine with no display, e.g. to time it on a headless GPU (benchmarks/viewer.py).
It offers what `Window` offers the viewer; it never closes by itself and has no input."""
from __future__ import annotations


class OffscreenSurface:
    """An RGBA8 framebuffer of `size` (width, height) on `gpu` (default: rayvr's headless context)."""

    def __init__(self, size, gpu=None):
        from ..gpu import get_context

        self.gpu = gpu or get_context()
        self.size = (int(size[0]), int(size[1]))
        self._color = self.gpu.gl.texture(self.size, 4)
        self.framebuffer = self.gpu.gl.framebuffer(color_attachments=[self._color])
        self.on_event = None
        self.key_names = _glfw_key_names()   # so a script's keys are checked as for a window

    @property
    def framebuffer_size(self) -> tuple[int, int]:
        return self.size

    @property
    def window_size(self) -> tuple[int, int]:
        return self.size

    def set_size(self, size) -> None:
        self.framebuffer.release()
        self._color.release()
        self.size = (int(size[0]), int(size[1]))
        self._color = self.gpu.gl.texture(self.size, 4)
        self.framebuffer = self.gpu.gl.framebuffer(color_attachments=[self._color])

    def poll(self) -> None:
        pass

    def should_close(self) -> bool:
        return False

    def present(self) -> None:
        pass

    def close(self) -> None:
        self.framebuffer.release()
        self._color.release()


def _glfw_key_names() -> set[str]:
    """glfw's key names when glfw is installed (no display needed), else none."""
    try:
        import glfw
    except ImportError:
        return set()
    from .window import key_names

    return set(key_names(glfw).values())
