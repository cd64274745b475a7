"""The compressed 8-wide BVH (rayvr.scene.bvh8): a valid tree whose decoded 8-bit boxes hold every
triangle (so quantisation never loses a hit), children in direction slots, consecutive child
nodes and leaf triangles, fewer bytes per triangle than bvh4; traced by ray_query.glsl it finds
the same closest hits as bvh4 and as embree."""
import numpy as np
import pytest
import trimesh

from rayvr.errors import SceneError
from rayvr.gpu import get_context
from rayvr.scene import GpuScene, bvh8, bvh_wide
from rayvr.scene.bvh import build, triangle_bounds


def walk(w, tris, nodes=None, order=None):
    """From the root as the shader walks it: each triangle slot reached once, each node once, every
    triangle inside every decoded box on its way, and each node's children as the layout says.
    nodes, order: others than w's (the GPU's), else w.nodes and w.order."""
    nodes = w.nodes if nodes is None else nodes
    order = w.order if order is None else order
    bits = nodes.view(np.uint32)
    lo, hi = bvh8.decode(nodes)
    t_lo, t_hi = triangle_bounds(tris[order])
    reached = np.zeros(len(order), np.int64)
    visited = np.zeros(len(nodes), np.int64)

    def subtree(node, path_lo, path_hi):
        visited[node] += 1
        imask = int(bits[node, 3]) >> 24
        metas = bvh_wide.unpack_bytes(bits[node, 6:8])
        children, used = 0, 0
        for s in range(8):
            c_lo, c_hi = np.maximum(path_lo, lo[node, s]), np.minimum(path_hi, hi[node, s])
            if imask >> s & 1:
                children += 1
                child = int(bits[node, 4]) + bin(imask & ((1 << s) - 1)).count("1")
                yield from subtree(child, c_lo, c_hi)
            elif metas[s]:
                children += 1
                count, offset = int(metas[s]) >> 5, int(metas[s]) & 31
                assert 1 <= count <= bvh8.MAX_LEAF and offset + count <= 32
                first = int(bits[node, 5]) + offset
                reached[first:first + count] += 1
                used += count
                yield t_lo[first:first + count], t_hi[first:first + count], c_lo, c_hi
            else:
                assert (lo[node, s] > hi[node, s]).any() or (lo[node, s] == hi[node, s]).all(), "an empty slot is inverted"
        assert 1 <= children <= 8

    for p_lo, p_hi, c_lo, c_hi in subtree(0, np.full(3, -np.inf, np.float32), np.full(3, np.inf, np.float32)):
        assert (p_lo >= c_lo).all() and (p_hi <= c_hi).all(), "a decoded box loses a triangle"
    np.testing.assert_array_equal(reached, 1)
    np.testing.assert_array_equal(visited, 1)


def torus(offset=0.0, scale=1.0):
    m = trimesh.creation.torus(1.0, 0.3, major_sections=32, minor_sections=16)
    return (m.triangles * scale + offset).astype(np.float32)


@pytest.mark.parametrize("method", ["sah", "lbvh"])
@pytest.mark.parametrize("offset", [0.0, 1e5, -3e6])
@pytest.mark.parametrize("shape", ["torus", "flat", "tiny"])
def test_collapse_is_a_valid_bvh8_whose_boxes_hold_their_triangles(method, offset, shape):
    """Far from the origin, flat along an axis (zero extent) and sub-ulp small."""
    tris = torus(offset, {"torus": 1.0, "flat": np.float32([1.0, 1.0, 0.0]), "tiny": 1e-6}[shape])
    b = build(*triangle_bounds(tris), method)
    w = bvh8.collapse(b)
    walk(w, tris)
    assert w.nodes.shape == (w.node_count, bvh8.NODE_FLOATS) and w.nbytes == 80 * w.node_count
    np.testing.assert_array_equal(np.sort(w.order), np.arange(len(tris)))
    if shape == "torus" and offset == 0.0:
        assert w.node_count < 0.6 * bvh_wide.collapse(b).node_count
        assert w.sah_cost(c_tri=0) < bvh_wide.collapse(b).sah_cost(c_tri=0)   # fewer node visits than BVH4


@pytest.mark.parametrize("n", [1, 2, 7, 33])
def test_tiny_trees(n):
    tris = np.random.default_rng(n).uniform(-1, 1, (n, 3, 3)).astype(np.float32)
    walk(bvh8.collapse(build(*triangle_bounds(tris), "sah", leaf_size=1 if n > 3 else 4)), tris)


