"""BVH builds: structure invariants, SAH quality, degenerate input, refit (checked on the GPU)."""
import numpy as np
import pytest
import trimesh

from rayvr.errors import SceneError
from rayvr.gpu import get_context
from rayvr.scene import GpuScene, Material, Scene
from rayvr.scene.bvh import build, triangle_bounds


def check_structure(b, lo, hi, leaf_size=4):
    nodes = b.nodes.reshape(-1, 4, 4)
    bits = nodes.view(np.uint32)
    seen = np.zeros(len(lo), int)
    order = b.order
    for n in range(len(nodes)):
        for row in (0, 2):
            cmin, cmax = nodes[n, row, :3], nodes[n, row + 1, :3]
            link, count = bits[n, row, 3], bits[n, row + 1, 3]
            if count > 0:
                assert count <= leaf_size
                prims = order[link:link + count]
                seen[prims] += 1
                assert (cmin <= lo[prims]).all() and (cmax >= hi[prims]).all()
            elif cmin[0] < 1e29:   # internal child: its box is the union of its children's
                kid = nodes[link]
                np.testing.assert_array_equal(cmin, np.minimum(kid[0, :3], kid[2, :3]))
                np.testing.assert_array_equal(cmax, np.maximum(kid[1, :3], kid[3, :3]))
    assert (seen == 1).all(), "every primitive is in exactly one leaf"


@pytest.mark.parametrize("method", ["lbvh", "sah"])
def test_structure(method):
    m = trimesh.creation.torus(1.0, 0.3, major_sections=32, minor_sections=16)
    lo, hi = triangle_bounds(m.triangles.astype(np.float32))
    b = build(lo, hi, method)
    check_structure(b, lo, hi)
    assert b.node_count < len(lo)


def test_sah_build_is_at_least_as_good_as_lbvh():
    rng = np.random.default_rng(0)
    # clustered geometry: where Morton splits are poor
    centres = np.concatenate([rng.normal(c, 0.05, size=(1500, 3)) for c in ([0, 0, 0], [3, 0.2, 0], [0.1, 4, 1])])
    tris = (centres[:, None, :] + rng.normal(0, 0.01, size=(len(centres), 3, 3))).astype(np.float32)
    lo, hi = triangle_bounds(tris)
    sah, lb = build(lo, hi, "sah"), build(lo, hi, "lbvh")
    assert sah.sah_cost(lo, hi) <= lb.sah_cost(lo, hi)
    assert 1.0 < sah.sah_cost(lo, hi) < 200


@pytest.mark.parametrize("method", ["lbvh", "sah"])
def test_degenerate_input(method):
    tri = np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0]]], np.float32)
    same = np.repeat(tri, 1000, axis=0)              # every centroid identical
    lo, hi = triangle_bounds(same)
    check_structure(build(lo, hi, method), lo, hi)
    for n in (1, 3, 4):                               # the whole mesh in one leaf
        lo, hi = triangle_bounds(same[:n])
        b = build(lo, hi, method)
        assert b.nodes.shape == (1, 16)
        check_structure(b, lo, hi)


def test_bad_input_is_refused():
    lo = np.zeros((3, 3), np.float32)
    hi = np.ones((3, 3), np.float32)
    hi[1, 2] = np.nan
    with pytest.raises(SceneError, match="NaN or Inf"):
        build(lo, hi)
    with pytest.raises(SceneError, match="unknown 'octree'"):
        build(lo, lo, "octree")


