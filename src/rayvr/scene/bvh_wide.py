"""BVH4: a BVH2 (`bvh.Bvh`, from any builder) collapsed into 4-wide nodes, vectorised in numpy.

Each BVH4 node is one BVH2 node whose two children are opened (replaced by their own two
children, recursively) where that lowers the SAH cost, up to 4 children: leaves are pulled up
unchanged, the internal children left become BVH4 nodes. The choice is optimal for the SAH
(Ylitie, Karras & Laine 2017's dynamic program over (subtree, places left)); as leaves are
fixed, it minimises the summed area of the BVH4 nodes, i.e. the expected node visits. Nodes are
numbered one BVH4 level at a time from the root (siblings adjacent). 1M triangles: ~0.3 s.

Two GPU layouts of the same collapse (`ray_query.glsl` traverses both with RQ_BVH_WIDTH 4), the
children's boxes as struct of arrays so one vec4 (or one uint of bytes) covers all 4 children:

"bvh4", 112 bytes = 7 vec4:

    vec4 min.x  vec4 max.x  vec4 min.y  vec4 max.y  vec4 min.z  vec4 max.z  uvec4 item

"bvh4q" (RQ_BVH_QUANTIZED 1), 64 bytes = 4 vec4, child boxes on an 8-bit grid per node after
Ylitie, Karras & Laine 2017:

    vec4(origin.xyz, exponents)  uvec4(lo.x, hi.x, lo.y, hi.y)  uvec4(lo.z, hi.z, 0, 0)  uvec4 item

origin is the node's box min (float32); `exponents` holds per axis in bits 0..7, 8..15, 16..23 the
float32 exponent field of the power-of-two scale 2**e (the shader shifts it into place: exact, no
exp2). Each lo/hi word holds one byte q per child (child k in bits 8k..8k+7), and child k's plane
is origin + float(q) * scale: q * scale is exact, so one rounding of the add, fused or not, and
`decode` reproduces the GPU's box bit for bit. lo is floored and hi ceiled on the grid, then
checked in float32 and stepped until the decoded box holds the exact child box.

item (both layouts): a BVH4 node index, or a leaf as the traversal stacks it: bit 31 set, count - 1
in bits 28..30, first slot in bits 0..27 (leaves hold 1..8 slots; a TLAS leaf is one instance).
An empty child slot has item 0 (the root, never a child) and a box no ray enters: at 1e30 in
"bvh4" (like bvh.py's empty slots), inverted (lo 255, hi 0 on every axis) in "bvh4q", where the
traversal also skips item 0 (an inverted box is rejected by the slab test only up to rounding).

`WideBvh` keeps its source BVH2 and reads the boxes from it, so a refit of the source (same
topology) shows in `nodes`.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from .bvh import _EMPTY_LO, Bvh, _half_area

WIDTH = 4
NODE_FLOATS = 28                 # "bvh4"
NODE_BYTES = NODE_FLOATS * 4
QUANTIZED_NODE_FLOATS = 16       # "bvh4q"
QUANTIZED_NODE_BYTES = QUANTIZED_NODE_FLOATS * 4
LEAF_BIT = np.uint32(0x80000000)
LINK_MASK = np.uint32(0x0FFFFFFF)


@dataclasses.dataclass
class WideBvh:
    """A BVH4 over the same leaves and slot order as its source BVH2 (see the module docstring)."""

    source: Bvh
    slots: np.ndarray    # (K, 4) int64: the source's child slot (2 * node + side) of each child; -1 empty
    items: np.ndarray    # (K, 4) uint32: each child's item (node index or packed leaf); 0 when empty
    quantized: bool = False   # GPU layout: "bvh4q" (64 B nodes) or "bvh4" (112 B)

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
    def node_floats(self) -> int:
        return QUANTIZED_NODE_FLOATS if self.quantized else NODE_FLOATS

    @property
    def nbytes(self) -> int:
        return self.node_count * self.node_floats * 4

    def exact_child_boxes(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(lo, hi) float32 (K, 4, 3) of every child from the source's current boxes, and the
        (K, 4) mask of empty slots (their boxes are 1e30)."""
        v = self.source.nodes.reshape(-1, 2, 4)          # child slot, (min|max row), xyzw
        s = np.maximum(self.slots, 0)
        empty = self.slots < 0
        lo = np.where(empty[..., None], np.float32(_EMPTY_LO), v[s, 0, :3])
        hi = np.where(empty[..., None], np.float32(_EMPTY_LO), v[s, 1, :3])
        return lo, hi, empty

    @property
    def nodes(self) -> np.ndarray:
        """(K, node_floats) float32 GPU nodes of this layout; uint fields hold their bits."""
        lo, hi, empty = self.exact_child_boxes()
        if self.quantized:
            out = quantize(lo, hi, empty)
        else:
            out = np.empty((len(lo), NODE_FLOATS), np.float32)
            boxes = out[:, :24].reshape(-1, 6, 4)
            boxes[:, 0::2], boxes[:, 1::2] = lo.transpose(0, 2, 1), hi.transpose(0, 2, 1)
        out[:, -4:] = self.items.view(np.float32)
        return out

    def relinked(self, leaf_map, node_base: int = 0) -> np.ndarray:
        """GPU nodes placed in a larger buffer: node items + node_base, leaf slots (uint32)
        through leaf_map; the same contract as `Bvh.relinked`."""
        nodes = self.nodes
        items = nodes.view(np.uint32)[:, -4:]
        leaf = (items & LEAF_BIT) != 0
        inner = ~leaf & (self.slots >= 0)
        items[leaf] = (items[leaf] & ~LINK_MASK) | np.asarray(leaf_map(items[leaf] & LINK_MASK), np.uint32)
        items[inner] += np.uint32(node_base)
        return nodes

    def tlas_nodes(self, instances: np.ndarray) -> np.ndarray:
        """The nodes as a TLAS whose leaf slot s holds instance instances[s] (one per leaf)."""
        return self.relinked(lambda slot: instances[slot])

    def sah_cost(self, c_trav: float = 1.0, c_tri: float = 1.0) -> float:
        """Expected node visits (c_trav each) and triangle tests (c_tri each) per ray relative to
        the root's area, as `Bvh.sah_cost` (the leaves are the source's, so only c_trav terms differ)."""
        lo, hi, empty = self.exact_child_boxes()
        area = _half_area(lo, hi)
        leaf = (self.items & LEAF_BIT) != 0
        count = ((self.items >> np.uint32(28)) & np.uint32(7)) + 1
        root = max(float(_half_area(*self.source.bounds())), 1e-30)
        inner = ~leaf & ~empty
        return float((c_trav * (root + area[inner].sum()) + c_tri * (area * count)[leaf & ~empty].sum()) / root)

    def child_boxes(self) -> tuple[np.ndarray, np.ndarray]:
        """(lo, hi) of every child as the GPU reads it, (K, 4, 3) each: exact boxes ("bvh4", empty
        slots at 1e30) or the decoded quantised ones ("bvh4q", empty slots inverted)."""
        if self.quantized:
            return decode(self.nodes)
        lo, hi, _ = self.exact_child_boxes()
        return lo, hi