def test_children_sit_in_the_slot_of_their_direction():
    """Eight boxes at the corners of a cube: each in the slot whose bits are its positive axes, so a
    ray of octant oct (bit k: axis k negative) meets slot r ^ oct r-th, near to far."""
    corners = np.array([[s >> k & 1 for k in range(3)] for s in range(8)], np.float64) * 4.0
    lo = (corners - 0.5)[np.random.default_rng(0).permutation(8)]
    kids = np.arange(8)[None, :]
    placed = bvh8.direction_slots(kids, lo, lo + 1.0)
    np.testing.assert_array_equal((lo[placed[0]] > 1.0) @ [1, 2, 4], np.arange(8))
    placed = bvh8.direction_slots(np.array([[3, -1, 5, -1, -1, -1, -1, -1]]), lo, lo + 1.0)
    assert sorted(placed[0][placed[0] >= 0]) == [3, 5]


def test_leaves_above_four_triangles_are_refused():
    tris = torus()
    with pytest.raises(SceneError, match="leaf_size <= 4"):
        bvh8.collapse(build(*triangle_bounds(tris), "sah", leaf_size=8))


def test_tlas_nodes_name_instances_through_a_table():
    tris = np.random.default_rng(1).uniform(-5, 5, (20, 3, 3)).astype(np.float32)
    w = bvh8.collapse(build(*triangle_bounds(tris), "sah", leaf_size=1))
    instances = np.arange(20, dtype=np.uint32)[::-1].copy()
    out = w.tlas_nodes(instances[w.order])
    bits = out.view(np.uint32)
    assert out.shape[1] == bvh8.NODE_FLOATS
    table = bits.reshape(-1)[w.node_count * 20:]
    has_leaves = bits[:w.node_count, 6:8].any(axis=1)
    base = bits[:w.node_count, 5][has_leaves] - w.node_count * 20   # the table's index
    np.testing.assert_array_equal(table[base], instances[w.order][w.tri_base[has_leaves]])
    np.testing.assert_array_equal(out[:w.node_count, :5], w.nodes[:, :5])


def test_relinked_offsets_child_and_triangle_bases():
    w = bvh8.collapse(build(*triangle_bounds(torus()), "sah"))
    moved = w.relinked(lambda slot: slot + 1000, 7).view(np.uint32)
    bits = w.nodes.view(np.uint32)
    inner = (bits[:, 3] >> 24) != 0
    np.testing.assert_array_equal(moved[:, 4][inner], bits[:, 4][inner] + 7)
    np.testing.assert_array_equal(moved[:, 5], bits[:, 5] + 1000)
    np.testing.assert_array_equal(np.delete(moved, [4, 5], axis=1), np.delete(bits, [4, 5], axis=1))


def test_refit_of_the_source_shows_in_the_nodes():
    tris = torus()
    b = build(*triangle_bounds(tris), "sah")
    w = bvh8.collapse(b)
    moved = tris * np.float32([2.0, 0.5, 1.0])
    b.refit(*triangle_bounds(moved))
    walk(w, moved)


def test_bvh8_takes_fewer_bytes_per_triangle(gpu):
    from test_ray_query import scene_of

    t = trimesh.creation.torus(1.0, 0.3, major_sections=48, minor_sections=24)
    per_tri = {}
    for layout in ("bvh4", "bvh8"):
        gs = GpuScene(get_context(), scene_of(t.vertices, t.faces, [np.eye(4)]), bvh_layout=layout)
        per_tri[layout] = gs.report()["blas_node_bytes_per_triangle"]
        gs.release()
    assert per_tri["bvh8"] < 0.6 * per_tri["bvh4"]


def test_bvh8_finds_bvh4s_closest_hits_and_embrees(gl, tmp_path):
    """Random rays, a quarter from inside, over a soup, a torus and rotated, scaled instances:
    bvh8 (8-bit boxes) hits exactly what bvh4 (float boxes) hits, and agrees with embree."""
    pytest.importorskip("embreex.rtcore_scene")
    from test_ray_query import compare, gpu_trace, meshes, random_rays, scene_of, world_triangles

    rng = np.random.default_rng(4)
    transforms = []
    for _ in range(5):
        q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        m = np.eye(4)
        m[:3, :3], m[:3, 3] = q * rng.uniform(0.3, 1.5), rng.uniform(-3, 3, 3)
        transforms.append(m)
    for name, xf in (("soup", [np.eye(4)]), ("torus", transforms), ("icosphere", transforms[:2])):
        v, f = next((v, f) for n, v, f in meshes() if n == name)
        scene = scene_of(v, f, xf)
        compare(gl, scene, tmp_path, n=3000, bvh_layout="bvh8")
        tris = world_triangles(scene)[0]
        o, d = random_rays(rng, tris.reshape(-1, 3).min(0), tris.reshape(-1, 3).max(0), 3000)
        out = {}
        for layout in ("bvh4", "bvh8"):
            gs = GpuScene(get_context(), scene, bvh_layout=layout)
            out[layout] = gpu_trace(gl, gs, o, d, tmp_path)
            gs.release()
        (t4, i4, p4, o4, _), (t8, i8, p8, o8, _) = out["bvh4"], out["bvh8"]
        np.testing.assert_array_equal(o8, o4)
        same = (i8 == i4) & (p8 == p4)
        assert same.mean() >= 0.9999, f"{name}: {(~same).sum()} rays differ"
        np.testing.assert_allclose(t8[same], t4[same], rtol=1e-6)