@pytest.mark.parametrize("bvh_layout", ["bvh2", "bvh4", "bvh4q", "bvh8"])
def test_refit_keeps_hits_right(gl, tmp_path, bvh_layout):
    import test_ray_query as rq   # the embree comparison lives there

    m = trimesh.creation.icosphere(subdivisions=2)
    s = Scene("refit")
    s.add_material(Material("M"))
    s.add_object("S", m.vertices, m.faces, 0)
    gs = GpuScene(get_context(), s, bvh_layout=bvh_layout)
    moved = m.vertices * [1.0, 1.5, 0.7] + [0.3, -0.2, 0.1] + 0.05 * np.sin(5 * m.vertices)
    gs.refit(0, moved)
    gs.update(np.zeros(3))
    tris = moved[m.faces]
    lo, hi = tris.reshape(-1, 3).min(0), tris.reshape(-1, 3).max(0)
    o, d = rq.random_rays(np.random.default_rng(2), lo, hi, 2000)
    t, inst, prim, occ, _ = rq.gpu_trace(gl, gs, o, d, tmp_path)
    eprim, et = rq.embree_trace(tris, o, d)
    hit = eprim >= 0
    assert (np.where(hit, prim.astype(np.int64) == eprim, inst == 0xFFFFFFFF)).mean() >= 0.9999
    np.testing.assert_allclose(t[hit], et[hit], rtol=1e-5, atol=1e-6)


@pytest.mark.parametrize("bvh_layout", ["bvh2", "bvh4", "bvh4q", "bvh8"])
def test_single_triangle_mesh_traces(gl, tmp_path, bvh_layout):
    import test_ray_query as rq

    s = Scene("one")
    s.add_material(Material("M"))
    s.add_object("T", [[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], 0)
    gs = GpuScene(get_context(), s, bvh_layout=bvh_layout)
    o = np.array([[0.2, 0.2, 1.0], [0.8, 0.8, 1.0], [0.2, 0.2, -1.0]])
    d = np.array([[0, 0, -1.0], [0, 0, -1.0], [0, 0, 1.0]])
    t, inst, prim, occ, bary = rq.gpu_trace(gl, gs, o, d, tmp_path)
    np.testing.assert_allclose(t, [1, -1, 1])
    np.testing.assert_array_equal(occ, [True, False, True])
    np.testing.assert_allclose(bary[0], [0.2, 0.2], rtol=1e-6)


def test_threaded_lbvh_makes_the_same_tree(gl, tmp_path, monkeypatch):
    import test_ray_query as rq
    from rayvr.scene import bvh

    m = trimesh.creation.icosphere(subdivisions=4)
    lo, hi = triangle_bounds(m.triangles.astype(np.float32))
    serial = build(lo, hi, "lbvh", threads=1)
    monkeypatch.setattr(bvh, "PARALLEL_MIN", 100)
    threaded = build(lo, hi, "lbvh", threads=3)
    np.testing.assert_array_equal(threaded.order, serial.order)
    assert threaded.node_count == serial.node_count
    assert threaded.sah_cost() == pytest.approx(serial.sah_cost(), rel=1e-6)
    check_structure(threaded, lo, hi)
    before = threaded.nodes.copy()
    threaded.refit(lo, hi)
    np.testing.assert_array_equal(threaded.nodes, before)
    rq.compare(gl, rq.scene_of(m.vertices, m.faces, [np.eye(4)]), tmp_path, n=2000, method="lbvh")


@pytest.mark.parametrize("bvh_layout", ["bvh2", "bvh4", "bvh4q", "bvh8"])
def test_refit_rewrites_one_mesh_as_a_full_repack_would(monkeypatch, bvh_layout):
    """refit() writes only the mesh's slices; the buffers equal a fresh pack of the refit BLASes."""
    s = Scene("three")
    s.add_material(Material("M"))
    for k, m in enumerate((trimesh.creation.icosphere(subdivisions=2), trimesh.creation.box(),
                           trimesh.creation.icosphere(subdivisions=1))):
        s.add_object(f"O{k}", m.vertices + [3.0 * k, 0, 0], m.faces, 0)
    gs = GpuScene(get_context(), s, bvh_layout=bvh_layout)
    moved = s.meshes[1].positions * 1.5 + 0.2
    gs.refit(1, moved)
    monkeypatch.setattr(GpuScene, "_build_blas", lambda self, method, progress: gs.blas)
    fresh = GpuScene(get_context(), s, bvh_layout=bvh_layout)
    for name in ("vertices", "triangles", "blas_nodes", "instances", "indices"):
        assert gs.buffers[name].read() == fresh.buffers[name].read(), name
    np.testing.assert_array_equal(gs.mesh_corners, fresh.mesh_corners)
    gs.release(), fresh.release()
