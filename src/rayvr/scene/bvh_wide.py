"""BVH4: a BVH2 (`bvh.Bvh`, from any builder) collapsed into 4-wide nodes, vectorised in numpy.

Each BVH4 node is one BVH2 node whose two children are opened (replaced by their own two
children, recursively) where that lowers the SAH cost, up to 4 children: leaves are pulled up
unchanged, the internal children left become BVH4 nodes. The choice is optimal for the SAH
(Ylitie, Karras & Laine 2017's dynamic program over (subtree, places left)); as leaves are
fixed, it minimises the summed area of the BVH4 nodes, i.e. the expected node visits. Nodes are
numbered one BVH4 level at a time from the root (siblings adjacent). 1M triangles: ~0.3 s.

GPU layout (what `ray_query.glsl` traverses with RQ_BVH_WIDTH 4), 112 bytes = 7 vec4, the
children's boxes as struct of arrays so one vec4 per box plane covers all 4 children:

    vec4 min.x  vec4 max.x  vec4 min.y  vec4 max.y  vec4 min.z  vec4 max.z  uvec4 item

item: a BVH4 node index, or a leaf as the traversal stacks it: bit 31 set, count - 1 in bits
28..30, first slot in bits 0..27 (leaves hold 1..8 slots; a TLAS leaf is one instance). An
empty child slot has its box at 1e30 (like bvh.py's empty slots: no ray with tmax <= 1e29
enters it) and item 0.

`WideBvh` keeps its source BVH2 and reads the boxes from it, so a refit of the source (same
topology) shows in `nodes`.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from .bvh import _EMPTY_LO, Bvh, _half_area

WIDTH = 4
NODE_FLOATS = 28
NODE_BYTES = NODE_FLOATS * 4
LEAF_BIT = np.uint32(0x80000000)
LINK_MASK = np.uint32(0x0FFFFFFF)


@dataclasses.dataclass
class WideBvh:
    """A BVH4 over the same leaves and slot order as its source BVH2 (see the module docstring)."""

    source: Bvh
    slots: np.ndarray    # (K, 4) int64: the source's child slot (2 * node + side) of each child; -1 empty
    items: np.ndarray    # (K, 4) uint32: each child's item (node index or packed leaf); 0 when empty

    @property
    def method(self) -> str:
        return self.source.method

    @property
    def order(self) -> np.ndarray:
        return self.source.order

    @property
    def node_count(self) -> int:
        return len(self.slots)

    @property
    def nbytes(self) -> int:
        return self.node_count * NODE_BYTES

    @property
    def nodes(self) -> np.ndarray:
        """(K, 28) float32 GPU nodes, boxes from the source's current child boxes."""
        v = self.source.nodes.reshape(-1, 2, 4)          # child slot, (min|max row), xyzw
        s = np.maximum(self.slots, 0)
        empty = (self.slots < 0)[..., None]
        lo = np.where(empty, np.float32(_EMPTY_LO), v[s, 0, :3])   # (K, 4, 3)
        hi = np.where(empty, np.float32(_EMPTY_LO), v[s, 1, :3])
        out = np.empty((len(s), 7, 4), np.float32)
        out[:, 0:6:2] = lo.transpose(0, 2, 1)
        out[:, 1:6:2] = hi.transpose(0, 2, 1)
        out[:, 6] = self.items.view(np.float32)
        return out.reshape(-1, NODE_FLOATS)

    def relinked(self, leaf_map, node_base: int = 0) -> np.ndarray:
        """GPU nodes placed in a larger buffer: node items + node_base, leaf slots (uint32)
        through leaf_map; the same contract as `Bvh.relinked`."""
        nodes = self.nodes
        items = nodes.view(np.uint32)[:, 24:28]
        leaf = (items & LEAF_BIT) != 0
        inner = ~leaf & (self.slots >= 0)
        items[leaf] = (items[leaf] & ~LINK_MASK) | np.asarray(leaf_map(items[leaf] & LINK_MASK), np.uint32)
        items[inner] += np.uint32(node_base)
        return nodes

    def child_boxes(self) -> tuple[np.ndarray, np.ndarray]:
        """(lo, hi) of every child, (K, 4, 3) each (empty slots at 1e30)."""
        n = self.nodes.reshape(-1, 7, 4)
        return n[:, 0:6:2].transpose(0, 2, 1), n[:, 1:6:2].transpose(0, 2, 1)