def quantize(lo: np.ndarray, hi: np.ndarray, empty: np.ndarray) -> np.ndarray:
    """(K, 16) float32 "bvh4q" nodes (item words left 0) whose decoded child boxes hold the
    float32 boxes (lo, hi) (K, 4, 3); empty slots (K, 4) get the inverted box lo 255, hi 0."""
    origin, exponent, q_lo, q_hi = quantize_grid(lo, hi, empty)
    planes = np.stack([q_lo, q_hi], axis=-1).transpose(0, 2, 3, 1)   # (K, axis, lo|hi, child)
    out = np.zeros((len(lo), QUANTIZED_NODE_FLOATS), np.float32)
    bits = out.view(np.uint32)
    out[:, 0:3] = origin
    bits[:, 3] = exponent_word(exponent)
    bits[:, 4:10] = pack_bytes(planes).reshape(-1, 6)
    return out


def quantize_grid(lo: np.ndarray, hi: np.ndarray, empty: np.ndarray):
    """The 8-bit grid of each node's child boxes (K, W, 3) float32, empty slots (K, W): the node's
    origin (K, 3) float32 (its box min), per axis the exponent e of the grid step 2**e (K, 3) and
    the children's planes q_lo, q_hi (K, W, 3) int64 in 0..255, such that origin + q * 2**e in
    float32 (`_decode_planes`) holds every live box; empty slots get q_lo 255, q_hi 0."""
    e3 = empty[..., None]
    origin = np.where(e3, np.inf, lo).min(axis=1)                     # (K, 3) float32, the node's box
    top = np.where(e3, -np.inf, hi).max(axis=1)
    exponent = _grid_exponents(origin, top)
    scale = _pow2(exponent)
    o, sc = origin[:, None, :], scale[:, None, :]
    q_lo = np.clip(np.floor((lo.astype(np.float64) - o) / sc), 0, 255).astype(np.int64)
    q_hi = np.clip(np.ceil((hi.astype(np.float64) - o) / sc), 0, 255).astype(np.int64)
    live = ~e3
    while True:   # float64 rounding can leave a plane one step inside the box: step it out
        low = live & (_decode_planes(o, sc, q_lo) > lo)
        high = live & (_decode_planes(o, sc, q_hi) < hi)
        if not (low.any() or high.any()):
            break
        q_lo, q_hi = q_lo - low, q_hi + high    # q_lo 0 is origin and q_hi 255 >= top: both stop in range
    return origin, exponent, np.where(e3, 255, q_lo), np.where(e3, 0, q_hi)


