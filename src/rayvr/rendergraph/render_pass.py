"""The anatomy of a pass, after Falcor's RenderPass.

A pass declares pins in a pure `reflect()`, builds its programs once in `compile()`, and binds and
dispatches in `execute()`. Its properties are a dict that round-trips (enums as strings).

    class Blit(RenderPass):
        SRC, DST = "src", "dst"                       # pin names are constants
        PROPERTIES = {"scale": 1.0}                    # defaults; the keys are the schema

        def reflect(self, cd):
            r = Reflection()
            r.add_input(self.SRC, "image to copy")
            r.add_output(self.DST, "copy").format("rgba8")
            return r
"""
from __future__ import annotations

import copy
import dataclasses
import enum
from typing import Any

from ..errors import OptionError, did_you_mean
from .formats import get_format


class PinKind(str, enum.Enum):
    TEXTURE = "texture"   # a 2D texture array, one layer per view (or `views` layers)
    BUFFER = "buffer"     # an SSBO of `byte_size` bytes


class PinDirection(str, enum.Enum):
    INPUT = "input"
    OUTPUT = "output"
    INTERNAL = "internal"  # owned by the pass, persists across frames (history)


@dataclasses.dataclass
class Pin:
    """One declared resource of a pass. Builder methods return self so they chain."""

    name: str
    direction: PinDirection
    desc: str = ""
    kind: PinKind = PinKind.TEXTURE
    fmt: str | None = None           # None on an input: accept what is connected
    size_rule: str = "output"        # "output" | "fixed" | "scaled"
    size_value: tuple = (1.0, 1.0)   # (w, h) for fixed, (sx, sy) for scaled
    layers: int | None = None        # None: one layer per view
    byte_size: int = 0               # buffers
    is_optional: bool = False
    unused_reason: str | None = None  # an input this configuration does not read (see unused())
    mip_levels: int = 1

    def format(self, name: str) -> "Pin":
        """Declare the texture format (a name of `formats.FORMATS`)."""
        get_format(name, where=f"pin '{self.name}'")
        self.fmt = name
        return self

    def optional(self, flag: bool = True) -> "Pin":
        """An optional input: the pass still runs when it is unconnected or its source is pruned."""
        self.is_optional = flag
        return self

    def unused(self, reason: str) -> "Pin":
        """An input the pass, as compiled for this scene and graph, does not read (`reason` says
        why): its edge keeps nothing alive, so a source that feeds only unused inputs is pruned."""
        self.unused_reason = reason
        self.is_optional = True
        return self

    def texture_size(self, width: int, height: int) -> "Pin":
        """A fixed size in pixels instead of the graph's output size."""
        self.size_rule, self.size_value = "fixed", (int(width), int(height))
        return self

    def scaled(self, sx: float, sy: float | None = None) -> "Pin":
        """The graph's output size times (sx, sy), rounded, at least 1."""
        self.size_rule, self.size_value = "scaled", (float(sx), float(sy if sy is not None else sx))
        return self

    def views(self, layers: int) -> "Pin":
        """A fixed layer count instead of one layer per view."""
        self.layers = int(layers)
        return self

    def buffer(self, byte_size: int) -> "Pin":
        """Make the pin an SSBO of `byte_size` bytes."""
        self.kind, self.byte_size = PinKind.BUFFER, int(byte_size)
        return self

    def resolved_size(self, output_size: tuple[int, int]) -> tuple[int, int]:
        """The pin's (w, h) in pixels at the graph's per-view output size."""
        if self.size_rule == "fixed":
            return int(self.size_value[0]), int(self.size_value[1])
        if self.size_rule == "scaled":
            return (max(1, round(output_size[0] * self.size_value[0])),
                    max(1, round(output_size[1] * self.size_value[1])))
        return output_size


class Reflection:
    """The pins a pass declares, in order."""

    def __init__(self):
        self.pins: dict[str, Pin] = {}

    def _add(self, name: str, direction: PinDirection, desc: str) -> Pin:
        if name in self.pins:
            raise OptionError(f"pin '{name}' declared twice in reflect(); give each pin one name")
        pin = Pin(name, direction, desc)
        self.pins[name] = pin
        return pin

    def add_input(self, name: str, desc: str = "") -> Pin:
        return self._add(name, PinDirection.INPUT, desc)

    def add_output(self, name: str, desc: str = "") -> Pin:
        return self._add(name, PinDirection.OUTPUT, desc)

    def add_internal(self, name: str, desc: str = "") -> Pin:
        return self._add(name, PinDirection.INTERNAL, desc)

    addInput, addOutput, addInternal = add_input, add_output, add_internal

    def pins_of(self, direction: PinDirection) -> list[Pin]:
        """The pins of one direction, in declaration order."""
        return [p for p in self.pins.values() if p.direction is direction]

    def inputs(self) -> list[Pin]:
        return self.pins_of(PinDirection.INPUT)

    def outputs(self) -> list[Pin]:
        return self.pins_of(PinDirection.OUTPUT)

    def internals(self) -> list[Pin]:
        return self.pins_of(PinDirection.INTERNAL)


