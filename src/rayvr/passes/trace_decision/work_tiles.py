"""The trace decision's work tiles (glsl/work_tiles.glsl): the 8x4 tiles of one view that hold a
pixel whose light is not another view's, listed by TraceDecision where SVGF spreads reused light,
and the indirect dispatch over them of a pass whose workgroup is such a tile."""
from __future__ import annotations

from ..compaction.pixel_list import HEADER_BYTES, dispatch_list

WORK_TILES = "workTiles"
WORK_TILES_LISTED = "work_tiles_listed"   # ctx.dictionary: TraceDecision fills the list this compile
TILE = (8, 4)   # glsl/work_tiles.glsl WORK_TILE_X, WORK_TILE_Y


def work_tiles_bytes(size: tuple[int, int], views: int) -> int:
    """Bytes of a list that can hold every tile of every view."""
    return HEADER_BYTES + 4 * (-(-size[0] // TILE[0])) * (-(-size[1] // TILE[1])) * views


def add_input(r, cd) -> None:
    """Declare the optional `workTiles` input (TraceDecision.workTiles)."""
    r.add_input(WORK_TILES, "the tiles that hold a pixel whose light is not another view's (TraceDecision)"
                ).buffer(work_tiles_bytes(cd.size, cd.views)).indirect().optional()


def usable(ctx, cd, group: tuple[int, int, int]) -> bool:
    """Whether a pass with workgroups of `group` (x, y, views) runs over the bound list: the
    decision fills it (its `work_tiles`) and the pass's workgroup is the list's tile."""
    return (WORK_TILES in cd.input_formats and bool(ctx.dictionary.get(WORK_TILES_LISTED))
            and tuple(group) == (*TILE, 1))


def run(res, buffer) -> None:
    """Bind the list to program `res` (block WorkTiles) and dispatch it, a workgroup a tile."""
    dispatch_list(res, "WorkTiles", buffer)
