"""The ready-made graphs' options, declared once: each option with its choices, what each
choice needs and whether it fits a frame budget, and each graph builder with the options it takes.

`rayvr.graphs.BUILDERS` is the table of builders. The command line's choices and help, the
viewer's graph names, the error study's rows and the tuner's option sets are read from it, so a
new denoiser is one `Choice` in `DENOISE` (and its branch where the graphs wire it), a way of
sampling direct light one in `DIRECT`.
"""
from __future__ import annotations

import dataclasses
import inspect
import itertools
from collections.abc import Callable

from .errors import OptionError

NONE = "none"   # every option's "off" spelling on the command line; None in Python


@dataclasses.dataclass(frozen=True)
class Choice:
    """One value of a graph option. `realtime`: it fits a frame budget (the tuner tries it; an
    offline denoiser does not). `requires(where)`: raises OptionError naming `where` and the
    install when what the choice needs is missing (None: nothing extra)."""

    value: str
    help: str
    realtime: bool = True
    requires: Callable[[str], object] | None = None

    def require(self, where: str) -> None:
        """OptionError naming `where` when what this choice needs is missing."""
        if self.requires is not None:
            self.requires(where)

    def available(self) -> bool:
        """Whether what this choice needs is installed."""
        try:
            self.require(self.value)
        except OptionError:
            return False
        return True


@dataclasses.dataclass(frozen=True)
class GraphOption:
    """A keyword of the graph builders whose value is one of `choices` or None (off): its
    command-line flag is `--<name>` with 'none' for off, `help` says what it does."""

    name: str
    help: str
    choices: tuple[Choice, ...]

    @property
    def values(self) -> tuple[str, ...]:
        return tuple(c.value for c in self.choices)

    @property
    def cli_choices(self) -> tuple[str, ...]:
        """The command line's values: 'none' first."""
        return (NONE, *self.values)

    def cli_help(self, default: str = NONE) -> str:
        """The command line's help: every value and what it does, and the default."""
        listed = "; ".join([NONE, *(f"{c.value} ({c.help})" for c in self.choices)])
        return f"{self.help}: {listed}; default {default}" if self.help else f"{listed}; default {default}"

    def either(self) -> str:
        """The values quoted, for a message: "'svgf' or 'oidn'", "'a', 'b' or 'c'"."""
        quoted = [f"'{v}'" for v in self.values]
        return " or ".join([", ".join(quoted[:-1]), quoted[-1]] if len(quoted) > 1 else quoted)

    def __getitem__(self, value: str) -> Choice:
        return next(c for c in self.choices if c.value == value)

    def realtime_values(self) -> tuple[str, ...]:
        """The values that fit a frame budget and whose needs are installed."""
        return tuple(c.value for c in self.choices if c.realtime and c.available())

    def available_values(self) -> tuple[str, ...]:
        """The values whose needs are installed."""
        return tuple(c.value for c in self.choices if c.available())

    def is_realtime(self, value) -> bool:
        """Whether `value` (None and 'none' are off) fits a frame budget."""
        return value in (None, NONE) or (value in self.values and self[value].realtime)


def _require_pyoidn(where: str):
    from .passes.oidn import require_pyoidn

    return require_pyoidn(where)


DENOISE = GraphOption("denoise", "", (
    Choice("svgf", "SVGF + TAA over the frames, real time"),
    Choice("oidn", "Intel Open Image Denoise on the last frame, offline: needs rayvr[oidn]", realtime=False,
           requires=_require_pyoidn),
))
GI = GraphOption("gi", "indirect light for RASTER, SHADOWS and REFLECTIONS materials", (
    Choice("probes", "irradiance probes ray traced once per frame for all views"),
))
DIRECT = GraphOption("direct", "how SHADOWS materials and above sample direct light (none: the light table's "
                                "light_samples per pixel)", (
    Choice("restir", "ReSTIR: candidates from the light table resampled over space, time and the views"),
))
REUSE = GraphOption("reuse", "which pixels trace their own rays across views", (
    Choice("views", "views take the shaded light of the same surface in a nearby source view where its "
                    "lobe is rough or wide against the eyes' parallax; disocclusions and narrow lobes are traced"),
))
FOVEATION = GraphOption("foveation", "fewer rays where the eye does not look", (
    Choice("fixed", "the ray budget falls with the angle from each view's centre"),
    Choice("gaze", "the ray budget falls with the angle from where the eye tracker says the eye looks"),
))
OPTIONS = (GI, DENOISE, DIRECT)   # the options the tuner tries
TRACE_OPTIONS = (REUSE, FOVEATION)   # the trace decision's (rayvr.passes.TraceDecision)


