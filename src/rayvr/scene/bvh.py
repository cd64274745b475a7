"""BVH builds, fully vectorised in numpy (one pass over all nodes of a tree level at a time).

Two builders make the same tree shape: `lbvh` (Karras 2012: Morton-code sort, split at the
highest differing bit; fast) and `sah` (binned SAH after Wald 2007, 16 bins on 3 axes; the
quality reference). `Bvh.nodes` is the GPU layout `ray_query.glsl` traverses with RQ_BVH_WIDTH 2
(`bvh_wide.collapse` turns it into the BVH4 layouts "bvh4" and "bvh4q"): a BVH2 whose node holds both
children's boxes, 64 bytes:

    vec4(child0.min, link0)  vec4(child0.max, count0)  vec4(child1.min, link1)  vec4(child1.max, count1)

(link and count are uint bits). count 0: link is a node index; count > 0: a leaf of `count`
primitives starting at `link` in the reordered primitive list (`Bvh.order`); the traversal
packs a leaf as 28 bits of `link` and 3 of `count - 1`, so leaves hold 1..8 primitives and leaf
links stay below 2**28 (GpuScene checks both). Only internal
nodes exist on the GPU; leaves live in their parent's child slots. An empty child slot (only
in a root whose whole mesh is one leaf) is a box at 1e30, which no ray with tmax <= 1e29 enters.

Large LBVH builds run on a thread pool (numpy releases the GIL in its array loops): Morton
codes and gathers in slices, then the tree is split serially into ~4 chunks per thread, the
chunks are built in parallel and their GPU nodes stitched under the top nodes. Refit and SAH
cost work from the GPU nodes alone.
"""
from __future__ import annotations

import dataclasses
import os

import numpy as np

from ..errors import SceneError

NODE_FLOATS = 16
NODE_BYTES = NODE_FLOATS * 4
BINS = 16
_EMPTY_LO = _EMPTY_HI = 1e30    # a point no ray with tmax <= 1e29 reaches (an inverted box would pass the slab test)


