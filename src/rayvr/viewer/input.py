"""Keyboard and mouse input as events, and the per-frame state the camera controllers read.

Window callbacks (glfw) and scripted input (`script.py`) produce the same `InputEvent`s and go
through one `InputState.handle()`, so a script exercises exactly what a person's hands do. Keys
are named as glfw names them without the prefix: "W", "LEFT_SHIFT", "F12", "SPACE", "1".
ImGui gets every event first; while it wants the mouse or keyboard (a panel under the cursor, a
text field being edited) the camera does not see them.
"""
from __future__ import annotations

import dataclasses

BUTTONS = {"left": 0, "right": 1, "middle": 2}


@dataclasses.dataclass(frozen=True)
class InputEvent:
    """One input event. kind: 'key' (key, down), 'char' (char), 'move' (x, y in window pixels
    from the top-left), 'button' (button 0 left / 1 right / 2 middle, down), 'scroll' (dx, dy)."""

    kind: str
    key: str = ""
    down: bool = False
    char: int = 0
    x: float = 0.0
    y: float = 0.0
    button: int = 0
    dx: float = 0.0
    dy: float = 0.0


class InputState:
    """What the camera reads each frame: keys held, keys pressed this frame, the mouse drag and
    the scroll since the last frame. `ui_wants_mouse` / `ui_wants_keyboard` are set by the UI
    (from ImGui's io, one frame old as ImGui intends)."""

    def __init__(self):
        self.keys_down: set[str] = set()
        self.pressed: set[str] = set()
        self.mouse: tuple[float, float] | None = None
        self.buttons_down: set[int] = set()
        self.drag_buttons: set[int] = set()   # buttons pressed outside the UI, still held
        self.drag = (0.0, 0.0)                # mouse motion this frame while a drag button is held
        self.scroll = 0.0
        self.ui_wants_mouse = False
        self.ui_wants_keyboard = False

    def begin_frame(self) -> None:
        """Forget this frame's presses, drag and scroll (held keys and buttons stay)."""
        self.pressed.clear()
        self.drag = (0.0, 0.0)
        self.scroll = 0.0

    def handle(self, event: InputEvent) -> None:
        """Update the state with one event (the UI has seen it already)."""
        if event.kind == "key":
            if event.down:
                if not self.ui_wants_keyboard:
                    self.keys_down.add(event.key)
                    self.pressed.add(event.key)
            else:
                self.keys_down.discard(event.key)
        elif event.kind == "move":
            if self.mouse is not None and self.drag_buttons:
                self.drag = (self.drag[0] + event.x - self.mouse[0], self.drag[1] + event.y - self.mouse[1])
            self.mouse = (event.x, event.y)
        elif event.kind == "button":
            if event.down:
                self.buttons_down.add(event.button)
                if not self.ui_wants_mouse:
                    self.drag_buttons.add(event.button)
            else:
                self.buttons_down.discard(event.button)
                self.drag_buttons.discard(event.button)
        elif event.kind == "scroll":
            if not self.ui_wants_mouse:
                self.scroll += event.dy

    def held(self, *keys: str) -> bool:
        """True when any of `keys` is held."""
        return any(k in self.keys_down for k in keys)
