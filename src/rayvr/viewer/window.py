"""The viewer's window: glfw, an OpenGL 4.5 core context through GLX that rayvr renders with.

The renderer draws straight into this context (`Window.gpu`, a GpuContext attached to it), so a
frame never leaves the GPU. A headless EGL context current on the thread (rayvr's default, made
by earlier headless work in the same process) is stepped aside while the window lives and made
current again when it closes. Callbacks become `InputEvent`s for `on_event`.
"""
from __future__ import annotations

import contextlib
import os

from ..errors import ViewerError
from ..gpu.context import attach_context
from ..gpu.current import egl_stepped_aside
from .input import InputEvent


def key_names(glfw) -> dict[int, str]:
    """glfw key codes -> names without the KEY_ prefix ('W', 'LEFT_SHIFT', 'F12')."""
    return {getattr(glfw, n): n[4:] for n in dir(glfw)
            if n.startswith("KEY_") and n != "KEY_UNKNOWN" and n != "KEY_LAST"}


class Window:
    """A glfw window of `size` (width, height) pixels with its GL context current on this thread."""

    def __init__(self, size, title: str = "rayvr", visible: bool = True):
        import glfw

        self._glfw = glfw
        self._errors: list[str] = []
        self._stack = contextlib.ExitStack()
        self.on_event = None   # callable(InputEvent), set by the viewer
        glfw.set_error_callback(self._error)
        if not glfw.init():
            raise ViewerError(f"rayvr view cannot start glfw on DISPLAY={os.environ.get('DISPLAY', '')}: "
                              f"{self._last_error()}")
        try:
            self._stack.enter_context(egl_stepped_aside())
            glfw.default_window_hints()
            glfw.window_hint(glfw.CONTEXT_VERSION_MAJOR, 4)
            glfw.window_hint(glfw.CONTEXT_VERSION_MINOR, 5)
            glfw.window_hint(glfw.OPENGL_PROFILE, glfw.OPENGL_CORE_PROFILE)
            glfw.window_hint(glfw.OPENGL_FORWARD_COMPAT, True)
            glfw.window_hint(glfw.VISIBLE, bool(visible))
            glfw.window_hint(glfw.DEPTH_BITS, 0)
            self.handle = glfw.create_window(int(size[0]), int(size[1]), title, None, None)
            if not self.handle:
                raise ViewerError(f"rayvr view cannot open an OpenGL 4.5 core window: {self._last_error()}; "
                                  f"the driver must offer OpenGL 4.5 through GLX (rayvr info shows what EGL offers)")
            glfw.make_context_current(self.handle)
            glfw.swap_interval(0)   # show the renderer's own frame time, not the display's
            self.gpu = attach_context()
        except BaseException:
            self.close()
            raise
        self.names = key_names(glfw)
        glfw.set_key_callback(self.handle, self._key)
        glfw.set_char_callback(self.handle, self._char)
        glfw.set_cursor_pos_callback(self.handle, self._move)
        glfw.set_mouse_button_callback(self.handle, self._button)
        glfw.set_scroll_callback(self.handle, self._scroll)

    # -- glfw callbacks -> InputEvents ----------------------------------------------------------
    def _error(self, code, description) -> None:
        text = description.decode(errors="replace") if isinstance(description, bytes) else str(description)
        self._errors.append(f"{text} (glfw error {code:#x})")

    def _last_error(self) -> str:
        return self._errors[-1] if self._errors else "no reason given"

    def _emit(self, event: InputEvent) -> None:
        if self.on_event is not None:
            self.on_event(event)

    def _key(self, _win, key, _scancode, action, _mods) -> None:
        name = self.names.get(key)
        if name is not None and action != self._glfw.REPEAT:
            self._emit(InputEvent("key", key=name, down=action == self._glfw.PRESS))

    def _char(self, _win, codepoint) -> None:
        self._emit(InputEvent("char", char=int(codepoint)))

    def _move(self, _win, x, y) -> None:
        self._emit(InputEvent("move", x=float(x), y=float(y)))

    def _button(self, _win, button, action, _mods) -> None:
        self._emit(InputEvent("button", button=int(button), down=action == self._glfw.PRESS))

    def _scroll(self, _win, dx, dy) -> None:
        self._emit(InputEvent("scroll", dx=float(dx), dy=float(dy)))

    # -- the viewer's surface --------------------------------------------------------------------
    @property
    def key_names(self) -> set[str]:
        return set(self.names.values())

    @property
    def framebuffer(self):
        """The window's default framebuffer (moderngl)."""
        return self.gpu.gl.screen

    @property
    def framebuffer_size(self) -> tuple[int, int]:
        return tuple(self._glfw.get_framebuffer_size(self.handle))

    @property
    def window_size(self) -> tuple[int, int]:
        return tuple(self._glfw.get_window_size(self.handle))

    def set_size(self, size) -> None:
        self._glfw.set_window_size(self.handle, int(size[0]), int(size[1]))

    def poll(self) -> None:
        self._glfw.poll_events()

    def should_close(self) -> bool:
        return bool(self._glfw.window_should_close(self.handle))

    def present(self) -> None:
        self._glfw.swap_buffers(self.handle)

    def close(self) -> None:
        """Destroy the window and its context; the stepped-aside EGL context is current again."""
        glfw = self._glfw
        if getattr(self, "handle", None):
            glfw.make_context_current(None)
            glfw.destroy_window(self.handle)
            self.handle = None
        glfw.terminate()
        self._stack.close()