@dataclasses.dataclass
class Bvh:
    """A built BVH: GPU nodes (see the module docstring) and the primitive order of leaf slots."""

    nodes: np.ndarray        # (M, 16) float32, link/count columns hold uint32 bits
    order: np.ndarray        # (N,) int64: primitive index of each leaf slot
    method: str
    _levels: list | None = dataclasses.field(default=None, repr=False)

    @property
    def node_count(self) -> int:
        """Internal nodes (the GPU has no leaf nodes: leaves live in their parent's child slots)."""
        return len(self.nodes)

    @property
    def nbytes(self) -> int:
        """Bytes of the GPU nodes."""
        return self.nodes.nbytes

    def _children(self):
        v = self.nodes.reshape(-1, 2, 2, 4)            # node, child, (min|max row), xyzw
        bits = v.view(np.uint32)
        return v, bits[:, :, 0, 3], bits[:, :, 1, 3]     # boxes, link, count

    def relinked(self, leaf_map, node_base: int = 0) -> np.ndarray:
        """A copy of the GPU nodes placed in a larger buffer: node links + node_base, leaf links
        (uint32 slots) through leaf_map (e.g. an offset, or the TLAS's slot -> instance)."""
        nodes = self.nodes.copy()
        bits = nodes.view(np.uint32)
        for c in (0, 8):
            leaf = bits[:, c + 7] > 0
            bits[leaf, c + 3] = leaf_map(bits[leaf, c + 3])
            bits[~leaf, c + 3] += np.uint32(node_base)
        return nodes

    def tlas_nodes(self, instances: np.ndarray) -> np.ndarray:
        """The nodes as a TLAS whose leaf slot s holds instance instances[s] (one per leaf)."""
        return self.relinked(lambda slot: instances[slot])

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """(lo, hi) float32 box of every primitive: the root's child boxes, empty slots skipped
        (node boxes are exact min/max of the primitive boxes, so this is bit-exact)."""
        root = self.nodes[0].reshape(2, 2, 4)
        valid = root[:, 0, :1] < 1e29
        return np.where(valid, root[:, 0, :3], np.inf).min(axis=0), np.where(valid, root[:, 1, :3], -np.inf).max(axis=0)

    def levels(self) -> list[np.ndarray]:
        """GPU node indices by depth, root first (children always lie deeper than parents)."""
        if self._levels is None:
            _, link, count = self._children()
            levels, frontier = [], np.array([0], np.int64)
            while len(frontier):
                levels.append(frontier)
                c_link, c_count = link[frontier], count[frontier]
                internal = (c_count == 0) & (self.nodes.reshape(-1, 2, 8)[frontier, :, 0] < 1e29)
                frontier = c_link[internal].astype(np.int64)
            self._levels = levels
        return self._levels

    def sah_cost(self, lo=None, hi=None, c_trav: float = 1.0, c_tri: float = 1.0) -> float:
        """Surface-area-heuristic cost: expected traversal steps (c_trav per internal node) and
        triangle tests (c_tri each) per ray, relative to the root's area. lo/hi: unused
        (the node boxes are exact), kept for symmetry with build()."""
        v, link, count = self._children()
        valid = v[:, :, 0, 0] < 1e29
        area = _half_area(v[:, :, 0, :3], v[:, :, 1, :3])
        root = max(float(_half_area(*self.bounds())), 1e-30)
        inner = valid & (count == 0)
        return float((c_trav * (root + area[inner].sum()) + c_tri * (area * count)[valid & (count > 0)].sum()) / root)

    def refit(self, lo: np.ndarray, hi: np.ndarray) -> None:
        """New primitive boxes (same topology, e.g. animated vertices): recompute node boxes."""
        boxes = np.take(np.concatenate([np.asarray(lo, np.float32), -np.asarray(hi, np.float32)], axis=1),
                        self.order, axis=0)
        v, link, count = self._children()
        v = v.copy()
        leaf = count > 0
        node_i, child_i = np.nonzero(leaf)
        starts = link[leaf].astype(np.int64)
        owner = np.full(len(boxes), -1, np.int64)
        owner[starts] = np.arange(len(starts))
        by_start = owner[owner >= 0]
        red = np.minimum.reduceat(boxes, starts[by_start], axis=0)
        v[node_i[by_start], child_i[by_start], 0, :3] = red[:, :3]
        v[node_i[by_start], child_i[by_start], 1, :3] = -red[:, 3:]
        for level in reversed(self.levels()):
            for c in (0, 1):
                kids = level[(count[level, c] == 0) & (v[level, c, 0, 0] < 1e29)]
                k = link[kids, c].astype(np.int64)
                v[kids, c, 0, :3] = np.minimum(v[k, 0, 0, :3], v[k, 1, 0, :3])
                v[kids, c, 1, :3] = np.maximum(v[k, 0, 1, :3], v[k, 1, 1, :3])
        self.nodes = v.reshape(-1, NODE_FLOATS)