def trace_choice(option: GraphOption, value, where: str) -> str | None:
    """`value` of REUSE or FOVEATION checked: None for off (None or 'none'), else one of its values."""
    if value is None or value == NONE:
        return None
    if value not in option.values:
        raise OptionError(f"{where}({option.name}={value!r}): use None ('none') or {option.either()}")
    return value


class _FromPreset:
    """The default of a graph option that its preset decides (a singleton: FROM_PRESET)."""

    def __repr__(self) -> str:
        return "FROM_PRESET"


FROM_PRESET = _FromPreset()

# Named configurations of the hybrid graph; an option a call does not give takes its preset's value.
# "clean" is what a user should see by default: indirect light from the probes and every ray-traced
# term denoised and accumulated over frames, so a still view converges (the least error per frame
# budget measured: benchmarks/RESULTS.md). "raw" is the bare pipeline: each frame's own light, no
# indirect light for RASTER, SHADOWS and REFLECTIONS materials, nothing carried across frames.
PRESETS = {
    "clean": {"gi": "probes", "denoise": "svgf", "taa": True},
    "raw": {"gi": None, "denoise": None, "taa": False},
}
DEFAULT_PRESET = "clean"


def preset_options(preset: str, where: str = "hybrid", given: dict | None = None, **options) -> dict:
    """`given` and `options` ({option: value}) with each value left FROM_PRESET taken from `preset`
    (a name of PRESETS); OptionError naming `where` for an unknown preset."""
    given = {**(given or {}), **options}
    if preset not in PRESETS:
        from .errors import did_you_mean

        raise OptionError(f"{where}(preset={preset!r}): unknown preset{did_you_mean(str(preset), PRESETS)}; use "
                          f"{' or '.join(repr(p) for p in PRESETS)}")
    return {k: PRESETS[preset].get(k) if v is FROM_PRESET else v for k, v in given.items()}


@dataclasses.dataclass(frozen=True)
class GraphBuilder:
    """A ready-made graph: its name, the function that builds it, the GraphOptions it takes,
    whether the command line and the viewer offer it by name (`--graph NAME`), and `extends`:
    the builder whose keywords `build` passes on (its **kw)."""

    name: str
    build: Callable
    options: tuple[GraphOption, ...]
    help: str
    command_line: bool = True
    extends: Callable | None = None

    def defaults(self, preset: str | None = None) -> dict:
        """Every keyword `build` takes (with those it passes on), with its default; an option its
        preset decides has the value of `preset` (default: the builder's own default preset)."""
        out = {}
        for fn in (self.extends, self.build):
            if fn is not None:
                out.update({name: p.default for name, p in inspect.signature(fn).parameters.items()
                            if p.default is not inspect.Parameter.empty})
        if any(v is FROM_PRESET for v in out.values()):
            out = preset_options(preset or out.get("preset", DEFAULT_PRESET), self.name, out)
        return out

    def takes(self, option: str) -> bool:
        return any(o.name == option for o in self.options)


def realtime_option_sets(options=OPTIONS) -> list[dict]:
    """Every combination of the options' real-time values, none first, then each alone in the
    order of `options`, then together: [{}, {'gi': 'probes'}, {'denoise': 'svgf'}, {both}]."""
    sets = []
    for combo in itertools.product(*[(None, *o.realtime_values()) for o in reversed(options)]):
        values = dict(zip([o.name for o in reversed(options)], combo))
        sets.append({o.name: values[o.name] for o in options if values[o.name] is not None})
    return sets
