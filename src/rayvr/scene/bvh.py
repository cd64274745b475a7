"""BVH builds, fully vectorised in numpy (one pass over all nodes of a tree level at a time).

Two builders make the same tree shape: `lbvh` (Karras 2012: Morton-code sort, split at the
highest differing bit; fast) and `sah` (binned SAH after Wald 2007, 16 bins on 3 axes; the
quality reference). `Bvh.nodes` is the GPU layout `ray_query.glsl` traverses: a BVH2 whose
node holds both children's boxes, 64 bytes:

    vec4(child0.min, link0)  vec4(child0.max, count0)  vec4(child1.min, link1)  vec4(child1.max, count1)

(link and count are uint bits). count 0: link is a node index; count > 0: a leaf of `count`
primitives starting at `link` in the reordered primitive list (`Bvh.order`). Only internal
nodes exist on the GPU; leaves live in their parent's child slots.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from ..errors import SceneError

NODE_FLOATS = 16
NODE_BYTES = NODE_FLOATS * 4
BINS = 16
_EMPTY_LO = _EMPTY_HI = 1e30    # a point no ray with tmax <= 1e29 reaches (an inverted box would pass the slab test)


@dataclasses.dataclass
class Bvh:
    """A built BVH: GPU nodes, primitive order, and the tree kept for refits and SAH cost."""

    nodes: np.ndarray        # (M, 16) float32, link/count columns hold uint32 bits
    order: np.ndarray        # (N,) int64: primitive index of each leaf slot
    start: np.ndarray        # per tree node (internal and leaf): first slot
    end: np.ndarray
    left: np.ndarray         # child tree node, -1 for leaves
    right: np.ndarray
    level_ranges: list       # (first, last+1) tree node ids per level, root level first
    method: str

    @property
    def node_count(self) -> int:
        return len(self.nodes)

    @property
    def nbytes(self) -> int:
        return self.nodes.nbytes

    def sah_cost(self, lo: np.ndarray, hi: np.ndarray, c_trav: float = 1.0, c_tri: float = 1.0) -> float:
        """Surface-area-heuristic cost for primitive boxes (lo, hi): traversal steps + tests,
        relative to the root's area."""
        nlo, nhi = _tree_bounds(self, lo[self.order], hi[self.order])
        area = _half_area(nlo, nhi)
        leaf = self.left < 0
        root = max(area[0], 1e-30)
        return float((c_trav * area[~leaf].sum() + c_tri * (area[leaf] * (self.end - self.start)[leaf]).sum()) / root)

    def refit(self, lo: np.ndarray, hi: np.ndarray) -> None:
        """New primitive boxes (same topology, e.g. animated vertices): recompute node boxes."""
        self.nodes = _gpu_nodes(self, lo, hi)


