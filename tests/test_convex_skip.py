"""A ray leaving a triangle that has its whole mesh behind it skips the ray's own instance
(rayvr.scene.convex_faces, ray_query.glsl's `skip`): which triangles qualify, that a skipped
instance is really not entered, and that rays and path-traced images are the same with the skip
as without it."""
import numpy as np
import pytest
import trimesh

import rayvr as rv
from rayvr.gpu import compute_program
from rayvr.gpu.bindings import BINDINGS
from rayvr.scene import Camera, GpuScene, Light, Mesh, Scene
from rayvr.scene.builtin import lambert
from rayvr.scene.convex_faces import REL_TOL, convex_faces, support
from rayvr.scene.gpu_scene import BVH_LAYOUTS

LAYOUTS = pytest.mark.parametrize("bvh_layout", BVH_LAYOUTS)


# ---- which triangles ---------------------------------------------------------------------------
def test_support_equals_brute_force():
    rng = np.random.default_rng(3)
    pts = rng.normal(size=(3000, 3)) * (1.0, 0.3, 2.0)
    dirs = rng.normal(size=(500, 3))
    np.testing.assert_allclose(support(pts, dirs, rng.integers(0, 3000, 500)), (dirs @ pts.T).max(axis=1), rtol=0,
                               atol=1e-12)


def test_closed_convex_meshes_have_every_triangle():
    for m in (trimesh.creation.icosphere(subdivisions=3), trimesh.creation.box((1, 2, 0.5)),
              trimesh.creation.cylinder(0.5, 2.0, sections=32)):
        assert convex_faces(m.vertices, m.faces).all()


def test_inside_out_and_non_convex_meshes_have_none_or_only_their_outer_side():
    s = trimesh.creation.icosphere(subdivisions=2)
    assert not convex_faces(s.vertices, s.faces[:, ::-1]).any()   # wound inwards: everything is in front
    t = trimesh.creation.torus(1.0, 0.3, major_sections=32, minor_sections=16)
    c = convex_faces(t.vertices, t.faces)
    centroid = t.triangles_center
    radial = np.linalg.norm(centroid[:, :2], axis=1)
    assert not c[radial < 1.0].any()                 # the inner half faces the hole
    assert c[radial > radial.max() - 0.02].all()     # the outer equator's tangent planes hold the torus
    assert 0.4 <= c.mean() <= 0.5                    # the outer half, at most


def test_a_dent_larger_than_the_tolerance_costs_the_triangles_over_it():
    s = trimesh.creation.icosphere(subdivisions=3)
    v = s.vertices.copy()
    noisy = v * (1.0 + np.random.default_rng(0).uniform(-1, 1, size=(len(v), 1)) * 0.2 * REL_TOL)
    assert convex_faces(noisy, s.faces).mean() > 0.95      # exporter noise within the tolerance
    top = np.argmax(v[:, 2])
    dented = v.copy()
    dented[top] *= 0.9                                      # pushed in by 10% of the radius
    c = convex_faces(dented, s.faces)
    around = np.isin(s.faces, [top]).any(axis=1)
    assert not c[around].any()
    assert c.mean() > 0.9


def test_flat_and_degenerate_meshes():
    quad = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    assert convex_faces(quad, [[0, 1, 2], [0, 2, 3]]).all()   # a ray leaving a plane cannot meet it again
    assert not convex_faces(quad, [[0, 1, 1]]).any()         # a degenerate triangle has no front


# ---- the traversal -----------------------------------------------------------------------------
KERNEL = """
#include "ray_query.glsl"
layout(local_size_x = 64) in;
layout(std430, binding = RAYVR_PASS_SSBO_0) readonly buffer Rays { vec4 rays[]; };   // o, skip | d, -
layout(std430, binding = RAYVR_PASS_SSBO_1) writeonly buffer Hits { vec4 hits[]; };  // t, instance, occluded, BLAS entries
void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= uint(rays.length() / 2)) return;
    vec4 o = rays[2u * i], d = rays[2u * i + 1u];
    uint skip = floatBitsToUint(o.w);
    Hit h;
    bool hit = trace_closest(o.xyz, d.xyz, 1e30, skip, h);
    uint entered = rq_stat_instances;
    bool occ = trace_occluded(o.xyz, d.xyz, 1e30, skip);
    hits[i] = vec4(hit ? h.t : -1.0, uintBitsToFloat(hit ? h.instance : 0xFFFFFFFFu), occ ? 1.0 : 0.0, float(entered));
}
"""