def triangle_bounds(tris: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(T, 3, 3) triangles -> per-triangle (lo, hi) float32."""
    a, b, c = tris[:, 0], tris[:, 1], tris[:, 2]
    return np.minimum(np.minimum(a, b), c), np.maximum(np.maximum(a, b), c)


PARALLEL_MIN = 200_000   # below this the threaded LBVH is not worth its stitching


MAX_LEAF_SIZE = 8    # ray_query.glsl packs count - 1 into 3 bits
MAX_LEAF_LINK = 1 << 28


def build(lo, hi, method: str = "auto", leaf_size: int = 4, progress: bool | None = None,
          threads: int | None = None) -> Bvh:
    """Build a BVH over primitive boxes lo, hi (N, 3). method: 'lbvh', 'sah' or 'auto'
    (SAH up to 100k primitives, LBVH beyond, where build time matters more). Large LBVH builds
    run their subtrees on `threads` threads (default: all cores; numpy releases the GIL)."""
    lo = np.ascontiguousarray(lo, dtype=np.float32)
    hi = np.ascontiguousarray(hi, dtype=np.float32)
    n = len(lo)
    if method == "auto":
        method = "sah" if n <= 100_000 else "lbvh"
    if not 1 <= leaf_size <= MAX_LEAF_SIZE:
        raise SceneError(f"bvh leaf_size: {leaf_size} is outside 1..{MAX_LEAF_SIZE} (the GPU node packs "
                         f"count - 1 in 3 bits); pass a leaf_size in that range")
    if method not in ("lbvh", "sah"):
        raise SceneError(f"bvh method: unknown {method!r}; use 'lbvh', 'sah' or 'auto'")
    if not (np.isfinite(lo).all() and np.isfinite(hi).all()):
        raise SceneError("bvh: NaN or Inf primitive bounds; remove non-finite vertices first")
    bar = None
    if progress or (progress is None and n >= 500_000):
        from tqdm import tqdm
        bar = tqdm(total=n, unit="prim", desc=f"BVH ({method})", leave=False)
    try:
        centroid = (lo + hi) * 0.5
        if method == "sah":
            tree = _Tree.build(_SahSplitter(np.arange(n, dtype=np.int64), centroid, lo, hi), n, leaf_size, bar)
            order = tree.splitter.perm
            return Bvh(tree.gpu_nodes(np.take(np.concatenate([lo, -hi], axis=1), order, axis=0)), order, method)
        threads = threads or os.cpu_count() or 1
        if threads > 1 and n >= PARALLEL_MIN:
            from concurrent.futures import ThreadPoolExecutor

            with ThreadPoolExecutor(max_workers=threads) as pool:
                order, codes, boxes = _sorted_inputs(lo, hi, centroid, pool, threads)
                nodes = _parallel_lbvh(codes, boxes, leaf_size, threads, bar, pool)
        else:
            order, codes, boxes = _sorted_inputs(lo, hi, centroid)
            nodes = _Tree.build(_LbvhSplitter(codes), n, leaf_size, bar).gpu_nodes(boxes)
        return Bvh(nodes, order, method)
    finally:
        if bar is not None:
            bar.close()


class _Tree:
    """The level-by-level tree of one build: node ranges [start, end) of leaf slots, children
    (consecutive pairs filling the next level), and per-level id ranges."""

    def __init__(self, splitter, start, end, left, ranges):
        self.splitter, self.start, self.end, self.left, self.ranges = splitter, start, end, left, ranges

    @classmethod
    def build(cls, splitter, n: int, leaf_size: int, bar=None, first: int = 0) -> "_Tree":
        starts, ends, lefts, ranges = [], [], [], []
        s, e = np.array([first], np.int64), np.array([first + n], np.int64)
        base = 0
        while len(s):
            split = (e - s) > leaf_size
            m = splitter.split(s[split], e[split])
            nxt = base + len(s)
            left = np.full(len(s), -1, np.int64)
            left[split] = nxt + 2 * np.arange(len(m), dtype=np.int64)
            starts.append(s), ends.append(e), lefts.append(left)
            ranges.append((base, nxt))
            if bar is not None:
                bar.update(int((e - s)[~split].sum()))
            base = nxt
            s = np.stack([s[split], m], axis=1).reshape(-1)
            e = np.stack([m, e[split]], axis=1).reshape(-1)
        return cls(splitter, np.concatenate(starts), np.concatenate(ends), np.concatenate(lefts), ranges)

    def boxes(self, boxes_sorted: np.ndarray, first: int = 0) -> np.ndarray:
        """(lo, -hi) boxes of every tree node: leaves by segment reduction, then bottom-up."""
        nb = np.empty((len(self.start), 6), np.float32)
        leaf = np.flatnonzero(self.left < 0)
        if len(boxes_sorted):
            owner = np.full(len(boxes_sorted), -1, np.int64)   # leaves partition the slots
            owner[self.start[leaf] - first] = leaf
            by_start = owner[owner >= 0]
            nb[by_start] = np.minimum.reduceat(boxes_sorted, self.start[by_start] - first, axis=0)
        else:
            nb[:, :3], nb[:, 3:] = _EMPTY_LO, -_EMPTY_HI
        for (lo_id, hi_id), (nlo, nhi) in reversed(list(zip(self.ranges, self.ranges[1:]))):
            ids = lo_id + np.flatnonzero(self.left[lo_id:hi_id] >= 0)
            pairs = nb[nlo:nhi].reshape(-1, 2, 6)
            nb[ids] = np.minimum(pairs[:, 0], pairs[:, 1])
        return nb

    def gpu_nodes(self, boxes_sorted: np.ndarray) -> np.ndarray:
        """GPU nodes of a whole tree from its slot-ordered (lo, -hi) primitive boxes."""
        return self.gpu_nodes_from(self.boxes(boxes_sorted), 0)

    def gpu_nodes_from(self, nb: np.ndarray, node_base: int) -> np.ndarray:
        """GPU nodes from node boxes `nb`; node links are offset by node_base, leaf links are
        the slots in `start`."""
        internal = np.flatnonzero(self.left >= 0)
        if not len(internal):   # everything in one leaf: a root with one leaf child
            out = np.zeros((1, 2, 2, 4), np.float32)
            bits = out.view(np.uint32)
            out[0, 0, 0, :3], out[0, 0, 1, :3] = nb[0, :3], -nb[0, 3:]
            bits[0, 0, 0, 3], bits[0, 0, 1, 3] = self.start[0], self.end[0] - self.start[0]
            out[0, 1, :, :3] = _EMPTY_LO
            if self.end[0] == self.start[0]:
                out[0, 0, :, :3] = _EMPTY_LO
            return out.reshape(-1, NODE_FLOATS)
        gpu_index = np.cumsum(self.left >= 0) - 1 + node_base
        child = (self.left[internal][:, None] + np.array([0, 1])).reshape(-1)   # right = left + 1
        box = nb[child]
        is_leaf = self.left[child] < 0
        out = np.empty((len(child), 2, 4), np.float32)      # per child: (min, link), (max, count)
        bits = out.view(np.uint32)
        out[:, 0, :3] = box[:, :3]
        out[:, 1, :3] = -box[:, 3:]
        start = self.start[child]
        bits[:, 0, 3] = np.where(is_leaf, start, gpu_index[child])
        bits[:, 1, 3] = np.where(is_leaf, self.end[child] - start, 0)
        return out.reshape(-1, NODE_FLOATS)


def _sorted_inputs(lo, hi, centroid, pool=None, threads: int = 1):
    """Morton order of the centroids, the sorted codes and the (lo, -hi) boxes in that order;
    the element-wise parts run in slices on `pool` when given."""
    n = len(lo)
    cmin, cmax = centroid.min(axis=0), centroid.max(axis=0)
    cuts = np.linspace(0, n, threads + 1).astype(np.int64)
    spans = list(zip(cuts[:-1], cuts[1:]))
    codes = np.empty(n, np.uint64)
    boxes_in = np.empty((n, 6), np.float32)

    def encode(span):
        a, b = span
        codes[a:b] = _morton_codes(centroid[a:b], cmin, cmax)
        boxes_in[a:b, :3], boxes_in[a:b, 3:] = lo[a:b], -hi[a:b]

    list(pool.map(encode, spans)) if pool else encode((0, n))
    order = _parallel_argsort(codes, pool) if pool else np.argsort(codes).astype(np.int64)
    sorted_codes = np.empty_like(codes)
    boxes = np.empty_like(boxes_in)

    def gather(span):
        a, b = span
        sorted_codes[a:b] = codes[order[a:b]]
        boxes[a:b] = np.take(boxes_in, order[a:b], axis=0)

    list(pool.map(gather, spans)) if pool else gather((0, n))
    return order, sorted_codes, boxes


def _parallel_argsort(codes: np.ndarray, pool) -> np.ndarray:
    """argsort of 63-bit codes: a stable radix pass on the top 8 bits, then the 256 buckets
    sorted on the pool."""
    top = (codes >> np.uint64(55)).astype(np.uint8)
    by_top = np.argsort(top, kind="stable")          # numpy sorts 8-bit keys by radix
    edges = np.concatenate([[0], np.cumsum(np.bincount(top, minlength=256))])
    bucketed = codes[by_top]
    order = np.empty(len(codes), np.int64)

    def sort_bucket(k):
        a, b = edges[k], edges[k + 1]
        if b > a:
            order[a:b] = by_top[a:b][np.argsort(bucketed[a:b])]

    list(pool.map(sort_bucket, range(256)))
    return order


def _parallel_lbvh(codes: np.ndarray, boxes: np.ndarray, leaf_size: int, threads: int, bar, pool) -> np.ndarray:
    """LBVH with its top split serially into ~4 chunks per thread, the chunks built on a thread
    pool, and the GPU nodes stitched: top nodes first, then each chunk's nodes."""
    n = len(codes)
    splitter = _LbvhSplitter(codes)
    chunk = max(n // (4 * threads), 4 * leaf_size)
    top = []                       # [start, end, child0, child1]; a child >= 0 is a top node, < 0 ~chunk
    chunks = []
    stack = [(0, n, None, 0)]
    while stack:
        s, e, parent, side = stack.pop()
        if e - s > chunk:
            idx = len(top)
            top.append([s, e, 0, 0])
            m = int(splitter.split(np.array([s]), np.array([e]))[0])
            stack += [(m, e, idx, 1), (s, m, idx, 0)]
        else:
            idx = ~len(chunks)
            chunks.append((s, e))
        if parent is not None:
            top[parent][2 + side] = idx
    if not top:
        return _Tree.build(splitter, n, leaf_size, bar).gpu_nodes(boxes)

    def job(se):
        s, e = se
        tree = _Tree.build(splitter, e - s, leaf_size, None, first=s)
        return tree, tree.boxes(boxes[s:e], first=s)

    results = list(pool.map(job, chunks))
    if bar is not None:
        bar.update(n)
    base = len(top)
    parts, roots = [], []          # each chunk: GPU nodes (or a leaf) and its box
    for (s, e), (tree, nb) in zip(chunks, results):
        roots.append((base, nb[0]))
        nodes = tree.gpu_nodes_from(nb, base) if len(tree.start) > 1 else None
        if nodes is None:          # a chunk that is a single leaf stays a leaf child
            roots[-1] = (None, nb[0])
        else:
            parts.append(nodes)
            base += len(nodes)
    top_nodes = np.zeros((len(top), 2, 2, 4), np.float32)
    bits = top_nodes.view(np.uint32)
    top_box = np.zeros((len(top), 6), np.float32)
    for t in reversed(range(len(top))):   # children have larger indices: bottom-up
        for side in (0, 1):
            c = top[t][2 + side]
            if c >= 0:
                box, link, count = top_box[c], c, 0
            else:
                node, box = roots[~c]
                s, e = chunks[~c]
                link, count = (node, 0) if node is not None else (s, e - s)
            top_nodes[t, side, 0, :3], top_nodes[t, side, 1, :3] = box[:3], -box[3:]
            bits[t, side, 0, 3], bits[t, side, 1, 3] = link, count
        top_box[t] = np.minimum(_child_box(top, top_box, roots, t, 0), _child_box(top, top_box, roots, t, 1))
    return np.concatenate([top_nodes.reshape(-1, NODE_FLOATS), *parts])


def _child_box(top, top_box, roots, t, side):
    c = top[t][2 + side]
    return top_box[c] if c >= 0 else roots[~c][1]


# ---- splitters: give each node range [s, e) a split point s < m < e -----------------------------

def _expand_bits(v: np.ndarray) -> np.ndarray:
    """Spread the low 21 bits of v so two zero bits separate each (for 63-bit Morton codes)."""
    v = v.astype(np.uint64) & np.uint64(0x1FFFFF)
    for shift, mask in ((32, 0x1F00000000FFFF), (16, 0x1F0000FF0000FF), (8, 0x100F00F00F00F00F),
                        (4, 0x10C30C30C30C30C3), (2, 0x1249249249249249)):
        v = (v | (v << np.uint64(shift))) & np.uint64(mask)
    return v


def _morton_codes(centroid: np.ndarray, lo=None, hi=None) -> np.ndarray:
    """63-bit Morton codes of the centroids quantised in the box [lo, hi] (default: their own).
    One scale for all axes (a cubic grid): per-axis scales stretch flat scenes such as terrain
    and double their SAH cost."""
    lo = centroid.min(axis=0) if lo is None else lo
    hi = centroid.max(axis=0) if hi is None else hi
    q = ((centroid - lo) * ((2**21 - 1) / max(float((hi - lo).max()), 1e-30))).astype(np.uint32)
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
