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
import math
from collections.abc import Mapping
from typing import Any, NamedTuple

from ..errors import OptionError, did_you_mean
from .formats import get_format


def whole_number(where: str, value, least: int, most: int | None = None, what: str = "") -> int:
    """`value` as an int when it is a whole number from `least` to `most` (None: no bound), else an
    OptionError naming `where` (e.g. "pass Shadows: property 'light_samples'") and what it counts."""
    whole = not isinstance(value, bool) and isinstance(value, (int, float)) and math.isfinite(value) \
        and int(value) == value
    if not (whole and value >= least and (most is None or value <= most)):
        span = f"from {least} to {most}" if most is not None else f">= {least}"
        raise OptionError(f"{where} must be an integer {span}" + (f" ({what})" if what else "") + f", got {value!r}")
    return int(value)


class Choice(NamedTuple):
    """One name of a choice property (RenderPass.CHOICES) that its shaders see as a number."""

    meaning: str   # shown in the refusal of another value ("" for none)
    define: int    # the value of the shader define that the pass sets from it


def choice_meaning(entry) -> str:
    """What a CHOICES entry's value says about its name: a Choice's meaning, or the text itself."""
    return entry.meaning if isinstance(entry, Choice) else str(entry)


class PinKind(str, enum.Enum):
    TEXTURE = "texture"   # a 2D texture array, one layer per view (or `views` layers)
    BUFFER = "buffer"     # an SSBO of `byte_size` bytes


class Access(str, enum.Enum):
    """How a pass touches a pin's resource; the graph derives its memory barriers from these."""

    SAMPLED = "sampled"          # texture fetches (sampler uniforms)
    IMAGE = "image"              # image load/store
    STORAGE = "storage"          # SSBO reads/writes
    INDIRECT = "indirect"        # SSBO read as indirect dispatch arguments (and as storage)
    FRAMEBUFFER = "framebuffer"  # colour attachment of a draw (written coherently: no barrier)
    UPDATE = "update"            # a buffer the host writes (Buffer.write) after shaders wrote it


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
    access: Access | None = None      # None: the kind's default (see access_kind)

    @property
    def access_kind(self) -> Access:
        """How the pass touches the resource: textures are sampled (inputs) or image-stored
        (outputs and internals), buffers are SSBOs, unless the pin declared otherwise."""
        if self.access is not None:
            return self.access
        if self.kind is PinKind.BUFFER:
            return Access.STORAGE
        return Access.SAMPLED if self.direction is PinDirection.INPUT else Access.IMAGE

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

    def accessed(self, how: Access | str) -> "Pin":
        """Declare how the pass touches the resource (default: see `access_kind`)."""
        self.access = Access(how)
        return self

    def indirect(self) -> "Pin":
        """A buffer input the pass dispatches indirectly from (and reads as an SSBO)."""
        return self.accessed(Access.INDIRECT)

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
        self.jitter = False   # the pass wants sub-pixel camera jitter (request_jitter)

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

    def request_jitter(self) -> "Reflection":
        """Ask for sub-pixel camera jitter in the views (a temporal pass that resolves it, TAA)."""
        self.jitter = True
        return self

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
    # what a pass's compile() publishes for the passes compiled after it (Falcor's render-graph
    # dictionary), e.g. TraceDecision's source views; one per compile of the graph
    dictionary: dict = dataclasses.field(default_factory=dict)

    def barrier(self, *accesses: Access | str) -> None:
        """A memory barrier inside a pass, between two of its own dispatches: make what the first
        wrote visible to the second's `accesses` (Access values; none: everything)."""
        self.gl.memory_barrier(barrier_bits(accesses) if accesses else self.gl.ALL_BARRIER_BITS)


# glMemoryBarrier bits that make shader writes visible to each kind of later access.
_BARRIER_BITS = {
    Access.SAMPLED: 0x00000008,      # GL_TEXTURE_FETCH_BARRIER_BIT
    Access.IMAGE: 0x00000020,        # GL_SHADER_IMAGE_ACCESS_BARRIER_BIT
    Access.STORAGE: 0x00002000,      # GL_SHADER_STORAGE_BARRIER_BIT
    Access.INDIRECT: 0x00002040,     # + GL_COMMAND_BARRIER_BIT
    Access.FRAMEBUFFER: 0x00000400,  # GL_FRAMEBUFFER_BARRIER_BIT
    Access.UPDATE: 0x00000200,       # GL_BUFFER_UPDATE_BARRIER_BIT
}
# What a reader outside the graph may do with a marked output: read it back (glGetTexImage,
# GL_TEXTURE_UPDATE_BARRIER_BIT), sample or copy it (a sink), blit it.
HOST_READ_BITS = 0x00000100 | 0x00000008 | 0x00000400 | 0x00000020 | 0x00000200 | 0x00000080


def barrier_bits(accesses) -> int:
    """The glMemoryBarrier bits for later accesses of the given kinds."""
    bits = 0
    for a in accesses:
        bits |= _BARRIER_BITS[Access(a)]
    return bits


