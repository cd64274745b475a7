"""LBVH built on the GPU with compute shaders (Karras 2012), emitting `bvh.py`'s GPU node layout.

Kernels (rayvr/scene/shaders/): centroid bounds (group reduction + atomics) -> 30-bit Morton
codes on a cubic grid -> a stable 4 x 8-bit radix sort of (code, triangle) pairs (per-tile
histograms, one exclusive scan, a stable scatter) -> Karras' parallel hierarchy (one thread per
internal node, parents, ranges) -> the bottom-up box pass with atomic arrival counters, which
also gathers the BVH-ordered triangles and applies Kensler's tree rotations where they shrink
the SAH cost (`rotations` rounds of that pass; 0: the plain Karras tree of the CPU LBVH) -> a
scan of the nodes that stay internal (more than `leaf_size` triangles; smaller subtrees become
leaves, as the CPU LBVH cuts them) -> the 64-byte nodes at their compacted indices.
Build times and SAH costs against the CPU builders: benchmarks/RESULTS.md ("bvh").
A build's result stays in the builder's GPU buffers (`GpuBvh`): `to_bvh()` reads it back into a
`bvh.Bvh` (what `build_gpu` returns and GpuScene keeps, for refit), `copy_into()` places it in
larger buffers without a read-back.

`collapse_bvh4()` turns a build into bvh_wide.py's "bvh4" layout on the GPU (`GpuBvh4`; the
traced default), greedily: level by level from the root (one dispatch per BVH4 level, an atomic
counter numbering the next level's nodes, siblings adjacent), each BVH4 node is a BVH2 node whose
internal child of largest area is opened while it has fewer than 4 children (bvh4_collapse.comp).
Leaves keep the builder's (<= LEAF_SIZE slots, so one leaf item each). `build_gpu_bvh4` returns
it as a `bvh_wide.WideBvh` over the read-back BVH2 (what GpuScene uploads and refits); the CPU's
`bvh_wide.collapse` is SAH-optimal instead (SAH cost 1-2% lower on test meshes), but numpy and
several times slower (benchmarks/RESULTS.md). `collapse_bvh8()` does the same for bvh8.py's
compressed 8-wide layout (`GpuBvh8`, bvh8_collapse.comp: up to 8 children, direction slots, 8-bit
boxes, each node's leaf triangles copied to a range of its own); `build_gpu_bvh8` returns a
`bvh8.Bvh8` over the read-back BVH2 from its slots and items, as build_gpu_bvh4 does.
"""
from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from ..errors import SceneError
from ..gpu.bindings import BINDINGS
from ..gpu.shaders import compute_program
from . import bvh8, bvh_wide
from .bvh import MAX_LEAF_SIZE, NODE_BYTES, NODE_FLOATS, Bvh

SHADERS = Path(__file__).resolve().parent / "shaders"
WG = 256
TILE = WG * 16          # keys per radix-sort workgroup
SCAN_BLOCK = WG * 4     # elements per scan workgroup
MAX_GROUPS = 65535
MIN_TRIANGLES = 8       # below this the CPU builder makes the (tiny) tree
_SLOT = {"tri_in": 0, "bounds": 1, "keys": 2, "vals": 3, "scan": 4, "sums": 5, "keys_out": 6, "vals_out": 7,
         "children": 8, "ranges": 9, "internal_parent": 10, "leaf_parent": 11, "arrivals": 12,
         "leaf_box": 13, "node_box": 14, "tri_out": 15, "sizes": 16,
         # bvh4_collapse.comp
         "bvh2_nodes": 0, "wide_source": 1, "wide_counter": 2, "wide_nodes": 3, "wide_links": 4,
         # bvh8_collapse.comp also
         "wide_tris_in": 5, "wide_tris": 6}
_BOUNDS_INIT = np.array([0xFFFFFFFF] * 3 + [0] * 3, np.uint32).tobytes()