def collapse(b: Bvh) -> WideBvh:
    """The BVH4 of a BVH2 (see the module docstring)."""
    v, link, count = b._children()
    link = link.reshape(-1).astype(np.int64)           # per child slot 2 * node + side
    count = count.reshape(-1)
    boxes = v.reshape(-1, 2, 4)
    valid = boxes[:, 0, 0] < 1e29
    internal = valid & (count == 0)
    cost, split = _optimal_splits(b, link, internal, _half_area(boxes[:, 0, :3], boxes[:, 1, :3]))
    wide_index = np.full(len(v), -1, np.int64)         # BVH2 node -> BVH4 node
    levels, frontier, placed = [], np.zeros(1, np.int64), 0
    while len(frontier):
        wide_index[frontier] = placed + np.arange(len(frontier))
        placed += len(frontier)
        kids = np.full((len(frontier), WIDTH), -1, np.int64)    # child slots, each with a share of the 4
        share = np.zeros_like(kids)
        kids[:, 0], kids[:, 1] = 2 * frontier, 2 * frontier + 1
        share[:, 0] = _best_pair(cost, 2 * frontier, WIDTH)[1]
        share[:, 1] = WIDTH - share[:, 0]
        n_kids = np.full(len(frontier), 2)
        while True:   # open the first child whose share is better spent on its two children
            j = np.where(kids >= 0, split[np.maximum(kids, 0), share], 0)
            rows = np.flatnonzero((j > 0).any(axis=1))
            if not len(rows):
                break
            p = np.argmax(j[rows] > 0, axis=1)
            opened, k, j = link[kids[rows, p]], share[rows, p], j[rows, p]
            kids[rows, p], share[rows, p] = 2 * opened, j
            kids[rows, n_kids[rows]], share[rows, n_kids[rows]] = 2 * opened + 1, k - j
            n_kids[rows] += 1
        kids = np.where(valid[np.maximum(kids, 0)], kids, -1)   # a single-leaf root's empty slot
        levels.append(kids)
        inner = kids[kids >= 0]
        frontier = link[inner[internal[inner]]]
    slots = np.concatenate(levels)
    s = np.maximum(slots, 0)
    leaf = count[s] > 0
    leaf_item = LEAF_BIT | ((count[s].astype(np.uint32) - 1) << np.uint32(28)) | link[s].astype(np.uint32)
    items = np.where(leaf, leaf_item, wide_index[np.where(leaf, 0, link[s])].astype(np.uint32))
    items = np.where(slots >= 0, items, 0).astype(np.uint32)
    return WideBvh(b, slots, items)


def _optimal_splits(b: Bvh, link, internal, area):
    """Bottom-up over the BVH2 (Ylitie et al. 2017's dynamic program, one tree level at a time):
    cost[s, k], the least total area of BVH4 nodes for child slot s's subtree given k <= 4
    places in its parent, and split[s, k], the places its first child takes when s is opened
    (0: s stays one child, a BVH4 node or a leaf). Leaves are fixed, so node area alone is the
    SAH cost that differs between collapses."""
    cost = np.zeros((len(area), WIDTH + 1))
    split = np.zeros((len(area), WIDTH + 1), np.int64)
    for level in reversed(b.levels()):
        s = (2 * level[:, None] + np.arange(2)).reshape(-1)
        s = s[internal[s]]
        best = {k: _best_pair(cost, 2 * link[s], k) for k in range(2, WIDTH + 1)}
        as_node = area[s] + best[WIDTH][0]
        cost[s, 1] = as_node
        for k, (opened, j) in best.items():
            cost[s, k] = np.minimum(as_node, opened)
            split[s, k] = np.where(opened < as_node, j, 0)
    return cost, split


def _best_pair(cost, first, k: int):
    """For sibling slots (first, first + 1) sharing k places: the least cost[first, j] +
    cost[first + 1, k - j] over j = 1..k-1, and that j."""
    c = np.stack([cost[first, j] + cost[first + 1, k - j] for j in range(1, k)], axis=1)
    return c.min(axis=1), c.argmin(axis=1) + 1


def for_width(b: Bvh, width: int):
    """The GPU layout of b for RQ_BVH_WIDTH `width`: b itself (2) or its collapse (4)."""
    return b if width == 2 else collapse(b)
