"""BVH8: a BVH2 collapsed into 8-wide nodes with 8-bit child boxes, after Ylitie, Karras & Laine
2017 ("Efficient Incoherent Ray Traversal on GPUs Through Compressed Wide BVHs").

The collapse is bvh_wide's SAH-optimal one at width 8. Each node then places its children in
slots by direction: slot s lies towards (+-1, +-1, +-1) with bit k of s giving the sign of axis k,
children assigned greedily by the dot product of their centre's offset from the node's centre
with their slot's direction. A ray whose direction has signs `oct` (bit k set: axis k negative)
visits slot r ^ oct as its r-th child, which orders the children roughly near to far with no sort.
A node's internal children are stored consecutively from `child_base` in slot order, and the
triangles of its leaves consecutively from `tri_base` (this BVH's own slot order, `order`), so a
node names all its children with two indices and one byte each. 80 bytes = 5 vec4:

    vec4(origin.xyz, exponents | imask << 24)   uvec4(child_base, tri_base, meta 0..3, meta 4..7)
    uvec4(lo.x 0..3, lo.x 4..7, hi.x 0..3, hi.x 4..7)   the same for y   the same for z

origin and exponents are bvh4q's grid (bvh_wide.quantize_grid: child plane = origin + q * 2**e,
a box that holds the exact one, decoded bit for bit as the shader does); imask has bit s set when
slot s is an internal node (the `popcount(imask & ((1 << s) - 1))`-th child from child_base); a
leaf's meta byte is count << 5 | offset (its triangles are tri_base + offset ..., count 1..4, so
a node's 8 leaves fit a 32-bit triangle mask); meta 0 and no imask bit: an empty slot (its box
inverted, lo 255 and hi 0). Leaves of the source must hold at most MAX_LEAF triangles.

As a TLAS (`tlas_nodes`) tri_base indexes a table of instance ids appended after the nodes (uint
index into the buffer), since a node's instances are not consecutive ones. `Bvh8` reads the child
boxes from its source BVH2, so a refit of the source shows in `nodes`.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from ..errors import SceneError
from . import bvh_wide
from .bvh import Bvh

WIDTH = 8
NODE_FLOATS = 20
NODE_BYTES = NODE_FLOATS * 4
MAX_LEAF = 4       # triangles per leaf: 8 leaves x 4 fill the shader's 32-bit triangle mask
# slot s's direction: axis k positive when bit k of s is set
SLOT_DIRECTIONS = np.array([[1.0 if s >> k & 1 else -1.0 for k in range(3)] for s in range(WIDTH)])


@dataclasses.dataclass
class Bvh8(bvh_wide.WideBvh):
    """A BVH8 over the leaves of its source BVH2 (see the module docstring). `slots` and `items`
    are bvh_wide's, per direction slot; the triangle order is this BVH's own."""

    def __post_init__(self):
        live = self.slots >= 0
        leaf = live & ((self.items & bvh_wide.LEAF_BIT) != 0)
        self.inner = live & ~leaf
        count = np.where(leaf, ((self.items >> np.uint32(28)) & 7).astype(np.int64) + 1, 0)
        if (count > MAX_LEAF).any():
            raise SceneError(f"bvh8: a leaf of {int(count.max())} triangles; the 8-wide layout takes leaves of at "
                             f"most {MAX_LEAF} (build with leaf_size <= {MAX_LEAF})")
        offset = np.cumsum(count, axis=1) - count
        total = count.sum(axis=1)
        self.tri_base = np.cumsum(total) - total
        self.meta = np.where(leaf, (count << 5) | offset, 0).astype(np.uint32)
        self.imask = (self.inner.astype(np.uint32) << np.arange(WIDTH, dtype=np.uint32)).sum(axis=1, dtype=np.uint32)
        first_inner = np.argmax(self.inner, axis=1)
        self.child_base = np.where(self.inner.any(axis=1), self.items[np.arange(len(self.items)), first_inner], 0)
        first = (self.items & bvh_wide.LINK_MASK).astype(np.int64)[leaf]
        n = count[leaf]
        within = np.arange(int(n.sum())) - np.repeat(np.cumsum(n) - n, n)
        self._order = self.source.order[np.repeat(first, n) + within]

    @property
    def order(self) -> np.ndarray:
        return self._order

    @property
    def node_floats(self) -> int:
        return NODE_FLOATS

    @property
    def nodes(self) -> np.ndarray:
        """(K, 20) float32 GPU nodes; uint fields hold their bits."""
        lo, hi, empty = self.exact_child_boxes()
        origin, exponent, q_lo, q_hi = bvh_wide.quantize_grid(lo, hi, empty)
        out = np.zeros((len(lo), NODE_FLOATS), np.float32)
        bits = out.view(np.uint32)
        out[:, 0:3] = origin
        bits[:, 3] = bvh_wide.exponent_word(exponent) | (self.imask << np.uint32(24))
        bits[:, 4] = self.child_base
        bits[:, 5] = self.tri_base
        bits[:, 6:8] = bvh_wide.pack_bytes(self.meta)
        for axis in range(3):
            bits[:, 8 + 4 * axis:10 + 4 * axis] = bvh_wide.pack_bytes(q_lo[:, :, axis])
            bits[:, 10 + 4 * axis:12 + 4 * axis] = bvh_wide.pack_bytes(q_hi[:, :, axis])
        return out

    def relinked(self, leaf_map, node_base: int = 0) -> np.ndarray:
        """GPU nodes placed in a larger buffer: child_base + node_base, tri_base through leaf_map,
        which must shift slots (a node's triangles stay consecutive), e.g. `slot + first`."""
        nodes = self.nodes
        bits = nodes.view(np.uint32)
        bits[:, 4] += np.where(self.imask != 0, np.uint32(node_base), np.uint32(0))
        bits[:, 5] = np.asarray(leaf_map(bits[:, 5]), np.uint32)
        return nodes

    def tlas_nodes(self, instances: np.ndarray) -> np.ndarray:
        """The nodes as a TLAS whose leaf slot s holds instance instances[s]: the instance ids
        appended as a uint table (padded to whole nodes), tri_base its uint index in the buffer."""
        nodes = self.nodes
        nodes.view(np.uint32)[:, 5] += np.uint32(nodes.size)
        table = np.zeros(-(-len(instances) // NODE_FLOATS) * NODE_FLOATS, np.uint32)
        table[:len(instances)] = instances
        return np.concatenate([nodes, table.view(np.float32).reshape(-1, NODE_FLOATS)])

    def child_boxes(self) -> tuple[np.ndarray, np.ndarray]:
        """(lo, hi) (K, 8, 3) of every child as the shader decodes them (empty slots inverted)."""
        return decode(self.nodes)


def decode(nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi) float32 (K, 8, 3) child boxes of BVH8 nodes, computed as ray_query.glsl does."""
    bits = nodes.view(np.uint32)
    planes = bvh_wide.unpack_bytes(bits[:, 8:20].reshape(-1, 3, 2, 2)).transpose(0, 3, 2, 1)   # (K, child, lo|hi, axis)
    return bvh_wide.decode_grid(nodes[:, 0:3], bits[:, 3] & np.uint32(0xFFFFFF), planes[:, :, 0], planes[:, :, 1])


def direction_slots(kids: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Each row's children (source child slots, -1 empty) placed in direction slots: greedily the
    (child, slot) pair whose centre offset from the node's centre points most along the slot's
    direction, until every child has a slot. lo, hi: boxes per source child slot (S, 3)."""
    live = kids >= 0
    k = np.maximum(kids, 0)
    c_lo, c_hi = lo[k].astype(np.float64), hi[k].astype(np.float64)
    node_lo = np.where(live[..., None], c_lo, np.inf).min(axis=1, keepdims=True)
    node_hi = np.where(live[..., None], c_hi, -np.inf).max(axis=1, keepdims=True)
    extent = np.maximum((node_hi - node_lo).max(axis=2, keepdims=True), 1e-30)
    score = ((c_lo + c_hi) - (node_lo + node_hi)) / extent @ SLOT_DIRECTIONS.T   # (n, child, slot)
    # on a grid of 2**-12 of the node's size: the ties of symmetric children stay ties (taken in
    # order) when rounding moves a centre, so a refit that scales a mesh keeps its slots
    score = np.where(live[..., None], np.round(score * 4096.0), -np.inf)
    out = np.full_like(kids, -1)
    rows = np.arange(len(kids))
    for _ in range(int(live.sum(axis=1).max(initial=0))):
        flat = score.reshape(len(kids), -1)
        pick = np.argmax(flat, axis=1)
        ok = np.isfinite(flat[rows, pick])
        child, slot = pick // WIDTH, pick % WIDTH
        r, child, slot = rows[ok], child[ok], slot[ok]
        out[r, slot] = kids[r, child]
        score[r, child, :] = -np.inf
        score[r, :, slot] = -np.inf
    return out


def collapse(b: Bvh) -> Bvh8:
    """The BVH8 of a BVH2 (see the module docstring)."""
    v = b.nodes.reshape(-1, 2, 4)                     # per child slot (2 * node + side): min row, max row
    lo, hi = v[:, 0, :3], v[:, 1, :3]
    slots, items = bvh_wide.collapse_slots(b, WIDTH, arrange=lambda kids: direction_slots(kids, lo, hi))
    return Bvh8(b, slots, items)