@pytest.mark.parametrize("fma", [1, 0])
@pytest.mark.parametrize("shape", ["far", "tiny", "flat"])
def test_quantised_boxes_never_lose_a_hit_bvh4_finds(gl, tmp_path, fma, shape):
    """Rays aimed at the triangles' corners and edges, where they graze the child boxes, over a
    mesh 1e5 from its instance origin, a sub-millimetre one and a flat one: every ray bvh4 (float
    boxes) hits, bvh8 hits as near, with its fma box test (RQ_BVH8_FMA_BOX 1) or the exact decode
    (which enters every box bvh4 enters)."""
    from test_ray_query import gpu_trace, scene_of

    m = trimesh.creation.torus(1.0, 0.3, major_sections=24, minor_sections=12)
    v = {"far": m.vertices + 1e5, "tiny": m.vertices * 1e-4, "flat": m.vertices * [1.0, 1.0, 0.0]}[shape]
    scene = scene_of(v, m.faces, [np.eye(4)])
    tris = v[m.faces]
    rng = np.random.default_rng(7)
    w = rng.dirichlet([0.05, 0.05, 0.05], size=len(tris) * 2)              # mostly near corners and edges
    target = np.einsum("nk,nkd->nd", w, np.repeat(tris, 2, axis=0))
    size = np.ptp(v, axis=0).max()
    d = rng.normal(size=target.shape)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    o = target - d * size * 2.0
    out = {}
    for layout in ("bvh4", "bvh8"):
        gs = GpuScene(get_context(), scene, bvh_layout=layout)
        gs.update(v.mean(axis=0))                       # render space beside the mesh
        out[layout] = gpu_trace(gl, gs, o - v.mean(axis=0), d, tmp_path, defines={"RQ_BVH8_FMA_BOX": fma})
        gs.release()
    t4, t8 = out["bvh4"][0], out["bvh8"][0]
    hit4 = out["bvh4"][1] != 0xFFFFFFFF
    assert hit4.mean() > 0.5
    assert (out["bvh8"][1][hit4] != 0xFFFFFFFF).all(), "bvh8 lost a hit"
    assert (t8[hit4] <= t4[hit4] * (1 + 1e-6)).all(), "bvh8 found a farther hit"
    assert out["bvh8"][3][out["bvh4"][3]].all(), "bvh8 lost an occluder"
    # bvh8's wider boxes may find a grazing hit that bvh4's float boxes round away, rarely
    assert (out["bvh8"][1] != out["bvh4"][1]).mean() < 0.005


def test_the_scene_picks_its_layout_and_the_image_stays(gpu):
    """Scene.bvh_layout reaches the renderer's GpuScene (an unknown one is refused), and the path
    tracer's image through bvh8 is bvh4's: the same hits, the same random numbers."""
    import rayvr as rv
    from rayvr.scene import builtin

    images = {}
    for layout in ("bvh4", "bvh8"):
        scene = builtin.cornell_box()
        scene.bvh_layout = layout
        with rv.Renderer(scene, rv.graphs.path_traced(max_bounces=3), size=(24, 24)) as r:
            r.render()
            assert r.gpu_scene.bvh_layout == layout
            assert r.gpu_scene.defines()["RQ_BVH_WIDTH"] == int(layout[-1])
            images[layout] = np.asarray(r.read_output("Accumulate.dst"))[..., :3].astype(np.float64)
    close = np.isclose(images["bvh8"], images["bvh4"], rtol=1e-5, atol=1e-6).all(axis=-1)
    assert close.mean() >= 0.998 and images["bvh4"].mean() > 0, close.mean()
    scene = builtin.cornell_box()
    scene.bvh_layout = "bvh16"
    with pytest.raises(SceneError, match="bvh_layout"):
        GpuScene(get_context(), scene)