@dataclasses.dataclass
class GpuBvh:
    """A BVH in GPU buffers: `nodes` (node_count x 64 B, bvh.py's layout), `triangles` (48 B per
    slot: 3 x vec4, vertex 0's w holds the original triangle index's bits) and `order` (uint32
    original triangle index per slot). The buffers belong to the builder and are overwritten by
    its next build; `to_bvh()` copies them out."""

    nodes: object
    triangles: object
    order: object
    node_count: int
    triangle_count: int
    node_base: int = 0      # added to the node links (build's node_base)
    tri_base: int = 0       # added to the leaf links (build's tri_base)

    def to_bvh(self) -> Bvh:
        """Read back into a CPU `Bvh` (method 'gpu')."""
        nodes = np.frombuffer(self.nodes.read(size=self.node_count * NODE_BYTES), np.float32)
        order = np.frombuffer(self.order.read(size=self.triangle_count * 4), np.uint32).astype(np.int64)
        return Bvh(nodes.reshape(-1, NODE_FLOATS).copy(), order, "gpu")

    def copy_into(self, nodes, node_offset: int, triangles, triangle_offset: int) -> None:
        """Copy nodes and ordered triangles GPU-side into larger buffers at the given node and
        triangle indices (build with node_base / tri_base equal to those indices), e.g. a
        scene's shared BLAS and triangle buffers: no read-back, no CPU packing."""
        ctx = self.nodes.ctx
        ctx.copy_buffer(nodes, self.nodes, self.node_count * NODE_BYTES, 0, node_offset * NODE_BYTES)
        ctx.copy_buffer(triangles, self.triangles, self.triangle_count * 48, 0, triangle_offset * 48)

    def read_triangles(self) -> np.ndarray:
        """The BVH-ordered triangles (N, 3, 4) float32, as GpuScene's triangle buffer holds them."""
        return np.frombuffer(self.triangles.read(size=self.triangle_count * 48), np.float32).reshape(-1, 3, 4).copy()


@dataclasses.dataclass
class GpuBvh4:
    """A GpuBvh collapsed on the GPU: `nodes` (node_count x 112 B, bvh_wide.py's "bvh4" layout,
    node items from 0, leaf items with the build's tri_base) and `links` (per node uvec4 source
    child slots, 2 * BVH2 node + side or 0xFFFFFFFF when empty, then uvec4 items). Builder-owned
    buffers, like GpuBvh's."""

    nodes: object
    links: object
    node_count: int

    def read_nodes(self) -> np.ndarray:
        """The (node_count, 28) float32 "bvh4" nodes (item words hold uint bits)."""
        data = self.nodes.read(size=self.node_count * bvh_wide.NODE_BYTES)
        return np.frombuffer(data, np.float32).reshape(-1, bvh_wide.NODE_FLOATS).copy()

    def to_wide(self, source: Bvh) -> bvh_wide.WideBvh:
        """A `WideBvh` over `source` (this build's BVH2, read back with to_bvh(); its boxes, so a
        refit of it shows in the nodes): reads back only the slots and items, 32 B per node."""
        links = np.frombuffer(self.links.read(size=self.node_count * 32), np.uint32).reshape(-1, 2, bvh_wide.WIDTH)
        return bvh_wide.WideBvh(source, links[:, 0].view(np.int32).astype(np.int64), links[:, 1].copy())


@dataclasses.dataclass
class GpuBvh8:
    """A GpuBvh collapsed on the GPU to bvh8.py's layout: `nodes` (node_count x 80 B; child bases from
    0, triangle bases from 0 in `triangles`), `triangles` (48 B per slot, the BVH8's slot order, vertex
    0's w the original triangle index) and `links` (per node 8 source child slots, 0xFFFFFFFF when
    empty, then 8 items). Builder-owned buffers, like GpuBvh's."""

    nodes: object
    triangles: object
    links: object
    node_count: int
    triangle_count: int

    def read_nodes(self) -> np.ndarray:
        """The (node_count, 20) float32 nodes (uint fields hold their bits)."""
        data = self.nodes.read(size=self.node_count * bvh8.NODE_BYTES)
        return np.frombuffer(data, np.float32).reshape(-1, bvh8.NODE_FLOATS).copy()

    def read_triangles(self) -> np.ndarray:
        """The triangles in the BVH8's slot order (N, 3, 4) float32."""
        return np.frombuffer(self.triangles.read(size=self.triangle_count * 48), np.float32).reshape(-1, 3, 4).copy()

    def to_bvh8(self, source: Bvh) -> bvh8.Bvh8:
        """A `bvh8.Bvh8` over `source` (this build's BVH2, read back with to_bvh()) with this
        collapse's slots and node numbering (its triangle order is bvh8.py's rule: nodes in index
        order, leaves in slot order); reads back 64 B per node."""
        links = np.frombuffer(self.links.read(size=self.node_count * 64), np.uint32).reshape(-1, 2, bvh8.WIDTH)
        return bvh8.Bvh8(source, links[:, 0].view(np.int32).astype(np.int64), links[:, 1].copy())


