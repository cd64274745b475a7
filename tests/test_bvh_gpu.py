"""The GPU LBVH builder (rayvr.scene.bvh_gpu): a valid tree over every triangle, CPU-LBVH quality,
the BVH-ordered triangle array, and closest hits that agree with embree through GpuScene."""
import numpy as np
import pytest

from rayvr.errors import SceneError
from rayvr.scene import GpuScene, bvh, bvh_gpu


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


def test_rays_through_gpu_bvh_match_embree(gl, tmp_path):
    pytest.importorskip("embreex.rtcore_scene")
    from test_ray_query import compare, meshes, scene_of

    for name in ("torus", "soup"):
        v, f = next((v, f) for n, v, f in meshes() if n == name)
        compare(gl, scene_of(v, f, [np.eye(4)]), tmp_path, method="gpu", n=2000)


def test_gpu_scene_uses_the_gpu_builder(gpu):
    s = GpuScene(gpu, _scene(soup(600)), bvh_method="gpu")
    assert s.blas[0].method == "gpu"
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
