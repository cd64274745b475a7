"""Scripted input for tests and demos: timed key and mouse events, screenshots and effect changes.

A script is JSON, events by frame number (frame 0 is the first the viewer draws):

    {"dt": 0.0111,                                        optional: seconds per frame (default 1/90)
     "events": [
       {"frame": 2,  "screenshot": "out/a.png"},          the window with its UI, after frame 2 drew
       {"frame": 3,  "key": "W", "action": "down"},       down, up, or tap (down now, up next frame)
       {"frame": 20, "key": "W", "action": "up"},
       {"frame": 21, "mouse": [120, 80]},                 cursor to window pixels (from the top-left)
       {"frame": 21, "button": "left", "action": "down"}, left, right or middle
       {"frame": 22, "scroll": 1.5},
       {"frame": 23, "text": "0.5"},                      typed characters (into a focused field)
       {"frame": 24, "effect": {"LeftWall": "path_traced"}},
       {"frame": 30, "quit": true}]}

Input events at frame k reach the viewer before it updates the camera and renders frame k, through
the same path as a window's callbacks. Frames advance by `dt` of simulated time, not wall time, so
a scripted run moves the camera the same way on every machine.
"""
from __future__ import annotations

import dataclasses
import math
from pathlib import Path

from ..fileio import read_json
from ..errors import OptionError, did_you_mean
from .input import BUTTONS, InputEvent

DEFAULT_DT = 1.0 / 90.0
ACTIONS = ("down", "up", "tap")
_KINDS = ("key", "mouse", "button", "scroll", "text", "screenshot", "effect", "quit")


@dataclasses.dataclass(frozen=True)
class ScriptAction:
    """A scripted viewer action: 'screenshot' (value: path), 'effect' ({material: effect}), 'quit'."""

    kind: str
    value: object = None


class InputScript:
    """Events and actions by frame; see the module docstring for the format."""

    def __init__(self, events: dict[int, list], dt: float = DEFAULT_DT, source: str = "script"):
        self.events = events
        self.dt = float(dt)
        self.source = source

    @property
    def last_frame(self) -> int:
        """The last frame with an event (-1 for an empty script)."""
        return max(self.events, default=-1)

    def at(self, frame: int) -> list:
        """The InputEvents and ScriptActions of `frame`, in file order."""
        return self.events.get(frame, [])

    @classmethod
    def load(cls, path, key_names) -> "InputScript":
        """Read and check a script; `key_names` are the key names the window knows (glfw's).
        OptionError naming the file and the event's field on any mistake."""
        path = Path(path)
        doc = read_json(path, f"--script {path}")
        return cls.parse(doc, key_names, str(path))

    @classmethod
    def parse(cls, doc, key_names, source: str = "script") -> "InputScript":
        """A script from its JSON value (a dict with "events", or the list alone)."""
        key_names = set(key_names)
        dt = DEFAULT_DT
        if isinstance(doc, dict):
            dt = doc.get("dt", DEFAULT_DT)
            if not (isinstance(dt, (int, float)) and not isinstance(dt, bool) and math.isfinite(dt) and dt > 0):
                raise OptionError(f"{source}: dt: expected seconds per frame > 0, got {dt!r}")
            doc = doc.get("events")
        if not isinstance(doc, list):
            raise OptionError(f"{source}: events: expected a list of {{\"frame\": N, ...}} objects "
                              f"(top level or under \"events\")")
        events: dict[int, list] = {}

        def add(frame, item):
            events.setdefault(frame, []).append(item)

        for i, e in enumerate(doc):
            where = f"{source}: events[{i}]"
            if not isinstance(e, dict):
                raise OptionError(f"{where}: expected an object such as {{\"frame\": 3, \"key\": \"W\", "
                                  f"\"action\": \"down\"}}, got {e!r}")
            frame = e.get("frame")
            if not (isinstance(frame, int) and not isinstance(frame, bool) and frame >= 0):
                raise OptionError(f"{where}.frame: expected a frame number >= 0, got {frame!r}")
            kinds = [k for k in _KINDS if k in e]
            unknown = [k for k in e if k not in _KINDS and k not in ("frame", "action")]
            if unknown or len(kinds) != 1:
                bad = unknown[0] if unknown else None
                hint = did_you_mean(bad, _KINDS) if bad else ""
                raise OptionError(f"{where}: give exactly one of {', '.join(_KINDS)}"
                                  + (f"; unknown field '{bad}'{hint}" if bad else f", not {kinds or 'none'}"))
            kind = kinds[0]
            value = e[kind]
            if kind in ("key", "button"):
                action = e.get("action", "tap")
                if action not in ACTIONS:
                    raise OptionError(f"{where}.action: '{action}' is not one of {', '.join(ACTIONS)}")
                if kind == "key":
                    if value not in key_names:
                        raise OptionError(f"{where}.key: unknown key {value!r}{did_you_mean(str(value), key_names)}; "
                                          f"use glfw's names without KEY_, e.g. W, LEFT_SHIFT, F12, SPACE")
                    make = lambda down, v=value: InputEvent("key", key=v, down=down)  # noqa: E731
                else:
                    if value not in BUTTONS:
                        raise OptionError(f"{where}.button: {value!r} is not one of {', '.join(BUTTONS)}")
                    make = lambda down, v=BUTTONS[value]: InputEvent("button", button=v, down=down)  # noqa: E731
                if action in ("down", "tap"):
                    add(frame, make(True))
                if action in ("up", "tap"):
                    add(frame + (action == "tap"), make(False))
            elif kind == "mouse":
                if not (isinstance(value, list) and len(value) == 2
                        and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)):
                    raise OptionError(f"{where}.mouse: expected [x, y] in window pixels, got {value!r}")
                add(frame, InputEvent("move", x=float(value[0]), y=float(value[1])))
            elif kind == "scroll":
                if not (isinstance(value, (int, float)) and not isinstance(value, bool)):
                    raise OptionError(f"{where}.scroll: expected a number of wheel steps, got {value!r}")
                add(frame, InputEvent("scroll", dy=float(value)))
            elif kind == "text":
                if not isinstance(value, str):
                    raise OptionError(f"{where}.text: expected a string, got {value!r}")
                for ch in value:
                    add(frame, InputEvent("char", char=ord(ch)))
            elif kind == "screenshot":
                if not (isinstance(value, str) and value.lower().endswith((".png", ".exr"))):
                    raise OptionError(f"{where}.screenshot: expected a .png (window) or .exr (HDR output) "
                                      f"path, got {value!r}")
                add(frame, ScriptAction("screenshot", value))
            elif kind == "effect":
                if not (isinstance(value, dict) and value):
                    raise OptionError(f"{where}.effect: expected {{\"Material\": \"effect\", ...}}, got {value!r}")
                add(frame, ScriptAction("effect", dict(value)))
            elif kind == "quit":
                add(frame, ScriptAction("quit"))
        return cls(events, dt, source)
