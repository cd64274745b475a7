"""Command-line values shared by the `rayvr` subcommands and the benchmarks: sizes, numbers in
a range, scenes (with the loader's warnings printed once, one line each, on stderr)."""
from __future__ import annotations

import math
import re
import sys

from ..errors import OptionError
from ..gpu.bindings import BINDINGS
from ..graph_options import NONE
from ..scene.spec import load_scene_spec as load_scene_arg  # noqa: F401  (the subcommands' and benchmarks' name)

MAX_SIDE = 8192
MAX_PIXELS = 1 << 28   # views x width x height: 64 views of 2048x2048; G-buffers take ~100 bytes a pixel
MAX_VIEWS = BINDINGS["RAYVR_MAX_VIEWS"]   # the pixel lists pack the view index in 6 bits


def _bound(low, high, low_open=False, high_open=False) -> str:
    if high is None:
        return f"{'>' if low_open else '>='} {low:g}"
    if low is None:
        return f"{'<' if high_open else '<='} {high:g}"
    return f"{'>' if low_open else '>='} {low:g} and {'<' if high_open else '<='} {high:g}"


def integer(option: str, low: int, high: int | None = None):
    """An argparse `type`: an integer in [low, high]; anything else is an OptionError naming
    `option` and the range (argparse's own message would be two lines)."""
    accepted = f"an integer from {low} to {high}" if high is not None else f"an integer >= {low}"

    def parse(text):
        try:
            value = int(str(text).strip(), 10)
        except ValueError:
            raise OptionError(f"{option} {text}: expected {accepted}") from None
        if value < low or (high is not None and value > high):
            raise OptionError(f"{option} {value}: out of range; give {accepted}")
        return value

    parse.__name__ = "integer"
    return parse


def number(option: str, low=None, high=None, low_open: bool = False, high_open: bool = False, unit: str = ""):
    """An argparse `type`: a finite number in the given range (NaN and infinities are refused)."""
    accepted = f"a finite number {_bound(low, high, low_open, high_open)}{unit}" if (low, high) != (None, None) \
        else f"a finite number{unit}"

    def parse(text):
        try:
            value = float(str(text).strip())
        except ValueError:
            raise OptionError(f"{option} {text}: expected {accepted}") from None
        bad = not math.isfinite(value) or (low is not None and (value < low or (low_open and value == low))) or \
            (high is not None and (value > high or (high_open and value == high)))
        if bad:
            raise OptionError(f"{option} {text}: out of range; give {accepted}")
        return value

    parse.__name__ = "number"
    return parse


def views_count(option: str = "--views"):
    """The view count: 1..MAX_VIEWS."""
    return integer(option, 1, MAX_VIEWS)


def parse_size(text: str, option: str = "--size", views: int = 1) -> tuple[int, int]:
    """'WIDTHxHEIGHT' in pixels, each side 1..8192, and `views` of them at most MAX_PIXELS."""
    m = re.fullmatch(r"\s*(\d+)\s*[xX]\s*(\d+)\s*", str(text))
    if not m or int(m.group(1)) < 1 or int(m.group(2)) < 1:
        raise OptionError(f"{option} {text}: expected WIDTHxHEIGHT in pixels, e.g. {option} 1440x1600")
    w, h = int(m.group(1)), int(m.group(2))
    if w > MAX_SIDE or h > MAX_SIDE:
        raise OptionError(f"{option} {text}: at most {MAX_SIDE} pixels a side; use a smaller size")
    if views * w * h > MAX_PIXELS:
        raise OptionError(f"{option} {text} with --views {views}: {views * w * h} pixels in all, more than the "
                          f"{MAX_PIXELS} rayvr allocates frame buffers for; use fewer views or a smaller size")
    return w, h


def add_lighting_arguments(p) -> None:
    """--environment / --environment-strength (render, converge, tune, view, check)."""
    p.add_argument("--environment", metavar="RGB|FILE",
                   help="light from every direction: a radiance r,g,b (e.g. 1,1,1) or an equirectangular "
                        "EXR/HDR panorama (2:1); a scene with no light at all gets a neutral 1,1,1")
    p.add_argument("--environment-strength", type=number("--environment-strength", 0, 1e9), default=1.0,
                   help="multiplier of --environment (default 1)")
    p.add_argument("--light-selection", default="power", metavar="power|spatial",
                   help="how a point draws its light sample: power (default; one table over every light) or "
                        "spatial (lamps by their irradiance estimate at the point: far fewer fireflies beside "
                        "small lamps, a little more noise elsewhere)")