def exponent_word(exponent: np.ndarray) -> np.ndarray:
    """(K,) uint32: the float32 exponent fields (e + 127) of a node's 3 grid steps in bits 0..23."""
    return ((exponent + 127).astype(np.uint32) << (np.arange(3, dtype=np.uint32) * 8)).sum(axis=1, dtype=np.uint32)


def pack_bytes(q: np.ndarray) -> np.ndarray:
    """Bytes (..., W) (W a multiple of 4) as (..., W / 4) uint32 words, byte k of a word in bits 8k..8k+7."""
    words = q.astype(np.uint32).reshape(*q.shape[:-1], -1, 4) << (np.arange(4, dtype=np.uint32) * 8)
    return words.sum(axis=-1, dtype=np.uint32)


def unpack_bytes(words: np.ndarray) -> np.ndarray:
    """pack_bytes undone: (..., n) uint32 words -> (..., 4n) bytes as uint32."""
    b = (words[..., None] >> (np.arange(4, dtype=np.uint32) * 8)) & 0xFF
    return b.reshape(*words.shape[:-1], -1)


def decode(nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi) float32 (K, 4, 3) child boxes of "bvh4q" nodes, computed as ray_query.glsl does."""
    bits = nodes.view(np.uint32)
    q = unpack_bytes(bits[:, 4:10]).reshape(-1, 3, 2, WIDTH).transpose(0, 3, 2, 1)   # (K, child, side, axis)
    return decode_grid(nodes[:, 0:3], bits[:, 3], q[:, :, 0], q[:, :, 1])


def decode_grid(origin: np.ndarray, exponents: np.ndarray, q_lo: np.ndarray, q_hi: np.ndarray):
    """(lo, hi) float32 (K, W, 3) of planes q (K, W, 3) on the grids of nodes with `origin` (K, 3)
    and exponent words (K,) (bits 0..23, see exponent_word), as the shader decodes them."""
    scale = ((exponents[:, None] >> (np.arange(3, dtype=np.uint32) * 8)) & 0xFF) << 23
    scale = scale.astype(np.uint32).view(np.float32)[:, None, :]
    return _decode_planes(origin[:, None, :], scale, q_lo), _decode_planes(origin[:, None, :], scale, q_hi)


def _decode_planes(origin, scale, q) -> np.ndarray:
    """origin + float(q) * scale in float32, as the shader computes it (q * scale is exact, so
    only the add rounds, whether or not the GPU fuses it)."""
    return np.asarray(origin, np.float32) + q.astype(np.float32) * np.asarray(scale, np.float32)


def _pow2(exponent: np.ndarray) -> np.ndarray:
    return np.ldexp(np.float32(1.0), exponent.astype(np.int32)).astype(np.float32)


def _grid_exponents(origin: np.ndarray, top: np.ndarray) -> np.ndarray:
    """Per node and axis the least e in [-126, 127] with origin + 255 * 2**e >= top in float32:
    255 steps of the grid span the node's box."""
    extent = top.astype(np.float64) - origin
    mant, exp = np.frexp(extent / 255.0)                 # extent / 255 = mant * 2**exp, mant in [0.5, 1)
    e = np.where(extent > 0, exp - (mant == 0.5), -126)
    e = np.clip(e, -126, 127).astype(np.int64)
    while True:
        short = _decode_planes(origin, _pow2(e), np.full(e.shape, 255)) < top
        if not short.any():
            return e
        e = e + short