class RenderPass:
    """Base of every pass. Subclasses set PROPERTIES (defaults) and override the hooks.

    `USES_SCENE`: the pass reads the GPU scene and the views (ray queries, materials, lights): the
    graph refuses to compile it without a scene and binds both before it runs. Shaders live
    beside the pass's module (`compute_program(gl, "name.comp")`). GPU objects a pass makes in
    compile() go through `own()`, and the graph frees them (`release()`) on recompile and close.
    """

    PROPERTIES: dict[str, Any] = {}
    USES_SCENE = False
    # The pass's shaders scrub non-finite radiance with glsl/nonfinite.glsl: the graph gives it a
    # GPU counter (rendergraph.nonfinite) and binds it before execute().
    COUNTS_NONFINITE = False
    # The pass traces rays for the views' pixels: its programs count them per view
    # (rendergraph.ray_counters; RQ_COUNT_RAYS and glsl/ray_counters.glsl), the profile's rays_per_view.
    COUNTS_RAYS = False
    # Properties that take one of a few names: key -> the names, or {name: what it means}, or
    # {name: Choice(meaning, define)} where the shaders see the name as a number (choice_define).
    # validate_property refuses any other value (one message for every pass), and the viewer's
    # property panel offers them.
    CHOICES: dict = {}
    # Properties that count something: key -> (least, most or None for no bound, what is counted).
    # validate_property refuses anything but a whole number in range (one message for every pass)
    # and gives it as an int.
    WHOLE: dict[str, tuple] = {}

    def __init__(self, props: dict | None = None, **kwargs):
        self._props = copy.deepcopy(self.PROPERTIES)
        self.name = type(self).__name__   # the graph sets the instance name on add_pass
        self._owned: list = []
        if props is not None and not isinstance(props, Mapping):
            raise OptionError(f"pass {self.name}: properties must be a dict of name: value, got {props!r}")
        self.set_properties({**(props or {}), **kwargs})

    # -- properties ------------------------------------------------------------------------
    def set_properties(self, props: dict) -> None:
        if not isinstance(props, Mapping):
            raise OptionError(f"pass {self.name}: properties must be a dict of name: value, got {props!r}")
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
            if isinstance(value, float) and not math.isfinite(value):
                raise OptionError(f"pass {self.name}: property '{key}' must be a finite number, got {value!r}")
            if key in self.WHOLE:
                return whole_number(f"pass {self.name}: property '{key}'", value, *self.WHOLE[key])
            return type(default)(value) if isinstance(default, float) else value
        if isinstance(value, enum.Enum):
            value = value.name.lower()
        if key in self.CHOICES:
            self._check_choice(key, value)
        return value

    def _check_choice(self, key: str, value) -> None:
        choices = self.CHOICES[key]
        if isinstance(value, str) and value in choices:
            return
        meanings = {c: choice_meaning(choices[c]) if isinstance(choices, dict) else "" for c in choices}
        named = [f"'{c}'" + (f" ({meanings[c]})" if meanings[c] else "") for c in choices]
        listed = named[0] if len(named) == 1 else ", ".join(named[:-1]) + " or " + named[-1]
        raise OptionError(f"pass {self.name}: property '{key}' is {value!r}; use {listed}")

    def choice_define(self, key: str) -> int:
        """The shader define value of choice property `key`'s current name (its Choice)."""
        return self.CHOICES[key][self._props[key]].define

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
        """Bind and dispatch. Must not allocate GPU memory. The graph issues the memory barriers
        between passes; a pass with several dispatches orders its own (`ctx.barrier`)."""

    def release(self) -> None:
        """Free the GPU objects compile() made (everything passed through `own()`)."""
        owned = self.__dict__.get("_owned") or []
        for obj in reversed(owned):
            obj.release()
        owned.clear()

    def own(self, obj):
        """Record a GPU object this pass made (buffer, sampler, framebuffer...) for `release()`."""
        self.__dict__.setdefault("_owned", []).append(obj)
        return obj

    # -- shaders beside the pass ---------------------------------------------------------------
    @classmethod
    def shader_path(cls, name: str):
        """The path of shader `name` in the folder of the module that defines the pass."""
        import sys
        from pathlib import Path

        return Path(sys.modules[cls.__module__].__file__).resolve().parent / name

    def compute_program(self, gl, name: str, defines: dict | None = None, header: str = ""):
        """The (cached) compute program of shader `name` beside the pass, with `defines` (and
        `header`, raw GLSL after #version: extension directives); a pass that COUNTS_RAYS compiles with
        RQ_COUNT_RAYS."""
        from ..gpu.shaders import compute_program

        if self.COUNTS_RAYS:
            from .ray_counters import SHADER_HEADER, SLOTS

            defines, header = {**(defines or {}), "RQ_COUNT_RAYS": 1, "RAY_COUNT_SLOTS": SLOTS}, header + SHADER_HEADER
        return compute_program(gl, self.shader_path(name), defines, header=header)

    def raster_program(self, gl, vertex: str, fragment: str, defines: dict | None = None):
        """The (cached) vertex + fragment program of the shaders beside the pass."""
        from ..gpu.shaders import raster_program

        return raster_program(gl, self.shader_path(vertex), self.shader_path(fragment), defines)

    def defines(self) -> dict:
        """`#define`s this pass compiles its shaders with (shown in the compile report)."""
        return {}

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self._props})"