def spheres_scene():
    """Two icospheres and a box (all convex), side by side."""
    s = Scene("spheres")
    s.add_material(lambert("M", (0.5, 0.5, 0.5)))
    ico = trimesh.creation.icosphere(subdivisions=3)
    box = trimesh.creation.box((6.0, 0.5, 6.0))
    sphere = s.add_mesh(Mesh("sphere", ico.vertices, ico.faces, np.uint32(0)))
    ground = s.add_mesh(Mesh("ground", box.vertices, box.faces, np.uint32(0)))
    for x in (-1.2, 1.2):
        t = np.eye(4)
        t[:3, 3] = (x, 0.0, 0.0)
        s.add_instance(sphere, t)
    t = np.eye(4)
    t[:3, 3] = (0.0, -1.3, 0.0)
    s.add_instance(ground, t)
    return s


def trace(gl, gs, tmp_path, o, d, skip):
    src = tmp_path / "skip.comp"
    src.write_text(KERNEL)
    prog = compute_program(gl, src, {**gs.defines(), "RQ_STATS": 1})
    n = len(o)
    rays = np.zeros((n, 2, 4), np.float32)
    rays[:, 0, :3], rays[:, 1, :3] = o, d
    rays[:, 0, 3] = np.asarray(skip, np.uint32).view(np.float32)
    rbuf, hbuf = gl.buffer(rays.tobytes()), gl.buffer(reserve=n * 16)
    gs.bind()
    rbuf.bind_to_storage_buffer(BINDINGS["RAYVR_PASS_SSBO_0"])
    hbuf.bind_to_storage_buffer(BINDINGS["RAYVR_PASS_SSBO_1"])
    prog.run((n + 63) // 64)
    out = np.frombuffer(hbuf.read(), np.float32).reshape(n, 4).copy()
    rbuf.release(), hbuf.release()
    return out[:, 0], out[:, 1].view(np.uint32), out[:, 2] > 0.5, out[:, 3]


@LAYOUTS
def test_rays_leaving_a_convex_instance_skip_it_and_find_the_same_hits(gl, tmp_path, bvh_layout):
    from rayvr.gpu import get_context

    gs = GpuScene(get_context(), spheres_scene(), bvh_layout=bvh_layout)
    assert gs.defines()["RQ_CONVEX_SKIP"] == 1 and gs.report()["convex_triangles"] == 1280 + 12   # per mesh
    rng = np.random.default_rng(2)
    n = 2000
    centre = np.array([-1.2, 0.0, 0.0])
    normal = rng.normal(size=(n, 3))
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    o = centre + normal * 1.001                       # just outside sphere 0
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    d = np.where((d * normal).sum(1, keepdims=True) < 0, -d, d)   # leaving outwards
    t0, i0, occ0, entered0 = trace(gl, gs, tmp_path, o, d, np.full(n, 0xFFFFFFFF))
    t1, i1, occ1, entered1 = trace(gl, gs, tmp_path, o, d, np.zeros(n))
    assert (i0 != 0).all(), "a ray leaving sphere 0 outwards met it again"
    assert 0.2 < (i0 != 0xFFFFFFFF).mean() < 0.8      # the other sphere and the ground catch some
    np.testing.assert_array_equal(i1, i0)
    np.testing.assert_array_equal(occ1, occ0)
    np.testing.assert_allclose(t1, t0, rtol=1e-6)
    assert entered1.sum() < entered0.sum() - 0.9 * n  # sphere 0's box held every origin: its BLAS was entered before
    # the skipped instance is not entered at all: rays aimed into sphere 0 pass through it
    inward = -normal
    _, i2, _, _ = trace(gl, gs, tmp_path, o, inward, np.zeros(n))
    assert (i2 != 0).all()
    _, i3, _, _ = trace(gl, gs, tmp_path, o, inward, np.full(n, 0xFFFFFFFF))
    assert (i3 == 0).all()
    gs.release()


def test_a_refit_mesh_loses_its_convex_triangles(gl):
    from rayvr.gpu import get_context

    scene = spheres_scene()
    gs = GpuScene(get_context(), scene)
    gs.refit(0, scene.meshes[0].positions * 1.1)
    assert not gs.convex_faces[0].any() and gs.convex_faces[1].all()
    words = np.frombuffer(gs.buffers["triangle_materials"].read(), np.uint32)
    assert (words[:1280] == 0).all() and (words[1280:] == 0x80000000).all()
    gs.release()


# ---- images ------------------------------------------------------------------------------------
def lit_spheres_scene():
    """The spheres and ground, a torus (half of it not convex) and a sun."""
    s = spheres_scene()
    t = trimesh.creation.torus(0.6, 0.2, major_sections=24, minor_sections=12)
    torus = s.add_mesh(Mesh("torus", t.vertices, t.faces, np.uint32(0)))
    m = np.eye(4)
    m[:3, :3] = [[1, 0, 0], [0, 0, 1], [0, -1, 0]]   # lying on the ground
    m[:3, 3] = (0.0, -0.85, 1.2)
    s.add_instance(torus, m)
    s.lights.append(Light("directional", direction=(-1.0, -0.5, -0.3), intensity=3.0))   # low: the torus shades itself
    s.cameras.append(Camera.look_at((0.0, 1.2, 3.4), (0.0, -0.6, 0.6), yfov_deg=50.0))
    return s


def render(graph, output: str, skip: bool, effects=None) -> np.ndarray:
    """One frame of lit_spheres_scene at 48x32; skip False: the traversal compiled without it."""
    from rayvr.gpu import get_context

    scene = lit_spheres_scene()
    for name, effect in (effects or {}).items():
        scene.materials[name].effect = effect
    gs = GpuScene(get_context(), scene)
    if not skip:
        defines = gs.defines
        gs.defines = lambda: {**defines(), "RQ_CONVEX_SKIP": 0}
    with rv.Renderer(scene, graph, size=(48, 32), gpu_scene=gs) as r:
        r.render()
        image = np.asarray(r.read_output(output))[..., :3].astype(np.float64)
    gs.release()
    assert np.isfinite(image).all() and image.mean() > 0.01
    return image


@pytest.mark.parametrize("kernel", ["megakernel", "wavefront"])
def test_path_traced_image_is_the_same_with_the_skip_as_without(kernel):
    def graph():
        g = rv.graphs.path_traced(samples_per_pixel=2, max_bounces=3)
        g.get_pass("PathTracer").set_properties({"kernel": kernel})
        return g

    skip, full = render(graph(), "Accumulate.dst", True), render(graph(), "Accumulate.dst", False)
    np.testing.assert_allclose(skip, full, rtol=1e-4, atol=1e-5 * full.max())


@pytest.mark.parametrize("gbuffer,direct,gi", [("raster", None, None), ("rt", None, None), ("rt", "restir", None),
                                               ("rt", None, "probes")])
def test_hybrid_image_is_the_same_with_the_skip_as_without(gbuffer, direct, gi):
    """Shadow and reflection rays from the G-buffer (raster or ray traced) skip as path vertices do:
    the G-buffer keeps each texel's exit instance; so do the shadow rays of the probes' rays (the
    probe ray record carries it from the shading stage to the shadow stage)."""
    def graph():
        return rv.graphs.hybrid(preset="raw", gbuffer=gbuffer, gi=gi, **({"direct": direct} if direct else {}))

    effects = {"M": rv.Effect.REFLECTIONS}
    skip = render(graph(), "Composite.color", True, effects)
    full = render(graph(), "Composite.color", False, effects)
    np.testing.assert_allclose(skip, full, rtol=1e-4, atol=1e-5 * full.max())