@dataclasses.dataclass
class CompileData:
    """What a pass may depend on when it reflects and compiles."""

    size: tuple[int, int] = (64, 64)      # per-view output size in pixels
    views: int = 1                        # view count (texture array layers)
    scene: Any = None                     # rayvr.scene.Scene or None
    caps: Any = None                      # rayvr.gpu.Capabilities or None (reflect must not need it)
    input_formats: dict = dataclasses.field(default_factory=dict)  # pin -> format of its source


class RenderData:
    """What `execute()` sees: resources by pin name, plus the frame's sizes."""

    def __init__(self, resources: dict, size: tuple[int, int], views: int):
        self._resources = resources
        self.size = size
        self.views = views

    def __getitem__(self, pin: str):
        return self._resources[pin]

    def get(self, pin: str, default=None):
        return self._resources.get(pin, default)

    def __contains__(self, pin: str) -> bool:
        return self._resources.get(pin) is not None


@dataclasses.dataclass
class RenderContext:
    """The GPU side of a frame: GL context, capabilities, scene on the GPU, views buffer, frame."""

    gl: Any                       # moderngl.Context
    caps: Any                     # rayvr.gpu.Capabilities
    scene: Any = None             # rayvr.scene.GpuScene or None
    views_buffer: Any = None      # moderngl.Buffer with the views SSBO (glsl/views.glsl)
    view_set: Any = None          # rayvr.xr.views.ViewSet of this frame
    frame_index: int = 0
    sample_index: int | None = None   # samples since the last camera or scene change (0: one
                                      # happened); None when no Renderer counts them


class RenderPass:
    """Base of every pass. Subclasses set PROPERTIES (defaults) and override the hooks."""

    PROPERTIES: dict[str, Any] = {}

    def __init__(self, props: dict | None = None, **kwargs):
        self._props = copy.deepcopy(self.PROPERTIES)
        self.name = type(self).__name__   # the graph sets the instance name on add_pass
        self.set_properties({**(props or {}), **kwargs})

    # -- properties ------------------------------------------------------------------------
    def set_properties(self, props: dict) -> None:
        for key, value in props.items():
            if key not in self._props:
                raise OptionError(
                    f"pass {self.name}: unknown property '{key}'{did_you_mean(key, self._props)}; "
                    f"known: {', '.join(self._props) or '(none)'}")
            self._props[key] = self.validate_property(key, value)
        self.on_properties_changed()

    def validate_property(self, key: str, value):
        """Check and normalise one property value; raise OptionError naming the pass and key."""
        default = self.PROPERTIES[key]
        if isinstance(default, bool) and not isinstance(value, bool):
            raise OptionError(f"pass {self.name}: property '{key}' must be true or false, got {value!r}")
        if isinstance(default, (int, float)) and not isinstance(default, bool):
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise OptionError(f"pass {self.name}: property '{key}' must be a number, got {value!r}")
            return type(default)(value) if isinstance(default, float) else value
        if isinstance(value, enum.Enum):
            return value.name.lower()
        return value

    def get_properties(self) -> dict:
        """Properties as plain JSON-able values; `type(p)(p.get_properties())` rebuilds the pass."""
        return copy.deepcopy(self._props)

    def on_properties_changed(self) -> None:
        """Hook for passes that derive state from properties."""

    def __getattr__(self, key):
        props = self.__dict__.get("_props")
        if props is not None and key in props:
            return props[key]
        raise AttributeError(f"{type(self).__name__} has no attribute or property '{key}'")

    # -- the pass's life ---------------------------------------------------------------------
    def reflect(self, cd: CompileData) -> Reflection:
        """Declare pins. Pure: depends only on properties and `cd`."""
        return Reflection()

    def skip_reason(self, cd: CompileData) -> str | None:
        """Why this pass has nothing to do for this scene (e.g. no material uses its effect)."""
        return None

    def compile(self, ctx: RenderContext, cd: CompileData) -> None:
        """Build programs and pass-owned GPU objects. Called once per graph compile."""

    def execute(self, ctx: RenderContext, data: RenderData) -> None:
        """Bind and dispatch. Must not allocate GPU memory."""

    def defines(self) -> dict:
        """`#define`s this pass compiles its shaders with (shown in the compile report)."""
        return {}

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self._props})"