class GpuBvhBuilder:
    """Builds LBVHs on the GPU. Compiles its kernels once and keeps scratch buffers (grown on
    demand) between builds; one builder per GL context."""

    def __init__(self, gpu, leaf_size: int = 4, rotations: int = 3):
        self.gl = gpu.gl if hasattr(gpu, "gl") else gpu
        if not 1 <= leaf_size <= MAX_LEAF_SIZE:
            raise SceneError(f"GpuBvhBuilder: leaf_size {leaf_size} is outside 1..{MAX_LEAF_SIZE} (the GPU node "
                             f"packs count - 1 in 3 bits); pass a leaf_size in that range")
        self.leaf_size, self.rotations = leaf_size, int(rotations)
        defines = {"TILE": f"{TILE}u", "SCAN_BLOCK": f"{SCAN_BLOCK}u", "LEAF_SIZE": leaf_size,
                   "ROTATIONS": int(self.rotations > 0)}

        def prog(name, **extra):
            return compute_program(self.gl, SHADERS / name, {**defines, **extra})

        self.k_bounds = prog("lbvh_bounds.comp")
        self.k_morton = prog("lbvh_morton.comp")
        self.k_hist = prog("radix_histogram.comp")
        self.k_scatter = prog("radix_scatter.comp")
        self.k_scan = [prog("scan.comp", STAGE=s) for s in (1, 2, 3)]
        self.k_hierarchy = prog("lbvh_hierarchy.comp")
        self.k_boxes = prog("lbvh_boxes.comp")
        self.k_emit = prog("lbvh_emit.comp")
        self.k_parents = prog("lbvh_parents.comp")
        self.k_collapse = prog("bvh4_collapse.comp")
        self.k_collapse8 = prog("bvh8_collapse.comp")
        self._capacity = self._wide_capacity = self._wide_triangles = 0
        self._bufs: dict[str, object] = {}
        self.profile = False                       # True: glFinish after each stage, times in stage_ms
        self.stage_ms: dict[str, float] = {}

    # ---- scratch --------------------------------------------------------------------------------
    def _reserve(self, n: int) -> None:
        if n <= self._capacity:
            return
        self.release()
        blocks = -(-n // TILE)
        scan_len = max(256 * blocks, n)
        sizes = {"tri_in": 36 * n, "bounds": 24, "keys": 4 * n, "vals": 4 * n, "scan": 4 * scan_len,
                 "sums": 4 * (-(-scan_len // SCAN_BLOCK) + 1), "keys_out": 4 * n, "vals_out": 4 * n,
                 "children": 8 * n, "ranges": 8 * n, "internal_parent": 4 * n, "leaf_parent": 4 * n,
                 "arrivals": 4 * n, "sizes": 4 * n, "leaf_box": 32 * n, "node_box": 32 * n, "tri_out": 48 * n,
                 "nodes": NODE_BYTES * n}
        self._check_size(max(sizes.values()), f"{n} triangles")
        self._bufs = {k: self.gl.buffer(reserve=v) for k, v in sizes.items()}
        self._capacity = n

    def _reserve_wide(self, node_count: int, triangles: int = 0) -> None:
        """Scratch of collapse_bvh4 and collapse_bvh8 for a BVH2 of node_count nodes (the wide
        BVHs have no more) over `triangles` (collapse_bvh8 copies them)."""
        if node_count <= self._wide_capacity and triangles <= self._wide_triangles:
            return
        node_count, triangles = max(node_count, self._wide_capacity), max(triangles, self._wide_triangles, 1)
        sizes = {"wide_source": 4 * node_count, "wide_counter": 8,
                 "wide_nodes": max(bvh_wide.NODE_BYTES, bvh8.NODE_BYTES) * node_count, "wide_links": 64 * node_count,
                 "wide_tris": 48 * triangles}
        self._check_size(max(sizes.values()), f"a wide BVH of up to {node_count} nodes")
        for k, v in sizes.items():
            if k in self._bufs:
                self._bufs[k].release()
            self._bufs[k] = self.gl.buffer(reserve=v)
        self._wide_capacity, self._wide_triangles = node_count, triangles

    def _check_size(self, nbytes: int, what: str) -> None:
        limit = int(self.gl.info.get("GL_MAX_SHADER_STORAGE_BLOCK_SIZE", 1 << 31))
        if nbytes > limit:
            raise SceneError(f"GpuBvhBuilder: {what} need a buffer of {nbytes / 2**20:.0f} MiB, "
                             f"more than this GPU's shader storage block limit ({limit / 2**20:.0f} MiB); "
                             f"split the mesh or use the CPU builder (bvh_method='lbvh')")

    def release(self) -> None:
        for b in self._bufs.values():
            b.release()
        self._bufs, self._capacity, self._wide_capacity, self._wide_triangles = {}, 0, 0, 0

    def _bind(self, **named) -> None:
        for slot_name, buf_name in named.items():
            self._bufs[buf_name].bind_to_storage_buffer(BINDINGS["RAYVR_PASS_SSBO_0"] + _SLOT[slot_name])

    def _stage(self, name: str | None) -> None:
        if not self.profile:
            return
        import time

        self.gl.finish()
        now = time.perf_counter()
        if name is not None:
            self.stage_ms[name] = (now - self._t) * 1e3
        self._t = now

    def _run(self, prog, dispatch: int, **uniforms) -> None:
        for k, v in uniforms.items():
            if k in prog:
                prog[k].value = v
        prog.run(max(1, min(dispatch, MAX_GROUPS)))
        self.gl.memory_barrier()

    def _scan(self, n: int, add: bool) -> int:
        """Exclusive scan of bufs['scan'][0, n) in place (block sums in bufs['sums'], total at
        sums[groups]); add=False leaves the block sums for the consumer to add. Returns groups."""
        groups = -(-n // SCAN_BLOCK)
        self._bind(scan="scan", sums="sums")
        self._run(self.k_scan[0], groups, n=n, groups=groups)
        self._run(self.k_scan[1], 1, n=n, groups=groups)
        if add:
            self._run(self.k_scan[2], -(-n // WG), n=n, groups=groups)
        return groups

    # ---- build ----------------------------------------------------------------------------------
    def build(self, triangles: np.ndarray, node_base: int = 0, tri_base: int = 0) -> GpuBvh:
        """Build over (N, 3, 3) float32 triangles (finite: not checked here). node_base / tri_base
        are added to node and leaf links (to place this BLAS in a buffer shared with others)."""
        tris = np.ascontiguousarray(triangles, dtype=np.float32).reshape(-1, 9)
        n = len(tris)
        if n < MIN_TRIANGLES:
            raise SceneError(f"GpuBvhBuilder.build: {n} triangles; the GPU builder needs at least "
                             f"{MIN_TRIANGLES}, build tiny meshes with bvh.build()")
        self.stage_ms = {}
        self._stage(None)
        self._reserve(n)
        b = self._bufs
        b["tri_in"].write(tris)
        b["bounds"].write(_BOUNDS_INIT)
        b["arrivals"].clear(size=4 * n)
        self._stage("upload")
        groups = -(-n // WG)
        self._bind(tri_in="tri_in", bounds="bounds", keys="keys", vals="vals")
        self._run(self.k_bounds, min(groups, 1024), n=n)
        self._run(self.k_morton, groups, n=n)
        self._stage("morton")
        self._sort(n)
        self._stage("sort")
        self._bind(keys="keys", scan="scan", children="children", ranges="ranges",
                   internal_parent="internal_parent", leaf_parent="leaf_parent", sizes="sizes")
        self._run(self.k_hierarchy, groups, n=n)
        self._stage("hierarchy")
        self._bind(tri_in="tri_in", vals="vals", children="children", internal_parent="internal_parent",
                   leaf_parent="leaf_parent", arrivals="arrivals", leaf_box="leaf_box", node_box="node_box",
                   tri_out="tri_out", sizes="sizes")
        self._run(self.k_boxes, groups, n=n, first_round=1)
        for _ in range(self.rotations - 1):   # more rounds of rotations over the rotated tree
            self._bind(children="children", internal_parent="internal_parent", leaf_parent="leaf_parent")
            self._run(self.k_parents, groups, n=n)
            b["arrivals"].clear(size=4 * n)
            self._bind(tri_in="tri_in", vals="vals", children="children", internal_parent="internal_parent",
                       leaf_parent="leaf_parent", arrivals="arrivals", leaf_box="leaf_box", node_box="node_box",
                       tri_out="tri_out", sizes="sizes")
            self._run(self.k_boxes, groups, n=n, first_round=0)
        self._stage("boxes")
        scan_groups = self._scan(n - 1, add=True)
        self._bind(scan="scan", keys_out="nodes", children="children", ranges="ranges", leaf_box="leaf_box",
                   node_box="node_box", sizes="sizes")
        self._run(self.k_emit, groups, n=n, node_base=node_base, tri_base=tri_base)
        self._stage("emit")
        node_count = int(np.frombuffer(b["sums"].read(size=4, offset=4 * scan_groups), np.uint32)[0])
        return GpuBvh(b["nodes"], b["tri_out"], b["vals"], node_count, n, node_base, tri_base)

    def collapse_bvh4(self, g: GpuBvh) -> GpuBvh4:
        """g (this builder's latest build) collapsed greedily into "bvh4" nodes on the GPU, one
        dispatch per BVH4 level (see the module docstring); the level sizes are read back."""
        self._collapse_levels(g, self.k_collapse)
        self._stage("collapse")
        return GpuBvh4(self._bufs["wide_nodes"], self._bufs["wide_links"], self._wide_nodes)

    def collapse_bvh8(self, g: GpuBvh) -> GpuBvh8:
        """g (this builder's latest build) collapsed greedily into bvh8.py's nodes on the GPU, one
        dispatch per BVH8 level, its triangles copied into the BVH8's slot order."""
        self._reserve_wide(g.node_count, g.triangle_count)
        self._collapse_levels(g, self.k_collapse8, bvh2_tri_base=g.tri_base,
                              wide_tris_in=g.triangles, wide_tris=self._bufs["wide_tris"])
        self._stage("collapse")
        b = self._bufs
        return GpuBvh8(b["wide_nodes"], b["wide_tris"], b["wide_links"], self._wide_nodes, g.triangle_count)

    def _collapse_levels(self, g: GpuBvh, prog, wide_tris_in=None, wide_tris=None, **uniforms) -> None:
        """Run a collapse kernel level by level from the BVH2's root (one dispatch per wide level,
        an atomic counter numbering the next level); sets _wide_nodes to the node count."""
        self._reserve_wide(g.node_count)
        b = self._bufs
        b["wide_source"].write(np.zeros(1, np.uint32))     # wide node 0: the BVH2 root
        b["wide_counter"].write(np.array([1, 0], np.uint32))
        g.nodes.bind_to_storage_buffer(BINDINGS["RAYVR_PASS_SSBO_0"] + _SLOT["bvh2_nodes"])
        self._bind(wide_source="wide_source", wide_counter="wide_counter", wide_nodes="wide_nodes",
                   wide_links="wide_links")
        for name, buf in (("wide_tris_in", wide_tris_in), ("wide_tris", wide_tris)):
            if buf is not None:
                buf.bind_to_storage_buffer(BINDINGS["RAYVR_PASS_SSBO_0"] + _SLOT[name])
        begin, end = 0, 1
        while begin < end:
            self._run(prog, -(-(end - begin) // WG), level_begin=begin, level_end=end,
                      bvh2_node_base=g.node_base, **uniforms)
            begin, end = end, int(np.frombuffer(b["wide_counter"].read(size=4), np.uint32)[0])
            if end > g.node_count:
                raise SceneError(f"GpuBvhBuilder: a collapse made {end} wide nodes from {g.node_count} BVH2 "
                                 f"nodes; the BVH2 is not a tree (report this as a bug)")
        self._wide_nodes = end

    def _sort(self, n: int) -> None:
        """Stable LSD radix sort of (keys, vals) by the 30-bit codes: 4 passes of 8 bits, the
        result back in keys/vals."""
        blocks = -(-n // TILE)
        src, dst = ("keys", "vals"), ("keys_out", "vals_out")
        for shift in (0, 8, 16, 24):
            self._bind(keys=src[0], scan="scan")
            self._run(self.k_hist, blocks, n=n, shift=shift, blocks=blocks)
            self._scan(256 * blocks, add=False)
            self._bind(keys=src[0], vals=src[1], scan="scan", sums="sums", keys_out=dst[0], vals_out=dst[1])
            self._run(self.k_scatter, blocks, n=n, shift=shift, blocks=blocks)
            self._bufs[src[0]], self._bufs[dst[0]] = self._bufs[dst[0]], self._bufs[src[0]]
            self._bufs[src[1]], self._bufs[dst[1]] = self._bufs[dst[1]], self._bufs[src[1]]


_builders: dict[int, GpuBvhBuilder] = {}


def builder_for(gpu, leaf_size: int = 4, rotations: int = 3) -> GpuBvhBuilder:
    """The shared builder of this GL context (kernels compiled once)."""
    gl = gpu.gl if hasattr(gpu, "gl") else gpu
    key = (id(gl), leaf_size, rotations)
    if key not in _builders:
        _builders[key] = GpuBvhBuilder(gl, leaf_size, rotations)
    return _builders[key]


def release_scratch(gpu) -> None:
    """Free the scratch buffers (~270 B per triangle) of this context's builders; the kernels stay."""
    gl = gpu.gl if hasattr(gpu, "gl") else gpu
    for (ctx_id, *_), builder in _builders.items():
        if ctx_id == id(gl):
            builder.release()


def build_gpu(gpu, triangles: np.ndarray, leaf_size: int = 4, rotations: int = 3) -> Bvh:
    """GPU LBVH of (N, 3, 3) triangles, read back as a CPU `Bvh` (tiny meshes use the CPU LBVH).
    The builder keeps its scratch for the next build: `release_scratch(gpu)` when done."""
    tris = _checked(triangles)
    if len(tris) < MIN_TRIANGLES:
        return _cpu_lbvh(tris, leaf_size)
    return builder_for(gpu, leaf_size, rotations).build(tris).to_bvh()


def build_gpu_bvh4(gpu, triangles: np.ndarray, leaf_size: int = 4, rotations: int = 3) -> bvh_wide.WideBvh:
    """GPU LBVH of (N, 3, 3) triangles collapsed to "bvh4" on the GPU, read back as a
    `bvh_wide.WideBvh` whose source is the BVH2 (tiny meshes: CPU LBVH and CPU collapse)."""
    tris = _checked(triangles)
    if len(tris) < MIN_TRIANGLES:
        return bvh_wide.collapse(_cpu_lbvh(tris, leaf_size))
    builder = builder_for(gpu, leaf_size, rotations)
    g = builder.build(tris)
    wide = builder.collapse_bvh4(g)
    return wide.to_wide(g.to_bvh())


def build_gpu_bvh8(gpu, triangles: np.ndarray, leaf_size: int = 4, rotations: int = 3) -> bvh8.Bvh8:
    """GPU LBVH of (N, 3, 3) triangles collapsed to "bvh8" on the GPU, read back as a `bvh8.Bvh8`
    whose source is the BVH2 (tiny meshes: CPU LBVH and CPU collapse)."""
    tris = _checked(triangles)
    if len(tris) < MIN_TRIANGLES:
        return bvh8.collapse(_cpu_lbvh(tris, leaf_size))
    builder = builder_for(gpu, leaf_size, rotations)
    g = builder.build(tris)
    return builder.collapse_bvh8(g).to_bvh8(g.to_bvh())


def _checked(triangles) -> np.ndarray:
    tris = np.asarray(triangles, dtype=np.float32).reshape(-1, 3, 3)
    if not np.isfinite(tris).all():
        raise SceneError("bvh (gpu): NaN or Inf triangle vertices; remove non-finite vertices first")
    return tris


def _cpu_lbvh(tris: np.ndarray, leaf_size: int) -> Bvh:
    from .bvh import build, triangle_bounds

    return build(*triangle_bounds(tris), method="lbvh", leaf_size=leaf_size)
