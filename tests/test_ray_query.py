"""The GLSL ray queries (ray_query.glsl over GpuScene's two-level BVH) against embreex."""
import numpy as np
import pytest
import trimesh

from rayvr.gpu import compute_program
from rayvr.gpu.bindings import BINDINGS
from rayvr.scene import GpuScene, Mesh, Scene
from rayvr.scene.builtin import lambert
from rayvr.scene.gpu_scene import BVH_LAYOUTS

embree_scene = pytest.importorskip("embreex.rtcore_scene")
from embreex.mesh_construction import TriangleMesh  # noqa: E402

KERNEL = """
#include "ray_query.glsl"
layout(local_size_x = 64) in;
layout(std430, binding = RAYVR_PASS_SSBO_0) readonly buffer Rays { vec4 rays[]; };   // o, tmax | d, occl
layout(std430, binding = RAYVR_PASS_SSBO_1) writeonly buffer Hits { vec4 hits[]; };  // t, b1, b2, instance | prim, occluded
void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= uint(rays.length() / 2)) return;
    vec4 o = rays[2u * i], d = rays[2u * i + 1u];
    Hit h;
    bool hit = trace_closest(o.xyz, d.xyz, o.w, h);
    bool occ = trace_occluded(o.xyz, d.xyz, o.w);
    hits[2u * i] = hit ? vec4(h.t, h.barycentrics, uintBitsToFloat(h.instance)) : vec4(-1.0, 0.0, 0.0, uintBitsToFloat(0xFFFFFFFFu));
    hits[2u * i + 1u] = vec4(uintBitsToFloat(hit ? h.primitive : 0xFFFFFFFFu), occ ? 1.0 : 0.0, 0.0, 0.0);
}
"""


