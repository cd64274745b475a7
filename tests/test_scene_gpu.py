"""GpuScene: feature pruning, material and light tables read back through the GLSL library,
the one-call raster draw, and robust ray origins."""
import math

import numpy as np
import pytest

import rayvr as rv
from rayvr.gpu import compute_program, get_context, raster_program
from rayvr.gpu.bindings import BINDINGS
from rayvr.scene import FEATURES, GpuScene, Material, Mesh, Scene, TextureRef, Texture
from rayvr.scene import builtin

OUT = BINDINGS["RAYVR_PASS_SSBO_1"]
IN = BINDINGS["RAYVR_PASS_SSBO_0"]


def run_kernel(gl, tmp_path, gs, body, inputs, out_vec4s, defines=None, includes=("lights.glsl", "ray_query.glsl")):
    """Run `body` once per input vec4 (variable `q`, index `i`); it writes out[i * out_vec4s + k]."""
    src = "\n".join(f'#include "{inc}"' for inc in includes) + f"""
layout(local_size_x = 32) in;
layout(std430, binding = RAYVR_PASS_SSBO_0) readonly buffer In {{ vec4 inputs[]; }};
layout(std430, binding = RAYVR_PASS_SSBO_1) writeonly buffer Out {{ vec4 out_[]; }};
void main() {{
    uint i = gl_GlobalInvocationID.x;
    if (i >= uint(inputs.length())) return;
    vec4 q = inputs[i];
    {body}
}}
"""
    path = tmp_path / f"k{abs(hash(src))}.comp"
    path.write_text(src)
    prog = compute_program(gl, path, defines if defines is not None else gs.defines())
    data = np.ascontiguousarray(inputs, np.float32).reshape(-1, 4)
    ib, ob = gl.buffer(data.tobytes()), gl.buffer(reserve=len(data) * out_vec4s * 16)
    gs.bind()
    ib.bind_to_storage_buffer(IN)
    ob.bind_to_storage_buffer(OUT)
    prog.run((len(data) + 31) // 32)
    out = np.frombuffer(ob.read(), np.float32).reshape(len(data), out_vec4s, 4).copy()
    ib.release(), ob.release()
    return out, prog


def test_absent_features_allocate_nothing_and_compile_no_code(gl, tmp_path):
    s = builtin.plane_with_point_light()
    gs = GpuScene(get_context(), s)
    d = gs.defines()
    assert d["SCENE_HAS_PUNCTUAL_LIGHTS"] == 1
    assert all(d[f] == 0 for f in FEATURES if f != "SCENE_HAS_PUNCTUAL_LIGHTS")
    assert "punctual_lights" in gs.buffers
    assert not {"emissive_triangles", "tangents"} & set(gs.buffers) and gs.texture_array is None
    rep = gs.report()
    assert rep["left_out"]["SCENE_HAS_EMISSIVE_TRIANGLES"] == "emissive_triangles buffer"
    assert rep["left_out"]["SCENE_HAS_TEXTURES"] == "texture array"
    assert "SCENE_HAS_TRANSMISSION" in rep["left_out"] and rep["bytes_per_triangle"] > 0
    body = ("LightSample l = sample_light(q.xyz, vec3(0.5)); MaterialParams m = material_params(0u, vec2(0.5));"
            "out_[i] = vec4(l.weight.x, m.transmission, m.base_color.r, 0.0);")
    out, prog = run_kernel(gl, tmp_path, gs, body, [[0, 0, 0, 0]], 1)
    assert "PunctualLights" in prog and "EmissiveTriangles" not in prog and "scene_textures" not in prog
    np.testing.assert_allclose(out[0, 0, 0], 1.0, rtol=1e-5)   # I / d^2 at 1 m


def test_transmission_code_exists_only_when_the_scene_has_it(gl, tmp_path):
    s = builtin.quad(material=Material("Glass", transmission=0.75, ior=1.4))
    gs = GpuScene(get_context(), s)
    assert gs.defines()["SCENE_HAS_TRANSMISSION"] == 1
    body = "MaterialParams m = material_params(0u, vec2(0.5)); out_[i] = vec4(m.transmission, m.ior, 0, 0);"
    out, _ = run_kernel(gl, tmp_path, gs, body, [[0, 0, 0, 0]], 1)
    np.testing.assert_allclose(out[0, 0, :2], [0.75, 1.4], rtol=1e-6)
    out, _ = run_kernel(gl, tmp_path, gs, body, [[0, 0, 0, 0]], 1, defines={**gs.defines(), "SCENE_HAS_TRANSMISSION": 0})
    assert out[0, 0, 0] == 0.0   # the same data, but no code reads it


def test_material_table_matches_and_follows_edits(gl, tmp_path):
    s = builtin.cornell_box()
    gs = GpuScene(get_context(), s)
    n = len(s.materials)
    body = ("MaterialParams m = material_params(uint(q.x), vec2(0.0));"
            "out_[2u * i] = vec4(m.base_color, m.roughness);"
            "out_[2u * i + 1u] = vec4(m.emissive, float(m.effect));")
    inputs = [[k, 0, 0, 0] for k in range(n)]
    out, _ = run_kernel(gl, tmp_path, gs, body, inputs, 2)
    for k, m in enumerate(s.materials):
        np.testing.assert_allclose(out[k, 0], [*m.base_color[:3], m.roughness], rtol=1e-6)
        np.testing.assert_allclose(out[k, 1], [*m.emission, int(m.effect)], rtol=1e-6)
    s.materials["Floor"].effect = rv.Effect.REFLECTIONS
    gs.update(np.zeros(3))
    out, _ = run_kernel(gl, tmp_path, gs, body, inputs, 2)
    assert out[s.materials.index("Floor"), 1, 3] == int(rv.Effect.REFLECTIONS)


def srgb_to_linear(c):
    c = np.asarray(c, np.float64)
    return np.where(c > 0.04045, ((c + 0.055) / 1.055) ** 2.4, c / 12.92)


def test_textures_with_khr_texture_transform(gl, tmp_path):
    rng = np.random.default_rng(0)
    img = rng.integers(0, 256, size=(4, 4, 4), dtype=np.uint8)
    img[..., 3] = 255
    ref = TextureRef(0, offset=(0.25, -0.5), rotation=0.3, scale=(0.5, 2.0))
    mat = Material("Tex", base_color=(1.0, 0.5, 1.0, 1.0), base_color_texture=ref)
    s = builtin.quad(material=mat)
    s.textures.append(Texture(img))
    gs = GpuScene(get_context(), s)
    assert gs.defines()["SCENE_HAS_TEXTURES"] == 1
    m = ref.uv_matrix()
    full = np.vstack([m, [0, 0, 1]])
    inputs, expect = [], []
    for r in range(4):
        for c in range(4):
            target = np.array([(c + 0.5) / 4, (r + 0.5) / 4, 1.0])     # texel centre, glTF uv (v down)
            uv = np.linalg.solve(full, target)[:2]
            inputs.append([uv[0], uv[1], 0, 0])
            expect.append(srgb_to_linear(img[r, c, :3] / 255.0) * [1.0, 0.5, 1.0])
    body = "MaterialParams m = material_params(0u, q.xy); out_[i] = vec4(m.base_color, m.alpha);"
    out, _ = run_kernel(gl, tmp_path, gs, body, inputs, 1)
    np.testing.assert_allclose(out[:, 0, :3], expect, atol=2e-3)


def test_punctual_lights_match_the_gltf_formulas(gl, tmp_path):
    s = builtin.quad()
    s.lights = [
        rv.scene.Light("point", position=(0, 2, 0), intensity=4.0, color=(1, 0.5, 0.25)),
        rv.scene.Light("spot", position=(0, 2, 0), direction=(0, -1, 0), intensity=10.0,
                       inner_cone_angle=0.2, outer_cone_angle=0.6, range=5.0),
        rv.scene.Light("directional", direction=(0, -1, 1), intensity=3.0),
    ]
    origin = np.array([100.0, 0.0, 0.0])
    gs = GpuScene(get_context(), s)
    gs.update(origin)
    pts = np.array([[0, 0, 0], [0.5, 0, 0], [1.0, 0, 0.5], [3, -1, 0]], float)
    inputs = [[*(p - origin), k] for k in range(3) for p in pts]
    body = ("LightSample l = eval_punctual_light(uint(q.w), q.xyz);"
            "out_[2u * i] = vec4(l.weight, l.distance); out_[2u * i + 1u] = vec4(l.direction, l.pdf);")
    out, _ = run_kernel(gl, tmp_path, gs, body, inputs, 2)
    for n, (x, y, z, k) in enumerate(inputs):
        p = np.array([x, y, z]) + origin
        L = s.lights[int(k)]
        if L.type == 2:
            np.testing.assert_allclose(out[n, 0, :3], [3, 3, 3], rtol=1e-6)
            np.testing.assert_allclose(out[n, 1, :3], -L.direction, rtol=1e-6)
            continue
        to = L.position - p
        d = np.linalg.norm(to)
        w = L.intensity * np.asarray(L.color) / d**2
        if L.type == 1:
            cd = np.dot(L.direction, -to / d)
            lo, hi = math.cos(L.outer_cone_angle), math.cos(L.inner_cone_angle)
            w = w * np.clip((cd - lo) / (hi - lo), 0, 1) ** 2 * np.clip(1 - (d / L.range) ** 4, 0, 1) ** 2
        np.testing.assert_allclose(out[n, 0, :3], w, rtol=1e-4, atol=1e-7)
        np.testing.assert_allclose(out[n, 0, 3], d, rtol=1e-5)
        np.testing.assert_allclose(out[n, 1, :3], to / d, rtol=1e-5, atol=1e-6)
        assert out[n, 1, 3] == 0.0


def polygon_irradiance(p, n, verts, radiance):
    """Lambert's formula: irradiance at p (normal n) from a uniformly emitting polygon."""
    v = [(q - p) / np.linalg.norm(q - p) for q in verts]
    total = 0.0
    for a, b in zip(v, v[1:] + v[:1]):
        g = np.cross(a, b)
        total += math.acos(np.clip(np.dot(a, b), -1, 1)) * np.dot(g / np.linalg.norm(g), n)
    return abs(total) / 2 * np.asarray(radiance)


def test_emissive_triangles_sampled_by_power_give_the_right_irradiance(gl, tmp_path):
    s = builtin.cornell_box()
    light = s.meshes[[i.name for i in s.instances].index("Light")]
    # a degenerate emissive triangle must be left out of the table
    deg = s.add_mesh(Mesh("Sliver", [[0, 0.3, 0], [0.1, 0.3, 0], [0.2, 0.3, 0]], [[0, 1, 2]], s.materials.index("Light")))
    s.add_instance(deg)
    gs = GpuScene(get_context(), s)
    assert gs.emissive_count == 2
    p = np.array([0.05, 0.0, -0.02])
    k = 64
    g = (np.arange(k) + 0.5) / k
    inputs = [[a, b, c, 0] for a in (0.25, 0.75) for b in g for c in g]
    body = (f"LightSample l = sample_light(vec3({p[0]}, {p[1]}, {p[2]}), q.xyz);"
            "out_[i] = l.valid ? vec4(l.weight * max(l.direction.y, 0.0), l.pdf) : vec4(0.0);")
    out, _ = run_kernel(gl, tmp_path, gs, body, inputs, 1)
    estimate = out[:, 0, :3].mean(axis=0)
    verts = list(light.positions.astype(float))
    exact = polygon_irradiance(p, np.array([0, 1.0, 0]), verts, s.materials["Light"].emission)
    np.testing.assert_allclose(estimate, exact, rtol=0.01)
    assert (out[:, 0, 3] > 0).all()


def test_draw_renders_every_instance_in_one_call(gl, tmp_path):
    vs = tmp_path / "d.vert"
    vs.write_text("""
#include "scene.glsl"
in uint rayvr_instance;
flat out uint v_material;
void main() {
    RasterVertex v = scene_raster_vertex(rayvr_instance, gl_VertexID);
    v_material = v.material;
    gl_Position = vec4(v.position.xy * 0.4, 0.0, 1.0);
}
""")
    fs = tmp_path / "d.frag"
    fs.write_text("""
flat in uint v_material;
out uint colour;
void main() { colour = v_material + 1u; }
""")
    s = builtin.mirror_and_checker(tiles=2)   # the checker at z = 2 and the mirror at z = 0 overlap in xy
    t = np.eye(4)
    t[:3, 3] = (1.5, 0, 0)
    s.instances[1].transform = t              # move the checker right: both visible
    gs = GpuScene(get_context(), s)
    prog = raster_program(gl, vs, fs, gs.defines())
    tex = gl.texture((40, 20), 1, dtype="u4")
    fbo = gl.framebuffer([tex])
    fbo.use()
    fbo.clear()
    gs.bind()
    gs.draw(prog, 1)
    img = np.frombuffer(tex.read(), np.uint32).reshape(20, 40)
    gl.screen.use() if gl.screen is not None else None
    # x in [-1, 1] * 0.4 -> pixels 12..28 for the mirror; checker x in [0.5, 2.5] * 0.4 -> 24..40
    assert img[10, 14] == 1                                   # Mirror (material 0)
    right = img[7:13, 30:40]                                  # y in [-0.4, 0.4] -> rows 6..14
    assert set(np.unique(right)) == {2, 3}                    # the two checker materials
    assert img[10, 2] == 0                                    # background


@pytest.mark.parametrize("scale", [1.0, 3e4])
def test_offset_ray_origin_prevents_self_intersection(gl, tmp_path, scale):
    import trimesh

    ico = trimesh.creation.icosphere(subdivisions=3, radius=scale)
    s = Scene("sphere")
    s.add_material(Material("M"))
    t = np.eye(4)
    t[:3, 3] = (2.5 * scale, 0.5 * scale, -1.5 * scale)     # far from the render origin too
    s.add_object("S", ico.vertices, ico.faces, 0, t)
    gs = GpuScene(get_context(), s)
    rng = np.random.default_rng(5)
    n = 2048
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    o = t[:3, 3] - 3 * scale * d
    body = """
    vec3 d = normalize(q.xyz - (vec3(%r, %r, %r)));
    Hit h;
    bool hit = trace_closest(q.xyz, -d, 1e29, h);
    SurfacePoint sp = surface_at(h, -d);
    vec3 o2 = offset_ray_origin(sp.position, sp.geometric_normal);
    // leave the convex surface into its outer hemisphere: must hit nothing
    vec3 w = normalize(sp.geometric_normal + 0.9 * normalize(cross(sp.geometric_normal, vec3(0.3, 0.5, 0.7))));
    bool self_hit = trace_occluded(o2, w, 1e29);
    out_[i] = vec4(hit ? 1.0 : 0.0, self_hit ? 1.0 : 0.0, dot(sp.geometric_normal, d), 0.0);
    """ % tuple(float(x) for x in t[:3, 3])
    out, _ = run_kernel(gl, tmp_path, gs, body, np.c_[o, np.zeros(n)], 1)
    assert out[:, 0, 0].all()
    assert (out[:, 0, 2] > 0).all()        # the normal faces the incoming ray (direction -d)
    assert out[:, 0, 1].sum() == 0


@pytest.mark.parametrize("bvh_layout", ["bvh2", "bvh4", "bvh4q", "bvh8"])
def test_alpha_masked_materials_are_skipped_by_rays(gl, tmp_path, bvh_layout):
    img = np.full((2, 2, 4), 200, np.uint8)
    img[..., 3] = [[255, 0], [0, 255]]                        # texel (row, col): opaque on the diagonal
    rays = [[-0.25, -0.25, 1, 0], [0.25, -0.25, 1, 0], [-0.25, 0.25, 1, 0], [0.25, 0.25, 1, 0]]
    body = ("Hit h; bool hit = trace_closest(q.xyz, vec3(0, 0, -1), 1e29, h);"
            "bool occ = trace_occluded(q.xyz, vec3(0, 0, -1), 1e29);"
            "out_[i] = vec4(hit ? 1.0 : 0.0, occ ? 1.0 : 0.0, 0.0, 0.0);")
    # BLEND is stochastic transparency (tests/test_alpha_blend.py): alpha 0 is never hit, 1 always
    for mode, expect in (("MASK", [1, 0, 0, 1]), ("BLEND", [1, 0, 0, 1]), ("OPAQUE", [1, 1, 1, 1])):
        mat = Material("Leaf", alpha_mode=mode, alpha_cutoff=0.5, base_color_texture=TextureRef(0))
        s = builtin.quad(material=mat)
        s.textures.append(Texture(img))
        gs = GpuScene(get_context(), s, bvh_layout=bvh_layout)
        assert gs.defines()["SCENE_HAS_ALPHA_MASK"] == (mode == "MASK")
        assert gs.defines()["SCENE_HAS_ALPHA_BLEND"] == (mode == "BLEND")
        assert gs.defines()["RQ_BVH_WIDTH"] == {"bvh2": 2, "bvh8": 8}.get(bvh_layout, 4)
        assert gs.defines()["RQ_BVH_QUANTIZED"] == (bvh_layout in ("bvh4q", "bvh8"))
        out, _ = run_kernel(gl, tmp_path, gs, body, rays, 1)
        np.testing.assert_array_equal(out[:, 0, 0], expect)
        np.testing.assert_array_equal(out[:, 0, 1], expect)


def test_normal_maps_tilt_the_shading_normal(gl, tmp_path):
    theta = math.radians(30)
    n_ts = np.array([math.sin(theta), 0.0, math.cos(theta)])
    img = np.zeros((2, 2, 4), np.uint8)
    img[..., :3] = np.round((n_ts + 1) / 2 * 255)
    img[..., 3] = 255
    mat = Material("Bumpy", normal_texture=TextureRef(0), metallic=0.0)
    s = builtin.quad(material=mat)
    s.meshes[0].tangents = np.tile(np.array([1, 0, 0, 1], np.float32), (4, 1))
    s.textures.append(Texture(img, srgb=False))
    t = np.eye(4)
    t[:3, :3] = [[0, 0, 1], [0, 1, 0], [-1, 0, 0]]            # turn the quad to face +X
    s.instances[0].transform = t
    gs = GpuScene(get_context(), s)
    assert gs.defines()["SCENE_HAS_NORMAL_MAPS"] == 1
    body = ("Hit h; bool hit = trace_closest(q.xyz, vec3(-1, 0, 0), 1e29, h);"
            "SurfacePoint sp = surface_at(h, vec3(-1, 0, 0));"
            "out_[i] = vec4(sp.normal, hit ? 1.0 : 0.0);")
    out, _ = run_kernel(gl, tmp_path, gs, body, [[1.0, 0.1, 0.1, 0]], 1)
    assert out[0, 0, 3] == 1
    expect = t[:3, :3] @ n_ts                                 # tangent +X -> world -Z, normal +Z -> +X
    np.testing.assert_allclose(out[0, 0, :3], expect, atol=1e-2)


def test_a_scene_too_large_for_the_gpu_is_refused_naming_the_buffer(gl, monkeypatch):
    # pretend the driver's SSBO limit is 1 KiB: the spheres' vertex buffer is larger
    monkeypatch.setitem(gl.info, "GL_MAX_SHADER_STORAGE_BLOCK_SIZE", 1024)
    with pytest.raises(rv.SceneError, match=r"scene 'spheres': the \w+ buffer needs .* shader storage block limit"):
        GpuScene(get_context(), builtin.spheres())