def collapse(b: Bvh, quantized: bool = False) -> WideBvh:
    """The BVH4 of a BVH2 (see the module docstring), packed as "bvh4q" if quantized."""
    slots, items = collapse_slots(b, WIDTH)
    return WideBvh(b, slots, items, quantized)


def collapse_slots(b: Bvh, width: int, arrange=None) -> tuple[np.ndarray, np.ndarray]:
    """The SAH-optimal collapse of b into nodes of up to `width` children: (slots, items), each
    (K, width), as WideBvh holds them. Nodes are numbered one wide level at a time, the internal
    children of a node adjacent in the order of its slots; arrange(kids) may reorder each row's
    children (source child slots, -1 empty) before they are numbered."""
    v, link, count = b._children()
    link = link.reshape(-1).astype(np.int64)           # per child slot 2 * node + side
    count = count.reshape(-1)
    boxes = v.reshape(-1, 2, 4)
    valid = boxes[:, 0, 0] < 1e29
    internal = valid & (count == 0)
    cost, split = _optimal_splits(b, link, internal, _half_area(boxes[:, 0, :3], boxes[:, 1, :3]), width)
    wide_index = np.full(len(v), -1, np.int64)         # BVH2 node -> wide node
    levels, frontier, placed = [], np.zeros(1, np.int64), 0
    while len(frontier):
        wide_index[frontier] = placed + np.arange(len(frontier))
        placed += len(frontier)
        kids = np.full((len(frontier), width), -1, np.int64)    # child slots, each with a share of the places
        share = np.zeros_like(kids)
        kids[:, 0], kids[:, 1] = 2 * frontier, 2 * frontier + 1
        share[:, 0] = _best_pair(cost, 2 * frontier, width)[1]
        share[:, 1] = width - share[:, 0]
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
        if arrange is not None:
            kids = arrange(kids)
        levels.append(kids)
        inner = kids[kids >= 0]
        frontier = link[inner[internal[inner]]]
    slots = np.concatenate(levels)
    s = np.maximum(slots, 0)
    leaf = count[s] > 0
    leaf_item = LEAF_BIT | ((count[s].astype(np.uint32) - 1) << np.uint32(28)) | link[s].astype(np.uint32)
    items = np.where(leaf, leaf_item, wide_index[np.where(leaf, 0, link[s])].astype(np.uint32))
    return slots, np.where(slots >= 0, items, 0).astype(np.uint32)


def _optimal_splits(b: Bvh, link, internal, area, width: int):
    """Bottom-up over the BVH2 (Ylitie et al. 2017's dynamic program, one tree level at a time):
    cost[s, k], the least total area of wide nodes for child slot s's subtree given k <= width
    places in its parent, and split[s, k], the places its first child takes when s is opened
    (0: s stays one child, a wide node or a leaf). Leaves are fixed, so node area alone is the
    SAH cost that differs between collapses."""
    cost = np.zeros((len(area), width + 1))
    split = np.zeros((len(area), width + 1), np.int64)
    for level in reversed(b.levels()):
        s = (2 * level[:, None] + np.arange(2)).reshape(-1)
        s = s[internal[s]]
        opened, j = _best_pairs(cost, 2 * link[s], width)
        as_node = area[s] + opened[:, width]
        cost[s, 1] = as_node
        cost[s, 2:] = np.minimum(as_node[:, None], opened[:, 2:])
        split[s, 2:] = np.where(opened[:, 2:] < as_node[:, None], j[:, 2:], 0)
    return cost, split


def _best_pairs(cost, first, width: int):
    """For sibling slots (first, first + 1) sharing k = 2..width places: the least cost[first, j]
    + cost[first + 1, k - j] over j = 1..k-1 and that j, as (n, width + 1) arrays (columns 0, 1 unused)."""
    pair = cost[first, 1:width, None] + cost[first + 1, None, 1:width]   # (n, j - 1, m - 1)
    best = np.full((len(first), width + 1), np.inf)
    arg = np.zeros((len(first), width + 1), np.int64)
    for k in range(2, width + 1):
        js = np.arange(1, k)
        c = pair[:, js - 1, k - js - 1]
        best[:, k], arg[:, k] = c.min(axis=1), c.argmin(axis=1) + 1
    return best, arg


def _best_pair(cost, first, k: int):
    """_best_pairs for one k: the least cost and the first child's places, each (n,)."""
    best, arg = _best_pairs(cost, first, k)
    return best[:, k], arg[:, k]