def gpu_trace(gl, gpu_scene, origins, dirs, tmp_path, tmax=1e30, defines=None):
    src = tmp_path / "trace.comp"
    src.write_text(KERNEL)
    prog = compute_program(gl, src, {**gpu_scene.defines(), **(defines or {})})
    n = len(origins)
    rays = np.zeros((n, 2, 4), np.float32)
    rays[:, 0, :3], rays[:, 0, 3], rays[:, 1, :3] = origins, tmax, dirs
    rbuf = gl.buffer(rays.tobytes())
    hbuf = gl.buffer(reserve=n * 32)
    gpu_scene.bind()
    rbuf.bind_to_storage_buffer(BINDINGS["RAYVR_PASS_SSBO_0"])
    hbuf.bind_to_storage_buffer(BINDINGS["RAYVR_PASS_SSBO_1"])
    prog.run((n + 63) // 64)
    out = np.frombuffer(hbuf.read(), np.float32).reshape(n, 2, 4)
    rbuf.release(), hbuf.release()
    inst = out[:, 0, 3].view(np.uint32)
    prim = out[:, 1, 0].view(np.uint32)
    return out[:, 0, 0], inst, prim, out[:, 1, 1] > 0.5, out[:, 0, 1:3]


def embree_trace(world_tris, origins, dirs):
    sc = embree_scene.EmbreeScene()
    TriangleMesh(sc, world_tris.astype(np.float32))
    res = sc.run(origins.astype(np.float32), dirs.astype(np.float32), output=1)
    return res["primID"], res["tfar"]


def random_rays(rng, lo, hi, n):
    centre, radius = (lo + hi) / 2, np.linalg.norm(hi - lo) * 0.75 + 1e-3
    o = rng.normal(size=(n, 3))
    o = centre + radius * o / np.linalg.norm(o, axis=1, keepdims=True)
    target = lo + (hi - lo) * rng.uniform(-0.1, 1.1, size=(n, 3))
    d = target - o
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    # a quarter of the rays start inside the bounds
    inside = rng.uniform(size=n) < 0.25
    o[inside] = lo + (hi - lo) * rng.uniform(size=(int(inside.sum()), 3))
    return o, d


def meshes():
    rng = np.random.default_rng(1)
    soup_v = rng.uniform(-1, 1, size=(600, 3))
    yield "icosphere", trimesh.creation.icosphere(subdivisions=3).vertices, trimesh.creation.icosphere(subdivisions=3).faces
    t = trimesh.creation.torus(1.0, 0.3, major_sections=24, minor_sections=12)
    yield "torus", t.vertices, t.faces
    yield "soup", soup_v, np.arange(600).reshape(-1, 3)
    b = trimesh.creation.box((1, 2, 0.5))
    yield "box", b.vertices, b.faces


def scene_of(positions, faces, transforms):
    s = Scene("test")
    s.add_material(lambert("M", (0.5, 0.5, 0.5)))
    m = s.add_mesh(Mesh("mesh", positions, faces, np.uint32(0)))
    for t in transforms:
        s.add_instance(m, t)
    return s


def world_triangles(scene, origin=np.zeros(3)):
    tris, inst, prim = [], [], []
    for i, ins in enumerate(scene.instances):
        m = scene.meshes[ins.mesh]
        tr = ins.transform.copy()
        tr[:3, 3] -= origin
        tris.append(m.triangles().astype(np.float64) @ tr[:3, :3].T + tr[:3, 3])
        inst.append(np.full(m.triangle_count, i))
        prim.append(np.arange(m.triangle_count))
    return np.concatenate(tris), np.concatenate(inst), np.concatenate(prim)


def compare(gl, scene, tmp_path, n=4000, origin=np.zeros(3), method="auto", seed=0, defines=None, bvh_layout="bvh4"):
    gs = GpuScene(gl_ctx(gl), scene, bvh_method=method, bvh_layout=bvh_layout)
    gs.update(origin)
    tris, inst_of, prim_of = world_triangles(scene, origin)
    lo, hi = tris.reshape(-1, 3).min(0), tris.reshape(-1, 3).max(0)
    o, d = random_rays(np.random.default_rng(seed), lo, hi, n)
    t, inst, prim, occ, _ = gpu_trace(gl, gs, o, d, tmp_path, defines=defines)
    eprim, et = embree_trace(tris, o, d)
    ehit = eprim >= 0
    ghit = inst != 0xFFFFFFFF
    g_global = np.full(n, -1)
    key = {(a, b): k for k, (a, b) in enumerate(zip(inst_of, prim_of))}
    for k in np.flatnonzero(ghit):
        g_global[k] = key[(int(inst[k]), int(prim[k]))]
    same = np.where(ehit, g_global == eprim, ~ghit)
    assert ehit.sum() > n * 0.2, "the test rays should mostly hit"
    assert same.mean() >= 0.9999, f"{(~same).sum()} of {n} rays disagree with embree"
    both = ehit & ghit
    np.testing.assert_allclose(t[both], et[both], rtol=1e-5, atol=1e-6)
    np.testing.assert_array_equal(occ, ehit)
    gs.release()


def gl_ctx(gl):
    from rayvr.gpu import get_context
    return get_context()


LAYOUTS = pytest.mark.parametrize("bvh_layout", BVH_LAYOUTS)


@LAYOUTS
@pytest.mark.parametrize("name", ["icosphere", "torus", "soup", "box"])
@pytest.mark.parametrize("method", ["sah", "lbvh"])
def test_closest_hits_match_embree(gl, tmp_path, name, method, bvh_layout):
    v, f = next((v, f) for n, v, f in meshes() if n == name)
    compare(gl, scene_of(v, f, [np.eye(4)]), tmp_path, method=method, bvh_layout=bvh_layout)


@LAYOUTS
def test_instances_match_embree(gl, tmp_path, bvh_layout):
    v, f = next((v, f) for n, v, f in meshes() if n == "torus")
    rng = np.random.default_rng(3)
    transforms = []
    for k in range(6):
        q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        t = np.eye(4)
        t[:3, :3] = q * rng.uniform(0.3, 1.5)
        t[:3, 3] = rng.uniform(-3, 3, size=3)
        transforms.append(t)
    compare(gl, scene_of(v, f, transforms), tmp_path, n=3000, bvh_layout=bvh_layout)


@LAYOUTS
def test_far_from_origin_is_as_precise_as_near(gl, tmp_path, bvh_layout):
    """Instances 1e5..1e6 m away, rendered with the frame origin beside them: hits agree with
    embree on the same geometry near the origin (render space keeps float32 precise)."""
    v, f = next((v, f) for n, v, f in meshes() if n == "icosphere")
    far = np.array([1.0e5, -3.0e5, 1.0e6])
    near_t = [np.eye(4), np.eye(4)]
    near_t[1][:3, 3] = (2.5, 0.0, 0.0)
    far_t = [t.copy() for t in near_t]
    for t in far_t:
        t[:3, 3] += far
    compare(gl, scene_of(v, f, far_t), tmp_path, n=3000, origin=far, bvh_layout=bvh_layout)


@LAYOUTS
def test_moving_an_instance_moves_its_hits(gl, tmp_path, bvh_layout):
    v, f = next((v, f) for n, v, f in meshes() if n == "box")
    scene = scene_of(v, f, [np.eye(4), np.eye(4)])
    scene.instances[1].transform[:3, 3] = (5.0, 0.0, 0.0)
    gs = GpuScene(gl_ctx(gl), scene, bvh_layout=bvh_layout)
    o = np.array([[5.0, 0.0, 10.0], [9.0, 0.0, 10.0]])
    d = np.array([[0.0, 0.0, -1.0], [0.0, 0.0, -1.0]])
    t, inst, *_ = gpu_trace(gl, gs, o, d, tmp_path)
    np.testing.assert_allclose(t, [9.75, -1], rtol=1e-6)
    assert inst[0] == 1
    scene.instances[1].transform[:3, 3] = (9.0, 0.0, 1.0)
    gs.update(np.array([1.0, 0.0, 0.0]))                     # and a new render origin
    t, inst, *_ = gpu_trace(gl, gs, o - [1.0, 0.0, 0.0], d, tmp_path)
    np.testing.assert_allclose(t, [-1, 8.75], rtol=1e-6)
    assert inst[1] == 1


@LAYOUTS
def test_watertight_triangle_test_matches_embree(gl, tmp_path, bvh_layout):
    """RQ_TRIANGLE 0 (Woop et al. watertight) stays selectable and correct with instances."""
    v, f = next((v, f) for n, v, f in meshes() if n == "torus")
    t = np.eye(4)
    t[:3, 3] = (2.0, 0.5, 0.0)
    compare(gl, scene_of(v, f, [np.eye(4), t]), tmp_path, n=2000, defines={"RQ_TRIANGLE": 0}, bvh_layout=bvh_layout)


STATS_KERNEL = """
#include "ray_query.glsl"
layout(local_size_x = 64) in;
layout(std430, binding = RAYVR_PASS_SSBO_0) readonly buffer Rays { vec4 rays[]; };
layout(std430, binding = RAYVR_PASS_SSBO_1) writeonly buffer Stats { uvec4 stats[]; };
void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= uint(rays.length() / 2)) return;
    Hit h;
    bool hit = trace_closest(rays[2u * i].xyz, rays[2u * i + 1u].xyz, 1e29, h);
    stats[i] = uvec4(rq_stat_nodes, rq_stat_triangles, rq_stat_instances, hit ? 1u : 0u);
}
"""


@LAYOUTS
def test_stats_count_nodes_triangles_and_instances(gl, tmp_path, bvh_layout):
    """RQ_STATS: a ray missing every instance box visits only the TLAS root; a ray through one
    box instance enters one BLAS and tests at least the triangle it hits, walking the 12-triangle
    BLAS from its root (leaves of <= 4: >= 2 BVH2 nodes; a BVH4 root can hold every leaf)."""
    v, f = next((v, f) for n, v, f in meshes() if n == "box")
    t = np.eye(4)
    t[:3, 3] = (5.0, 0.0, 0.0)
    gs = GpuScene(gl_ctx(gl), scene_of(v, f, [np.eye(4), t]), bvh_layout=bvh_layout)
    src = tmp_path / "stats.comp"
    src.write_text(STATS_KERNEL)
    prog = compute_program(gl, src, {**gs.defines(), "RQ_STATS": 1})
    rays = np.zeros((2, 2, 4), np.float32)
    rays[0, 0, :3], rays[0, 1, :3] = (0.0, 10.0, 10.0), (0.0, 0.0, -1.0)   # above both boxes
    rays[1, 0, :3], rays[1, 1, :3] = (5.0, 0.0, 10.0), (0.0, 0.0, -1.0)    # straight into box 1
    rbuf, sbuf = gl.buffer(rays.tobytes()), gl.buffer(reserve=2 * 16)
    gs.bind()
    rbuf.bind_to_storage_buffer(BINDINGS["RAYVR_PASS_SSBO_0"])
    sbuf.bind_to_storage_buffer(BINDINGS["RAYVR_PASS_SSBO_1"])
    prog.run(1)
    st = np.frombuffer(sbuf.read(), np.uint32).reshape(2, 4)
    rbuf.release(), sbuf.release(), gs.release()
    assert tuple(st[0]) == (1, 0, 0, 0)
    nodes, tris, instances, hit = st[1]
    assert hit == 1 and instances == 1
    assert 1 <= tris <= 12
    assert nodes >= 1 + (2 if bvh_layout == "bvh2" else 1)   # the TLAS root, then the BLAS nodes on the way to the hit
    assert nodes <= 1 + gs.report()["blas_nodes"]
