"""Workgroup shapes of the passes' compute dispatches: plain 2D tiles over every view, and the
ray passes' tiles that span several views of a camera grid (glsl/ray_group.glsl).

The ray passes take their tile and view count as properties (`tile`, `view_group`; checked here by
`check_shape`), so an experiment with another shape is a property set, not
an edit: the values reach the shaders as the RAY_GROUP_* defines."""
from __future__ import annotations

from ..errors import OptionError
from ..rendergraph.render_pass import whole_number

COMPUTE_GROUP = (8, 8)   # the local size of the passes' 2D compute shaders

# Views a ray pass's warp spans. Neighbouring views of a camera grid see nearly the same surface
# through the same pixel (exactly so on the focal plane), so a warp of a few pixels in several
# views traces more alike rays than one of more pixels in one small view. Each pass may give its
# own count to ray_group (benchmarks/RESULTS.md has the measurements behind each choice); 1: off.
VIEW_GROUP = 4
# Frames with fewer views are not grouped: stereo's two eyes see the same pixel's surface far apart.
MIN_GROUPED_VIEWS = 4


def groups_2d(size: tuple[int, int], views: int, group: tuple[int, ...] = COMPUTE_GROUP) -> tuple[int, int, int]:
    """Workgroups covering `size` pixels of every view with `group`-sized workgroups: (x, y) pixels,
    or (x, y, z) pixels by views."""
    gx, gy, gz = (*group, 1)[:3]
    return (size[0] + gx - 1) // gx, (size[1] + gy - 1) // gy, (views + gz - 1) // gz


def ray_group(views: int, tile: tuple[int, int] = COMPUTE_GROUP, view_group: int | None = None) -> tuple[int, int, int]:
    """The (x, y, views) shape of a ray pass's workgroup of tile[0] * tile[1] invocations: the tile
    shrunk (larger side first) to make room for `view_group` views (default VIEW_GROUP; fewer, a
    power of two, where the frame has fewer) when a frame has at least MIN_GROUPED_VIEWS."""
    x, y = tile
    z = 1
    want = VIEW_GROUP if view_group is None else view_group
    while z < want and 2 * z <= views and views >= MIN_GROUPED_VIEWS and x * y > 1:
        z *= 2
        if x > y:
            x //= 2
        else:
            y //= 2
    return x, y, z


def check_tile(pass_name: str, key: str, value) -> list[int]:
    """A `tile` property: [x, y] pixels, positive integers, at most 1024 invocations (the GL
    minimum of GL_MAX_COMPUTE_WORK_GROUP_INVOCATIONS). Returned as a list (it round-trips JSON)."""
    try:
        x, y = (_whole(v) for v in value)
        ok = x >= 1 and y >= 1 and x * y <= 1024
    except (TypeError, ValueError):
        ok = False
    if not ok:
        raise OptionError(f"pass {pass_name}: property '{key}' must be [x, y], two positive integers with "
                          f"x * y <= 1024 (a workgroup's pixels), got {value!r}")
    return [x, y]


def _whole(v) -> int:
    """`v` as an int when it is a whole number (the viewer's vector fields give floats)."""
    if isinstance(v, bool) or not isinstance(v, (int, float)) or int(v) != v:
        raise ValueError(v)
    return int(v)


def check_view_group(pass_name: str, key: str, value) -> int:
    """A `view_group` property: the views a workgroup spans, an integer >= 1 (1: one view)."""
    return whole_number(f"pass {pass_name}: property '{key}'", value, 1, None, "views a workgroup spans; 1: one view")


def check_shape(pass_name: str, key: str, value):
    """`value` checked when `key` names a workgroup shape property (`tile`, `view_group`, or those
    names after a prefix: `probe_tile`); any other property's value as it is."""
    if key == "tile" or key.endswith("_tile"):
        return check_tile(pass_name, key, value)
    if key == "view_group" or key.endswith("_view_group"):
        return check_view_group(pass_name, key, value)
    return value


# RenderContext.dictionary's key for the views a trace decision traces in full (TraceDecision).
SOURCE_VIEWS = "source_views"
# RenderContext.dictionary's key, true when a trace decision reuses light across the views of a
# camera grid and the ray passes that read it take one view per workgroup (TraceDecision).
ONE_VIEW_TILES = "one_view_tiles"
DITHERED_TRACE = "dithered_trace"   # ctx.dictionary: the trace decision's foveation spreads traced pixels thinly
GATHER_TILES = 8   # a ray pass's tile gather (glsl/tile_gather.glsl) where DITHERED_TRACE, with compact_tiles 0


def decision_view_group(ctx, view_group: int) -> int:
    """The views a workgroup of a pass that reads a trace decision (the ray passes, the composite)
    spans: 1 where the decision publishes ONE_VIEW_TILES, else the pass's `view_group`. A view
    that reuses another's light traces a few pixels, gathered where the source does not see its
    surface, and composites as few (SVGF spreads the rest): a tile of one view
    over a reused region has no work and leaves at once, while the same pixels of several views
    almost always hold one traced lane, which holds its warp (benchmarks/RESULTS.md, one-view
    tiles under view reuse)."""
    return 1 if ctx.dictionary.get(ONE_VIEW_TILES) else view_group


def view_order(ctx, views: int, group: tuple[int, int, int]) -> tuple[int, ...] | None:
    """The order in which a ray pass's workgroups take the views when they span several
    (group[2] > 1) and a trace decision (SOURCE_VIEWS in `ctx.dictionary`) traces some views in full
    and only a few pixels of the others: as many whole workgroups of source views as the sources
    fill go first, then every other view in grid order, so that a warp of source views has no
    mostly idle lanes. Sources that would share a workgroup with other views stay in grid order:
    a workgroup of neighbouring cameras traces nearly parallel rays, and one of scattered cameras
    costs more than the idle lanes save (benchmarks/RESULTS.md, source views first).
    None: the grid order."""
    sources = sorted(set(ctx.dictionary.get(SOURCE_VIEWS, ())))
    whole = len(sources) // group[2] * group[2] if group[2] > 1 else 0
    if whole == 0 or len(sources) >= views:
        return None
    first = set(sources[:whole])
    order = tuple(sources[:whole]) + tuple(v for v in range(views) if v not in first)
    return None if order == tuple(range(views)) else order


def ray_group_defines(group: tuple[int, int, int], order: tuple[int, ...] | None = None) -> dict:
    """The #defines glsl/ray_group.glsl reads (`order`: view_order's)."""
    defines = {"RAY_GROUP_X": group[0], "RAY_GROUP_Y": group[1], "RAY_GROUP_Z": group[2]}
    if order:
        defines["RAY_GROUP_VIEWS"] = len(order)
        defines["RAY_GROUP_VIEW_ORDER"] = f"uint[{len(order)}](" + ", ".join(f"{v}u" for v in order) + ")"
    return defines
