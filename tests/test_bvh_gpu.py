"""The GPU LBVH builder (rayvr.scene.bvh_gpu): a valid tree over every triangle, CPU-LBVH quality,
the BVH-ordered triangle array, its GPU collapse to "bvh4" (a valid BVH4 in bvh_wide's layout,
near the CPU's optimal collapse), and closest hits that agree with embree through GpuScene."""
import numpy as np
import pytest

from rayvr.errors import SceneError
from rayvr.scene import GpuScene, bvh, bvh8, bvh_gpu, bvh_wide


def soup(n, seed=0, spread=0.03):
    rng = np.random.default_rng(seed)
    centre = rng.uniform(-1, 1, (n, 1, 3))
    return (centre + rng.normal(0, spread, (n, 3, 3))).astype(np.float32)


def duplicates(n):
    """Many triangles on the same few centroids: equal Morton codes, split by slot index."""
    base = soup(4, seed=3)
    return np.repeat(base, n // 4, axis=0) + np.float32(0)


def walk(b: bvh.Bvh):
    """Every (box lo, box hi, first slot, count) leaf and every (parent, child box) pair, from the root."""
    v = b.nodes.reshape(-1, 2, 2, 4)
    bits = v.view(np.uint32)
    leaves, nested, stack, seen = [], [], [(0, None)], set()
    while stack:
        node, parent_box = stack.pop()
        assert node not in seen, f"node {node} reached twice"
        seen.add(node)
        for c in (0, 1):
            lo, hi = v[node, c, 0, :3], v[node, c, 1, :3]
            link, count = int(bits[node, c, 0, 3]), int(bits[node, c, 1, 3])
            if parent_box is not None:
                nested.append((parent_box, (lo, hi)))
            if count:
                leaves.append((lo, hi, link, count))
            else:
                stack.append((link, (lo, hi)))
    assert len(seen) == b.node_count, "every emitted node is reachable (compaction leaves no holes)"
    return leaves, nested


@pytest.mark.parametrize("rotations", [3, 0], ids=["rotated", "plain"])
@pytest.mark.parametrize("tris", [soup(3000), duplicates(2000), soup(9, seed=5)], ids=["soup", "duplicates", "tiny"])
def test_gpu_bvh_is_a_valid_tree(gpu, tris, rotations):
    b = bvh_gpu.build_gpu(gpu, tris, rotations=rotations)
    assert b.method == "gpu"
    np.testing.assert_array_equal(np.sort(b.order), np.arange(len(tris)))
    tri_lo, tri_hi = bvh.triangle_bounds(tris[b.order])
    leaves, nested = walk(b)
    covered = np.zeros(len(tris), np.int64)
    for lo, hi, first, count in leaves:
        assert 1 <= count <= 4
        covered[first:first + count] += 1
        np.testing.assert_array_equal(lo, tri_lo[first:first + count].min(0))   # leaf boxes are exact
        np.testing.assert_array_equal(hi, tri_hi[first:first + count].max(0))
    np.testing.assert_array_equal(covered, 1)          # each triangle in exactly one leaf
    for (plo, phi), (lo, hi) in nested:
        assert np.all(plo <= lo) and np.all(hi <= phi)  # children inside parents
    v = b.nodes.reshape(-1, 2, 2, 4)
    np.testing.assert_array_equal(np.minimum(v[0, 0, 0, :3], v[0, 1, 0, :3]), tris.reshape(-1, 3).min(0))
    np.testing.assert_array_equal(np.maximum(v[0, 0, 1, :3], v[0, 1, 1, :3]), tris.reshape(-1, 3).max(0))


@pytest.mark.parametrize("name", ["soup", "sphere"])
def test_gpu_bvh_quality_matches_cpu_lbvh(gpu, name):
    import trimesh

    sphere = trimesh.creation.icosphere(subdivisions=5)
    tris = soup(5000) if name == "soup" else sphere.vertices[sphere.faces].astype(np.float32)
    cpu = bvh.build(*bvh.triangle_bounds(tris), method="lbvh")
    plain = bvh_gpu.build_gpu(gpu, tris, rotations=0)     # the same Karras tree as the CPU LBVH
    assert plain.sah_cost() == pytest.approx(cpu.sah_cost(), rel=0.01)
    assert abs(plain.node_count - cpu.node_count) <= 0.02 * cpu.node_count
    rotated = bvh_gpu.build_gpu(gpu, tris)
    assert rotated.sah_cost() <= plain.sah_cost()
    if name == "sphere":   # regular meshes: Morton order alone splits them poorly, rotations win ~4%
        assert rotated.sah_cost() <= 0.975 * cpu.sah_cost()


def test_ordered_triangles_and_link_offsets(gpu):
    tris = soup(1500, seed=2)
    builder = bvh_gpu.builder_for(gpu)
    plain = builder.build(tris).to_bvh()
    g = builder.build(tris, node_base=100, tri_base=7000)
    slots = g.read_triangles()
    order = np.frombuffer(g.order.read(size=4 * len(tris)), np.uint32)
    np.testing.assert_array_equal(slots[:, :, :3], tris[order])
    np.testing.assert_array_equal(slots[:, 0, 3].view(np.uint32), order)
    shifted = g.to_bvh()
    bits, ref = shifted.nodes.view(np.uint32), plain.nodes.view(np.uint32)
    for c in (0, 8):
        leaf = ref[:, c + 7] > 0
        np.testing.assert_array_equal(bits[:, c + 3], ref[:, c + 3] + np.where(leaf, 7000, 100))


def test_copy_into_shared_buffers(gpu, gl):
    tris = soup(800, seed=4)
    g = bvh_gpu.builder_for(gpu).build(tris, node_base=5, tri_base=10)
    expect_nodes, expect_tris = g.to_bvh().nodes, g.read_triangles()
    nodes = gl.buffer(reserve=(5 + g.node_count + 2) * 64)
    slots = gl.buffer(reserve=(10 + len(tris)) * 48)
    g.copy_into(nodes, 5, slots, 10)
    got = np.frombuffer(nodes.read(), np.float32).reshape(-1, 16)
    np.testing.assert_array_equal(got[5:5 + g.node_count].view(np.uint32), expect_nodes.view(np.uint32))
    np.testing.assert_array_equal(np.frombuffer(slots.read(), np.float32).reshape(-1, 3, 4)[10:], expect_tris)
    nodes.release(), slots.release()


def test_scan_over_many_groups(gpu):
    """The exclusive scan the sort and the compaction share, past one group of block sums."""
    builder = bvh_gpu.GpuBvhBuilder(gpu)
    n = 300_000
    builder._reserve(n)
    data = np.random.default_rng(0).integers(0, 5, n).astype(np.uint32)
    builder._bufs["scan"].write(data)
    groups = builder._scan(n, add=True)
    got = np.frombuffer(builder._bufs["scan"].read(size=4 * n), np.uint32)
    np.testing.assert_array_equal(got, np.cumsum(data) - data)
    total = np.frombuffer(builder._bufs["sums"].read(size=4, offset=4 * groups), np.uint32)[0]
    assert total == data.sum()
    builder.release()


def sphere(subdivisions=5):
    import trimesh

    m = trimesh.creation.icosphere(subdivisions=subdivisions)
    return m.vertices[m.faces].astype(np.float32)


def flat_grid(n=100):
    """A flat square of 2 (n - 1)^2 triangles in the plane y = 0 (boxes of zero height)."""
    x, z = np.meshgrid(np.linspace(-1, 1, n), np.linspace(-1, 1, n))
    pos = np.stack([x, np.zeros_like(x), z], axis=-1).reshape(-1, 3)
    a = (np.arange(n - 1)[:, None] * n + np.arange(n - 1)).reshape(-1)
    quads = np.stack([a, a + n, a + 1, a + 1, a + n, a + n + 1], axis=1).reshape(-1, 3)
    return pos[quads].astype(np.float32)


@pytest.mark.parametrize("tris", [soup(5000), sphere(), flat_grid(), duplicates(4000)],
                         ids=["soup", "sphere", "flat", "duplicates"])
def test_gpu_bvh4_collapse_is_a_valid_bvh4(gpu, tris):
    """Every slot reached once, child boxes exactly their subtrees' bounds, 1..4 children, empty
    slots at 1e30 with item 0 (test_bvh_wide.check); the GPU's nodes bit for bit bvh_wide's
    packing of its slots and items; node visits near the CPU's SAH-optimal collapse."""
    from test_bvh_wide import check

    builder = bvh_gpu.builder_for(gpu)
    g = builder.build(tris)
    g4 = builder.collapse_bvh4(g)
    b = g.to_bvh()
    w = g4.to_wide(b)
    check(w, *bvh.triangle_bounds(tris))
    np.testing.assert_array_equal(g4.read_nodes().view(np.uint32), w.nodes.view(np.uint32))
    inner = (w.slots >= 0) & ((w.items & bvh_wide.LEAF_BIT) == 0)
    assert (w.items[inner] > np.nonzero(inner)[0]).all()   # numbered level by level from the root
    optimal = bvh_wide.collapse(b)
    assert optimal.sah_cost() <= w.sah_cost() * (1 + 1e-9) <= 1.06 * optimal.sah_cost()
    assert w.sah_cost(c_tri=0) < 0.7 * b.sah_cost(c_tri=0)   # fewer node visits than the BVH2
    assert (w.slots >= 0).sum(axis=1).mean() >= 2.7


@pytest.mark.parametrize("tris", [soup(5000), sphere(), flat_grid(), duplicates(4000), soup(9, seed=5)],
                         ids=["soup", "sphere", "flat", "duplicates", "tiny"])
def test_gpu_bvh8_collapse_is_a_valid_bvh8(gpu, tris):
    """The GPU's own nodes and triangle order (test_bvh8.walk: every triangle inside its decoded
    boxes, reached once, 1..8 children), and bvh8's CPU packing of its slots and items; node
    visits near the CPU's SAH-optimal collapse."""
    from test_bvh8 import walk

    builder = bvh_gpu.builder_for(gpu)
    g = builder.build(tris)
    g8 = builder.collapse_bvh8(g)
    b = g.to_bvh()
    w = g8.to_bvh8(b)
    gpu_order = g8.read_triangles()[:, 0, 3].view(np.uint32).astype(np.int64)
    np.testing.assert_array_equal(g8.read_triangles()[:, :, :3], tris[gpu_order])
    walk(w, tris, g8.read_nodes(), gpu_order)
    walk(w, tris)
    optimal = bvh8.collapse(b)
    assert optimal.sah_cost() <= w.sah_cost() * (1 + 1e-9) <= 1.08 * optimal.sah_cost()
    if len(tris) > 100:
        assert w.sah_cost(c_tri=0) < 0.8 * g4_cost(builder, g, b)   # fewer node visits than BVH4


def g4_cost(builder, g, b):
    return builder.collapse_bvh4(g).to_wide(b).sah_cost(c_tri=0)


def test_gpu_bvh4_links_and_refit(gpu):
    """Leaf items keep the build's tri_base, node items count from 0 whatever its node_base;
    the WideBvh reads its boxes from the read-back BVH2, so a refit of that shows."""
    from test_bvh_wide import check

    tris = sphere(3)
    builder = bvh_gpu.builder_for(gpu)
    g = builder.build(tris)
    plain = builder.collapse_bvh4(g).to_wide(g.to_bvh())
    g = builder.build(tris, node_base=100, tri_base=7000)
    shifted = builder.collapse_bvh4(g).read_nodes().view(np.uint32)[:, -4:]
    # the collapse numbers each level's nodes in atomicAdd order, which differs between runs:
    # compare the multisets of items, each array's leaves found by its own leaf bits
    leaf = (plain.items & bvh_wide.LEAF_BIT) != 0
    leaf_shifted = (shifted & bvh_wide.LEAF_BIT) != 0
    np.testing.assert_array_equal(np.sort(shifted[leaf_shifted]), np.sort(plain.items[leaf] + 7000))
    np.testing.assert_array_equal(np.sort(shifted[~leaf_shifted]), np.sort(plain.items[~leaf]))
    moved = tris * np.float32([2.0, 0.5, 1.0])
    plain.source.refit(*bvh.triangle_bounds(moved))
    check(plain, *bvh.triangle_bounds(moved))


def test_rays_through_gpu_bvh_match_embree(gl, tmp_path):
    pytest.importorskip("embreex.rtcore_scene")
    from test_ray_query import compare, meshes, scene_of

    for name in ("torus", "soup"):
        v, f = next((v, f) for n, v, f in meshes() if n == name)
        for layout in ("bvh4", "bvh2", "bvh8"):
            compare(gl, scene_of(v, f, [np.eye(4)]), tmp_path, method="gpu", n=2000, bvh_layout=layout)
    layers = np.concatenate([flat_grid(100), flat_grid(60) * np.float32(0.5) + np.float32([0, 0.4, 0])])
    for tris in (sphere(), layers):   # 20k and 26k triangles (two flat layers: boxes of zero height)
        positions = tris.reshape(-1, 3)
        for layout in ("bvh4", "bvh8"):
            compare(gl, scene_of(positions, np.arange(len(positions)).reshape(-1, 3), [np.eye(4)]), tmp_path,
                    method="gpu", n=3000, bvh_layout=layout)


def test_gpu_scene_uses_the_gpu_builder(gpu, monkeypatch):
    collapses = []
    for name in ("collapse_bvh4", "collapse_bvh8"):
        monkeypatch.setattr(bvh_gpu.GpuBvhBuilder, name, lambda self, g, f=getattr(bvh_gpu.GpuBvhBuilder, name), n=name:
                            collapses.append((n, g.triangle_count)) or f(self, g))
    for layout, on_gpu in (("bvh4", [("collapse_bvh4", 600)]), ("bvh8", [("collapse_bvh8", 600)]), ("bvh4q", []),
                           ("bvh2", [])):
        collapses.clear()
        s = GpuScene(gpu, _scene(soup(600)), bvh_method="gpu", bvh_layout=layout)
        assert s.blas[0].method == "gpu"
        assert collapses == on_gpu, "bvh4, bvh8: collapsed on the GPU; bvh4q: on the CPU (quantised there)"
        assert all(not b._bufs for b in bvh_gpu._builders.values()), "GpuScene frees the builder's scratch"
        s.release()
    with pytest.raises(SceneError, match="bvh_method"):
        GpuScene(gpu, _scene(soup(50)), bvh_method="fast")


def test_bad_leaf_size_is_refused(gpu):
    with pytest.raises(SceneError, match="leaf_size"):
        bvh_gpu.GpuBvhBuilder(gpu, leaf_size=9)
    with pytest.raises(SceneError, match="at least"):
        bvh_gpu.builder_for(gpu).build(soup(3))
    bad = soup(20)
    bad[3, 1, 2] = np.nan
    with pytest.raises(SceneError, match="NaN"):
        bvh_gpu.build_gpu(gpu, bad)


def _scene(tris):
    from rayvr.scene import Mesh, Scene
    from rayvr.scene.builtin import lambert

    s = Scene("soup")
    s.add_material(lambert("M", (0.5, 0.5, 0.5)))
    s.add_instance(s.add_mesh(Mesh("m", tris.reshape(-1, 3), np.arange(len(tris) * 3).reshape(-1, 3), np.uint32(0))),
                   np.eye(4))
    return s
