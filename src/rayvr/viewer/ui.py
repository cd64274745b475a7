"""Dear ImGui (imgui-bundle) on the viewer's GL context: its C++ OpenGL 3 renderer backend
(`imgui.backends.opengl3_*`, drawing into whatever framebuffer is bound) and input fed from
`InputEvent`s, so a window, a script and the offscreen benchmark drive it the same way.
ImPlot (in imgui-bundle) draws the timing plots."""
from __future__ import annotations

from ..errors import ViewerError
from .input import InputEvent, InputState

_SPECIAL = {"LEFT": "left_arrow", "RIGHT": "right_arrow", "UP": "up_arrow", "DOWN": "down_arrow",
            "LEFT_CONTROL": "left_ctrl", "RIGHT_CONTROL": "right_ctrl"}
_MODIFIERS = {"left_shift": "mod_shift", "right_shift": "mod_shift", "left_ctrl": "mod_ctrl",
              "right_ctrl": "mod_ctrl", "left_alt": "mod_alt", "right_alt": "mod_alt",
              "left_super": "mod_super", "right_super": "mod_super"}


def imgui_key_name(name: str) -> str:
    """The imgui.Key attribute for a glfw key name ('W' -> 'w', '1' -> '_1', 'KP_1' -> 'keypad1')."""
    if name in _SPECIAL:
        return _SPECIAL[name]
    if name.isdigit():
        return f"_{name}"
    if name.startswith("KP_"):
        rest = name[3:].lower()
        return f"keypad{rest}" if rest.isdigit() else f"keypad_{rest}"
    return name.lower()


class Ui:
    """One ImGui + ImPlot context and the OpenGL 3 backend on the current GL context."""

    def __init__(self):
        from imgui_bundle import imgui, implot

        self.imgui, self.implot = imgui, implot
        self.context = imgui.create_context()
        self.plot_context = implot.create_context()
        io = imgui.get_io()
        io.set_ini_filename(None)     # no imgui.ini written beside the user's files
        imgui.style_colors_dark()
        self._keys: dict[str, object] = {}
        self._backend = bool(imgui.backends.opengl3_init("#version 450"))
        if not self._backend:
            self.close()
            raise ViewerError("rayvr view: Dear ImGui's OpenGL 3 backend did not start on this context")

    def _key(self, name: str):
        if name not in self._keys:
            self._keys[name] = getattr(self.imgui.Key, imgui_key_name(name), None)
        return self._keys[name]

    def feed(self, event: InputEvent) -> None:
        """Pass one input event to ImGui."""
        io = self.imgui.get_io()
        if event.kind == "key":
            key = self._key(event.key)
            if key is not None:
                io.add_key_event(key, event.down)
                mod = _MODIFIERS.get(imgui_key_name(event.key))
                if mod:
                    io.add_key_event(getattr(self.imgui.Key, mod), event.down)
        elif event.kind == "char":
            io.add_input_character(event.char)
        elif event.kind == "move":
            io.add_mouse_pos_event(event.x, event.y)
        elif event.kind == "button":
            io.add_mouse_button_event(event.button, event.down)
        elif event.kind == "scroll":
            io.add_mouse_wheel_event(event.dx, event.dy)

    def resume(self, inp: InputState) -> None:
        """The panels show again after being hidden (they got no input meanwhile): forget held
        keys and buttons and tell ImGui where the mouse is."""
        io = self.imgui.get_io()
        io.clear_events_queue()
        io.clear_input_keys()
        io.clear_input_mouse()
        if inp.mouse is not None:
            io.add_mouse_pos_event(*inp.mouse)

    def share_wants(self, inp: InputState) -> None:
        """Tell the input state whether ImGui wants the mouse and keyboard (from its last frame)."""
        io = self.imgui.get_io()
        inp.ui_wants_mouse = bool(io.want_capture_mouse)
        inp.ui_wants_keyboard = bool(io.want_capture_keyboard)

    def frame(self, window_size, framebuffer_size, dt: float, build) -> None:
        """One ImGui frame: `build()` makes the widgets; the draw goes to the bound framebuffer."""
        imgui = self.imgui
        io = imgui.get_io()
        io.display_size = imgui.ImVec2(*window_size)
        io.display_framebuffer_scale = imgui.ImVec2(framebuffer_size[0] / max(window_size[0], 1),
                                                    framebuffer_size[1] / max(window_size[1], 1))
        io.delta_time = max(float(dt), 1e-4)
        imgui.backends.opengl3_new_frame()
        imgui.new_frame()
        try:
            build()
        finally:
            imgui.render()
        imgui.backends.opengl3_render_draw_data(imgui.get_draw_data())

    def close(self) -> None:
        imgui = self.imgui
        if self.context is not None:
            if self._backend:
                imgui.backends.opengl3_shutdown()
            self.implot.destroy_context(self.plot_context)
            imgui.destroy_context(self.context)
            self.context = None
