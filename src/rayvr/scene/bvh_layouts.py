"""The GPU node layouts of a BVH and how each is made from a BVH2 (any builder's `bvh.Bvh`).

"bvh2": the BVH2 itself (bvh.py, 64 B nodes); "bvh4": bvh_wide's collapse to 4-wide nodes (112 B,
float boxes); "bvh4q": the same with 8-bit boxes (64 B); "bvh8": bvh8's compressed 8-wide nodes
(80 B, 8-bit boxes, children in direction slots). `defines` are what ray_query.glsl is compiled
with to traverse a layout (GpuScene.defines carries them)."""
from __future__ import annotations

from . import bvh as bvh_mod
from . import bvh8, bvh_wide

LAYOUTS = ("bvh2", "bvh4", "bvh4q", "bvh8")
DEFAULT = "bvh4"
NODE_FLOATS = {"bvh2": bvh_mod.NODE_FLOATS, "bvh4": bvh_wide.NODE_FLOATS, "bvh4q": bvh_wide.QUANTIZED_NODE_FLOATS,
               "bvh8": bvh8.NODE_FLOATS}
DEFINES = {"bvh2": {"RQ_BVH_WIDTH": 2, "RQ_BVH_QUANTIZED": 0},
           "bvh4": {"RQ_BVH_WIDTH": 4, "RQ_BVH_QUANTIZED": 0},
           "bvh4q": {"RQ_BVH_WIDTH": 4, "RQ_BVH_QUANTIZED": 1},
           "bvh8": {"RQ_BVH_WIDTH": 8, "RQ_BVH_QUANTIZED": 1}}


def collapse_to(b: bvh_mod.Bvh, layout: str):
    """b in GPU layout `layout`: b itself ("bvh2"), a `bvh_wide.WideBvh` or a `bvh8.Bvh8`."""
    if layout == "bvh8":
        return bvh8.collapse(b)
    return b if layout == "bvh2" else bvh_wide.collapse(b, quantized=layout == "bvh4q")
