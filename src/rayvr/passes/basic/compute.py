"""What the basic passes share: the output-image defines and the dispatch over all layers."""
from __future__ import annotations

from pathlib import Path

from ...errors import OptionError
from ...gpu import compute_program
from ...gpu.program_resources import program_resources
from ...rendergraph.formats import get_format
from ..dispatch import groups_2d

HERE = Path(__file__).resolve().parent


def storable_format(pass_name: str, prop: str, fmt: str) -> str:
    """Check that `fmt` can be written with imageStore; OptionError naming pass and property."""
    f = get_format(fmt, where=f"pass {pass_name}: property '{prop}'")
    if not f.glsl:
        raise OptionError(f"pass {pass_name}: property '{prop}' = {fmt!r} cannot be written by a compute "
                          f"shader; choose r32f or another colour format")
    return fmt


def program(gl, shader: str, fmt: str):
    """The compute program `shader` (a file beside this module) specialised for output format `fmt`."""
    f = get_format(fmt)
    return compute_program(gl, HERE / shader, {"DST_FORMAT": f.glsl, "DST_UINT": int(f.dtype == "u4")})


def run_over(prog, dst, src=None, sampler=None) -> None:
    """Dispatch `prog` over every texel of every layer of texture array `dst` (its image `dst`),
    sampling `src` (the sampler uniform `src`, with `sampler`'s filtering) when given.
    dst_image.glsl's local size is the passes' COMPUTE_GROUP; the graph makes the stores visible
    to the next reader."""
    res = program_resources(prog)
    if src is not None:
        res.texture("src", src, sampler=sampler)
    w, h, layers = dst.size
    res.image("dst", dst)
    prog.run(*groups_2d((w, h), layers))


def rgba(value, pass_name: str, prop: str) -> tuple[float, float, float, float]:
    """A colour property as 4 floats (3 values get alpha 1)."""
    try:
        v = [float(x) for x in value]
    except (TypeError, ValueError):
        v = []
    if len(v) == 3:
        v.append(1.0)
    if len(v) != 4:
        raise OptionError(f"pass {pass_name}: property '{prop}' must be [r, g, b] or [r, g, b, a], got {value!r}")
    return tuple(v)