def triangle_bounds(tris: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(T, 3, 3) triangles -> per-triangle (lo, hi) float32."""
    a, b, c = tris[:, 0], tris[:, 1], tris[:, 2]
    return np.minimum(np.minimum(a, b), c), np.maximum(np.maximum(a, b), c)


def build(lo, hi, method: str = "auto", leaf_size: int = 4, progress: bool | None = None) -> Bvh:
    """Build a BVH over primitive boxes lo, hi (N, 3). method: 'lbvh', 'sah' or 'auto'
    (SAH up to 100k primitives, LBVH beyond, where build time matters more)."""
    lo = np.ascontiguousarray(lo, dtype=np.float32)
    hi = np.ascontiguousarray(hi, dtype=np.float32)
    n = len(lo)
    if method == "auto":
        method = "sah" if n <= 100_000 else "lbvh"
    if method not in ("lbvh", "sah"):
        raise SceneError(f"bvh method: unknown {method!r}; use 'lbvh', 'sah' or 'auto'")
    if not (np.isfinite(lo).all() and np.isfinite(hi).all()):
        raise SceneError("bvh: NaN or Inf primitive bounds; remove non-finite vertices first")
    bar = None
    if progress or (progress is None and n >= 500_000):
        from tqdm import tqdm
        bar = tqdm(total=n, unit="prim", desc=f"BVH ({method})", leave=False)
    centroid = (lo + hi) * 0.5
    if method == "lbvh":
        codes = _morton_codes(centroid)
        order = np.argsort(codes).astype(np.int64)
        splitter = _LbvhSplitter(codes[order])
    else:
        order = np.arange(n, dtype=np.int64)
        splitter = _SahSplitter(order, centroid, lo, hi)
    starts, ends, lefts, rights, ranges = [], [], [], [], []
    s, e = np.array([0], np.int64), np.array([n], np.int64)
    base = 0
    while len(s):
        split = (e - s) > leaf_size
        m = splitter.split(s[split], e[split])
        nxt = base + len(s)
        left = np.full(len(s), -1, np.int64)
        right = np.full(len(s), -1, np.int64)
        k = np.arange(int(split.sum()), dtype=np.int64)
        left[split], right[split] = nxt + 2 * k, nxt + 2 * k + 1
        starts.append(s), ends.append(e), lefts.append(left), rights.append(right)
        ranges.append((base, nxt))
        if bar is not None:
            bar.update(int((e - s)[~split].sum()))
        base = nxt
        s = np.stack([s[split], m], axis=1).reshape(-1)
        e = np.stack([m, e[split]], axis=1).reshape(-1)
    if bar is not None:
        bar.close()
    if method == "sah":
        order = splitter.perm
    bvh = Bvh(np.zeros((0, NODE_FLOATS), np.float32), order, np.concatenate(starts), np.concatenate(ends),
              np.concatenate(lefts), np.concatenate(rights), ranges, method)
    bvh.nodes = _gpu_nodes(bvh, lo, hi)
    return bvh


# ---- splitters: give each node range [s, e) a split point s < m < e -----------------------------

def _expand_bits(v: np.ndarray) -> np.ndarray:
    """Spread the low 21 bits of v so two zero bits separate each (for 63-bit Morton codes)."""
    v = v.astype(np.uint64) & np.uint64(0x1FFFFF)
    for shift, mask in ((32, 0x1F00000000FFFF), (16, 0x1F0000FF0000FF), (8, 0x100F00F00F00F00F),
                        (4, 0x10C30C30C30C30C3), (2, 0x1249249249249249)):
        v = (v | (v << np.uint64(shift))) & np.uint64(mask)
    return v


def _morton_codes(centroid: np.ndarray) -> np.ndarray:
    lo, hi = centroid.min(axis=0), centroid.max(axis=0)
    q = ((centroid - lo) * ((2**21 - 1) / np.maximum(hi - lo, 1e-30))).astype(np.uint32)
    return (_expand_bits(q[:, 0]) << np.uint64(2)) | (_expand_bits(q[:, 1]) << np.uint64(1)) | _expand_bits(q[:, 2])


class _LbvhSplitter:
    def __init__(self, sorted_codes: np.ndarray):
        self.codes = sorted_codes

    def split(self, s: np.ndarray, e: np.ndarray) -> np.ndarray:
        if not len(s):
            return s
        a, b = self.codes[s], self.codes[e - 1]
        x = a ^ b
        same = x == 0
        h = np.floor(np.log2(np.maximum(x, 1).astype(np.float64))).astype(np.uint64)
        h -= ((x >> h) == 0).astype(np.uint64)          # float rounding can overshoot by one bit
        target = ((a >> h) | np.uint64(1)) << h
        m = np.searchsorted(self.codes, target, side="left").astype(np.int64)
        m = np.where(same, (s + e) // 2, m)
        return np.clip(m, s + 1, e - 1)


def _half_area(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    d = np.maximum(hi - lo, 0.0).astype(np.float64)
    return d[..., 0] * d[..., 1] + d[..., 1] * d[..., 2] + d[..., 2] * d[..., 0]


class _SahSplitter:
    """Binned SAH over all nodes of a level at once; reorders `perm` within each node's range."""

    def __init__(self, perm, centroid, lo, hi):
        self.perm, self.centroid, self.lo, self.hi = perm, centroid, lo, hi

    def split(self, s: np.ndarray, e: np.ndarray) -> np.ndarray:
        nseg = len(s)
        if not nseg:
            return s
        cnt = e - s
        seg_first = np.cumsum(cnt) - cnt
        seg = np.repeat(np.arange(nseg), cnt)
        pos = np.arange(int(cnt.sum()), dtype=np.int64) - seg_first[seg] + s[seg]
        prim = self.perm[pos]
        c = self.centroid[prim]
        cmin = np.minimum.reduceat(c, seg_first, axis=0)
        cmax = np.maximum.reduceat(c, seg_first, axis=0)
        scale = BINS / np.maximum(cmax - cmin, 1e-30)
        b = np.clip(((c - cmin[seg]) * scale[seg]).astype(np.int64), 0, BINS - 1)
        plo_t = np.ascontiguousarray(self.lo[prim].T)
        phi_t = np.ascontiguousarray(self.hi[prim].T)
        best = np.full(nseg, np.inf)
        best_axis = np.zeros(nseg, np.int64)
        best_k = np.zeros(nseg, np.int64)
        for axis in range(3):
            key = seg * BINS + b[:, axis]
            n_bin = np.bincount(key, minlength=nseg * BINS).reshape(nseg, BINS)
            blo = np.full((3, nseg * BINS), np.inf, np.float32)
            bhi = np.full((3, nseg * BINS), -np.inf, np.float32)
            for c in range(3):   # 1-D ufunc.at is many times faster than on rows
                np.minimum.at(blo[c], key, plo_t[c])
                np.maximum.at(bhi[c], key, phi_t[c])
            blo = blo.reshape(3, nseg, BINS).transpose(1, 2, 0)
            bhi = bhi.reshape(3, nseg, BINS).transpose(1, 2, 0)
            l_area = _half_area(np.minimum.accumulate(blo, axis=1), np.maximum.accumulate(bhi, axis=1))
            r_area = _half_area(np.minimum.accumulate(blo[:, ::-1], axis=1)[:, ::-1],
                                np.maximum.accumulate(bhi[:, ::-1], axis=1)[:, ::-1])
            l_n = np.cumsum(n_bin, axis=1)
            r_n = l_n[:, -1:] - l_n + n_bin
            with np.errstate(invalid="ignore"):
                cost = l_area[:, :-1] * l_n[:, :-1] + r_area[:, 1:] * r_n[:, 1:]
            cost = np.where((l_n[:, :-1] > 0) & (r_n[:, 1:] > 0), cost, np.inf)
            k = np.argmin(cost, axis=1)
            ck = cost[np.arange(nseg), k]
            better = ck < best
            best = np.where(better, ck, best)
            best_axis = np.where(better, axis, best_axis)
            best_k = np.where(better, k, best_k)
        valid = np.isfinite(best)
        local = pos - s[seg]
        goes_left = np.where(valid[seg], b[np.arange(len(b)), best_axis[seg]] <= best_k[seg],
                             local < (cnt // 2)[seg])
        gl = goes_left.astype(np.int64)
        csum = np.cumsum(gl)
        excl = csum - gl
        l_rank = excl - excl[seg_first][seg]
        n_left = np.add.reduceat(gl, seg_first)
        r_rank = (local - l_rank)
        newpos = s[seg] + np.where(goes_left, l_rank, n_left[seg] + r_rank)
        self.perm[newpos] = prim
        return s + n_left


# ---- bounds and the GPU layout ----------------------------------------------------------------

def _tree_bounds(bvh: Bvh, lo_sorted: np.ndarray, hi_sorted: np.ndarray):
    """Boxes of every tree node: leaves by segment reduction, then internal nodes bottom-up.
    Boxes are kept as (lo, -hi) rows so one minimum does both ends."""
    nb = _tree_boxes(bvh, np.concatenate([lo_sorted, -hi_sorted], axis=1))
    return nb[:, :3], -nb[:, 3:]


def _tree_boxes(bvh: Bvh, boxes_sorted: np.ndarray) -> np.ndarray:
    count = len(bvh.start)
    nb = np.empty((count, 6), np.float32)
    leaf = np.flatnonzero(bvh.left < 0)
    if len(boxes_sorted):
        # leaves partition the slots: order them by first slot without a sort
        owner = np.full(len(boxes_sorted), -1, np.int64)
        owner[bvh.start[leaf]] = leaf
        by_start = owner[owner >= 0]
        nb[by_start] = np.minimum.reduceat(boxes_sorted, bvh.start[by_start], axis=0)
    else:
        nb[:, :3], nb[:, 3:] = _EMPTY_LO, -_EMPTY_HI
    # a level's internal nodes have their children as consecutive pairs filling the next level
    for (first, last), (nfirst, nlast) in reversed(list(zip(bvh.level_ranges, bvh.level_ranges[1:]))):
        ids = first + np.flatnonzero(bvh.left[first:last] >= 0)
        pairs = nb[nfirst:nlast].reshape(-1, 2, 6)
        nb[ids] = np.minimum(pairs[:, 0], pairs[:, 1])
    return nb


def _gpu_nodes(bvh: Bvh, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """GPU nodes from the primitive boxes (in original order)."""
    nb = _tree_boxes(bvh, np.take(np.concatenate([lo, -hi], axis=1), bvh.order, axis=0))
    nlo, nhi = nb[:, :3], -nb[:, 3:]
    internal = np.flatnonzero(bvh.left >= 0)
    if not len(internal):   # the whole mesh fits one leaf: a root with one leaf child
        out = np.zeros((1, NODE_FLOATS), np.float32)
        bits = out.view(np.uint32)
        out[0, 0:3], out[0, 4:7] = nlo[0], nhi[0]
        bits[0, 7] = bvh.end[0] - bvh.start[0]
        out[0, 8:11], out[0, 12:15] = _EMPTY_LO, _EMPTY_HI
        if bits[0, 7] == 0:
            out[0, 0:3], out[0, 4:7] = _EMPTY_LO, _EMPTY_HI
        return out
    gpu_index = np.cumsum(bvh.left >= 0) - 1
    child = bvh.left[internal][:, None] + np.array([0, 1])     # right child = left + 1
    child = child.reshape(-1)
    box = nb[child]
    is_leaf = bvh.left[child] < 0
    out = np.empty((len(internal) * 2, 2, 4), np.float32)      # per child: (min, link), (max, count)
    bits = out.view(np.uint32)
    out[:, 0, :3] = box[:, :3]
    out[:, 1, :3] = -box[:, 3:]
    start = bvh.start[child]
    bits[:, 0, 3] = np.where(is_leaf, start, gpu_index[child])
    bits[:, 1, 3] = np.where(is_leaf, bvh.end[child] - start, 0)
    out = out.reshape(-1, NODE_FLOATS)
    return out