def apply_lighting(scene, args) -> None:
    """Give `scene` the --light-selection and --environment of `args` (if any), and say on one line of stderr when the
    scene has no light at all and renders with the neutral default environment."""
    from ..scene import DEFAULT_ENVIRONMENT, load_environment
    from ..scene.gpu_scene import GpuScene

    selection = getattr(args, "light_selection", "power")
    if selection not in GpuScene.LIGHT_SELECTIONS:
        raise OptionError(f"--light-selection {selection}: use one of {', '.join(GpuScene.LIGHT_SELECTIONS)}")
    scene.light_selection = selection
    spec = getattr(args, "environment", None)
    if spec is not None:
        scene.environment = load_environment(spec, "--environment", getattr(args, "environment_strength", 1.0))
    elif scene.lighting_environment() is DEFAULT_ENVIRONMENT:
        print(f"rayvr: warning: {scene.path or scene.name}: no light (no punctual light, environment, or emissive "
              f"material without an emissive texture); "
              f"lighting it with a neutral uniform environment of radiance 1 (--environment to choose one)",
              file=sys.stderr)


def add_trace_arguments(p) -> None:
    """--reuse, --foveation, --foveal-radius, --periphery-share (render, view): the trace decision."""
    from ..graph_options import FOVEATION, REUSE
    from ..xr import foveation

    for option in (REUSE, FOVEATION):
        p.add_argument(f"--{option.name}", choices=option.cli_choices, default=NONE,
                       help=option.cli_help())
    p.add_argument("--foveal-radius", type=number("--foveal-radius", 0, 90, low_open=True, unit=" degrees"),
                   metavar="DEG", help=f"with --foveation: the radius of full ray density about the gaze "
                                       f"(default {foveation.DEFAULT_RADIUS_DEG:g}: the central "
                                       f"{2 * foveation.DEFAULT_RADIUS_DEG:g} degrees)")
    p.add_argument("--periphery-share", type=number("--periphery-share", foveation.MIN_PERIPHERY_SHARE, 1),
                   metavar="S", help=f"with --foveation: the share of rays the far periphery keeps (default "
                                     f"{foveation.DEFAULT_PERIPHERY_SHARE:g}, at least "
                                     f"{foveation.MIN_PERIPHERY_SHARE:g})")


def trace_options(args, grid_cols: int = 0) -> dict:
    """The graph builders' reuse=, foveation= and decision= from --reuse, --foveation,
    --foveal-radius, --periphery-share (and a camera grid's columns)."""
    reuse = None if args.reuse == NONE else args.reuse
    fov = None if args.foveation == NONE else args.foveation
    decision = {}
    for flag, key, value in (("--foveal-radius", "foveal_radius_deg", args.foveal_radius),
                             ("--periphery-share", "periphery_share", args.periphery_share)):
        if value is not None:
            if fov is None:
                raise OptionError(f"{flag} shapes the foveation's fall-off; add --foveation fixed or gaze "
                                  f"(or leave {flag} out)")
            decision[key] = value
    if reuse and grid_cols:
        decision["grid_cols"] = int(grid_cols)
    return {"reuse": reuse, "foveation": fov, "decision": decision or None}


def add_pass_property_argument(p) -> None:
    """--set PASS.KEY=VALUE: any property of a pass of the graph (repeatable)."""
    p.add_argument("--set", action="append", default=[], dest="pass_properties", metavar="PASS.KEY=VALUE",
                   help="set a property of one of the graph's passes (--report lists the passes); VALUE is JSON "
                        "(4, 0.05, true, [8, 4]) or else a word; repeatable, e.g. --set Shadows.light_samples=2")


def apply_pass_properties(graph, settings: list[str]) -> None:
    """Each `PASS.KEY=VALUE` of `settings` as graph.update_pass(PASS, {KEY: VALUE}); a bad one is
    the error of the pass (or graph) behind it, naming the option."""
    import json

    from ..errors import GraphError

    for text in settings:
        target, equals, raw = text.partition("=")
        name, dot, key = target.rpartition(".")
        if not (equals and dot and name and key):
            raise OptionError(f"--set {text}: give PASS.KEY=VALUE, e.g. --set Shadows.light_samples=2")
        try:
            value = json.loads(raw)
        except json.JSONDecodeError:
            value = raw
        try:
            graph.update_pass(name, {key: value})
        except (OptionError, GraphError) as exc:
            raise type(exc)(f"--set {text}: {exc}") from None


def say_nonfinite(counts: dict[str, int]) -> None:
    """One line on stderr per pass that set non-finite samples to 0 in this render."""
    from ..rendergraph.nonfinite import nonfinite_lines

    for line in nonfinite_lines(counts):
        print(f"rayvr: warning: {line}", file=sys.stderr)
