"""PathTracer against analytic values: a furnace (emissive, reflective sphere seen from inside) vs a
numerical solution of its integral equation, an emitter seen directly, NEE under a point light vs
the closed form, the G-buffer mode, determinism, and no NaN/Inf in hostile cases."""
import numpy as np
import pytest

import rayvr as rv
from rayvr.errors import OptionError
from rayvr.materials.material import Material
from rayvr.passes.accumulate import Accumulate
from rayvr.passes.path_tracer import PathTracer
from rayvr.renderer import Renderer
from rayvr.scene import builtin
from rayvr.scene.model import Camera, Light, Scene
from test_pipeline_analytic import lambert_point   # the closed form the hybrid passes are held to


def pt_graph(accumulate=True, **props):
    g = rv.RenderGraph("PT")
    g.add_pass(PathTracer(**props), "PT")
    if accumulate:
        g.add_pass(Accumulate(), "Acc")
        g.add_edge("PT.color", "Acc.src")
        g.mark_output("Acc.dst")
    g.mark_output("PT.color")
    return g


def render_pt(scene, frames=1, size=(16, 16), **props):
    """Mean radiance (layers, h, w, 3) float64 over `frames` frames."""
    with Renderer(scene, pt_graph(**props), size=size) as r:
        for _ in range(frames):
            r.render()
        return r.read_output("Acc.dst")[..., :3].astype(np.float64)


def sphere_furnace_radiance(albedo, emission, n=128):
    """Radiance leaving the inside of a uniformly emitting sphere along its normal, for the glTF
    BSDF with metallic 0 and roughness 1 (bsdf_reference: the compensated GGX layer over the
    albedo-scaled Lambert base). A chord meets the sphere at equal angles at both ends, so the
    radiance depends only on the angle t to the normal: L(t) = E + integral f(t, t') cos t' L(t') dw';
    solved by quadrature."""
    from bsdf_reference import Bsdf

    t = (np.arange(n) + 0.5) * (np.pi / 2) / n
    phi = (np.arange(n) + 0.5) * 2 * np.pi / n
    to, ti, ph = np.meshgrid(t, t, phi, indexing="ij")
    v = np.stack([np.sin(to), np.zeros_like(to), np.cos(to)], -1)
    l = np.stack([np.sin(ti) * np.cos(ph), np.sin(ti) * np.sin(ph), np.cos(ti)], -1)
    fcos = Bsdf((albedo,) * 3, metallic=0.0, roughness=1.0).eval(v, l)[..., 0]
    k = (fcos * np.sin(ti)).sum(-1) * (np.pi / 2 / n) * (2 * np.pi / n)
    return np.linalg.solve(np.eye(n) - k, np.full(n, emission))[0]


def furnace_scene(albedo, emission):
    import trimesh

    s = Scene("furnace")
    s.add_material(Material("Wall", base_color=(albedo, albedo, albedo, 1.0), metallic=0.0, roughness=1.0,
                            emissive=(1.0, 1.0, 1.0), emissive_strength=emission))
    ico = trimesh.creation.icosphere(subdivisions=3, radius=1.0)
    # wound inwards: the front faces (and emission) look at the centre
    s.add_object("Sphere", ico.vertices, ico.faces[:, ::-1].copy(), 0, normals=-ico.vertex_normals)
    s.cameras.append(Camera.look_at((0, 0, 0), (0, 0, -1), yfov_deg=60.0))
    return s


@pytest.mark.parametrize("albedo", [0.0, 0.5])
def test_furnace_converges_to_the_integral_equation(gpu, albedo):
    want = sphere_furnace_radiance(albedo, 1.0)
    color = render_pt(furnace_scene(albedo, 1.0), frames=2, size=(16, 16), samples_per_pixel=4, max_bounces=64)
    assert np.isfinite(color).all()
    assert color.mean() == pytest.approx(want, rel=0.015)
    # the naive E / (1 - albedo) ignores the specular layer and the base's albedo scaling; the
    # render must see them
    if albedo:
        assert abs(color.mean() - 1.0 / (1.0 - albedo)) > 0.02


def emissive_quad(double_sided=False):
    m = builtin.lambert("Lamp", (0.5, 0.5, 0.5), emissive=(1.0, 0.5, 0.25), emissive_strength=3.0,
                        double_sided=double_sided)
    return builtin.quad(size=2.0, material=m)


def test_emitter_seen_directly_gives_its_radiance_front_only(gpu):
    front = render_pt(emissive_quad(), frames=1, samples_per_pixel=2)
    centre = front[0, 4:12, 4:12]
    np.testing.assert_allclose(centre, np.broadcast_to([3.0, 1.5, 0.75], centre.shape), rtol=1e-6)
    back_scene = emissive_quad()
    back_scene.cameras[:] = [Camera.look_at((0, 0, -2), (0, 0, 0))]
    assert render_pt(back_scene, frames=1)[0, 4:12, 4:12].max() == 0.0
    two_sided = emissive_quad(double_sided=True)
    two_sided.cameras[:] = [Camera.look_at((0, 0, -2), (0, 0, 0))]
    np.testing.assert_allclose(render_pt(two_sided, frames=1)[0, 8, 8], [3.0, 1.5, 0.75], rtol=1e-6)


def plane_radiance_through_pixels(view, size, offset, intensity=2.0):
    """Closed-form radiance of plane_with_point_light seen through (x, y) + offset of every pixel."""
    ys, xs = np.mgrid[0:size[1], 0:size[0]]
    rays = [view.primary_ray((x + offset[0], y + offset[1])) for x, y in zip(xs.ravel(), ys.ravel())]
    o = np.array([ro for ro, _ in rays])
    d = np.array([rd for _, rd in rays])
    p = o + (-o[:, 1] / d[:, 1])[:, None] * d
    want = lambert_point(p, np.array([0.0, 1.0, 0.0]), intensity, 0.8, eye=view.pose.position)
    inside = (np.abs(p[:, 0]) < 1.9) & (np.abs(p[:, 2]) < 1.9)
    return want.reshape(size[1], size[0]), inside.reshape(size[1], size[0])


def test_next_event_estimation_matches_point_light_closed_form(gpu):
    from rayvr.rendergraph.render_pass import RenderContext

    scene = builtin.plane_with_point_light(height=1.0, intensity=2.0, albedo=0.8)
    size = (16, 16)
    with Renderer(scene, pt_graph(max_bounces=1, pixel_jitter=False), size=size) as r:
        r.render()
        color = r.read_output("PT.color")[0, ..., 0].astype(np.float64)
        view = r.view_set[0]
        want, inside = plane_radiance_through_pixels(view, size, (0.5, 0.5))
        np.testing.assert_allclose(color[inside], want[inside], rtol=2e-3)
        # the views' TAA jitter moves the rays off the pixel centres
        r.views_buffer.write(r.view_set.pack(r.view_set.origin(), 1, 0, jitter=(0.25, -0.25)))
        r.compiled.execute(RenderContext(r.gl, r.gpu.caps, scene=r.gpu_scene, views_buffer=r.views_buffer,
                                         view_set=r.view_set, frame_index=1))
        jittered = r.read_output("PT.color")[0, ..., 0].astype(np.float64)
    want, inside = plane_radiance_through_pixels(view, size, (0.75, 0.25))
    np.testing.assert_allclose(jittered[inside], want[inside], rtol=2e-3)
    assert np.abs(jittered - color)[inside].max() > 1e-3


def test_all_views_in_one_dispatch_each_view_its_own_rays(gpu):
    scene = builtin.plane_with_point_light(height=1.0, intensity=2.0, albedo=0.8)
    size = (16, 16)
    with Renderer(scene, pt_graph(max_bounces=1, pixel_jitter=False), views=2, size=size) as r:
        r.render()
        color = r.read_output("PT.color")[..., 0].astype(np.float64)
        views = list(r.view_set)
    assert color.shape[0] == 2 and np.abs(color[0] - color[1]).max() > 1e-3
    for layer, view in enumerate(views):
        want, inside = plane_radiance_through_pixels(view, size, (0.5, 0.5))
        np.testing.assert_allclose(color[layer][inside], want[inside], rtol=2e-3)


def gbuffer_pt_graph(pixel_list=False, **props):
    from rayvr.passes import EffectCompaction, GBufferRaster
    from rayvr.passes.gbuffer import channels

    g = rv.RenderGraph("HybridPT")
    g.add_pass(GBufferRaster(), "GBuffer")
    g.add_pass(PathTracer(mode="gbuffer", **props), "PT")
    channels.wire(g, "GBuffer", "PT")
    if pixel_list:
        g.add_pass(EffectCompaction(path_list=True), "Compaction")
        g.add_edge("GBuffer.effect", "Compaction.effect")
        g.add_edge("Compaction.pathPixels", "PT.pixels")
    g.mark_output("PT.color")
    g.mark_output("GBuffer.posW")
    return g


@pytest.mark.parametrize("pixel_list", [False, True])
def test_gbuffer_mode_traces_only_path_traced_pixels(gpu, pixel_list):
    scene = builtin.box_on_plane(light_height=3.0)
    scene.materials["Plane"].effect = rv.Effect.PATH_TRACED
    scene.materials["Box"].effect = rv.Effect.SHADOWS
    with Renderer(scene, gbuffer_pt_graph(pixel_list, max_bounces=1), size=(16, 16)) as r:
        r.render()
        color = r.read_output("PT.color")[0, ..., 0].astype(np.float64)
        pos = r.read_output("GBuffer.posW")[0].astype(np.float64)
        eye = r.view_set[0].pose.position
        origin = r.view_set.origin()
    p = pos[..., :3] + origin
    on_plane = (pos[..., 3] > 0) & (np.abs(p[..., 1]) < 1e-4)
    box = (pos[..., 3] > 0) & ~on_plane
    assert box.sum() > 10 and on_plane.sum() > 100
    if not pixel_list:
        assert np.all(color[box] == 0.0)   # not PATH_TRACED: written as 0 (a list leaves them untouched)
    # plane points the box does not hide from the light at (0, 3, 0): the closed form
    lit = on_plane & (np.maximum(np.abs(p[..., 0]), np.abs(p[..., 2])) > 0.45)
    want = lambert_point(p, np.array([0.0, 3.0, 0.0]), 10.0, 0.8, eye=eye)
    np.testing.assert_allclose(color[lit], want[lit], rtol=5e-3)


def test_gbuffer_mode_is_pruned_without_path_traced_materials(gpu):
    scene = builtin.box_on_plane()
    plan = gbuffer_pt_graph().plan(scene=scene, size=(16, 16))
    assert "PT" in plan.pruned
    assert PathTracer(mode="gbuffer").skip_reason(
        rv.rendergraph.render_pass.CompileData(scene=scene)) == "no material uses PATH_TRACED"


def test_paths_are_deterministic_per_frame_and_differ_between_frames(gpu):
    scene = furnace_scene(0.5, 1.0)
    g = pt_graph(samples_per_pixel=1, max_bounces=3)
    with Renderer(scene, g, size=(16, 16)) as r:
        r.render()
        first = r.read_output("PT.color")
        r.render()
        second = r.read_output("PT.color")
    with Renderer(scene, g, size=(16, 16)) as r:
        r.render()
        again = r.read_output("PT.color")
    np.testing.assert_array_equal(first, again)
    assert np.abs(first - second).max() > 0


def hostile_scene():
    """A mirror (roughness 0), a tiny blinding emitter, a point light on the floor, grazing views."""
    s = Scene("hostile")
    s.add_material(Material("Mirror", base_color=(1, 1, 1, 1), metallic=1.0, roughness=0.0))
    s.add_material(Material("Smooth", base_color=(0.9, 0.9, 0.9, 1), metallic=0.0, roughness=0.0))
    s.add_material(builtin.lambert("Sun", (0, 0, 0), emissive=(1, 1, 1), emissive_strength=1e7))
    s.add_object("Floor", *builtin.quad_mesh([(-4, 0, -4), (4, 0, -4), (4, 0, 4), (-4, 0, 4)], (0, 1, 0)), "Mirror")
    s.add_object("Wall", *builtin.quad_mesh([(-4, 0, -3), (4, 0, -3), (4, 3, -3), (-4, 3, -3)], (0, 0, 1)), "Smooth")
    s.add_object("Sun", *builtin.quad_mesh([(0, 2, -2), (1e-3, 2, -2), (1e-3, 2, -2 + 1e-3), (0, 2, -2 + 1e-3)],
                                            (0, -1, 0)), "Sun")
    s.lights.append(Light("point", position=(0.0, 0.0, -1.0), intensity=5.0))
    s.cameras.append(Camera.look_at((0, 1e-3, 3), (0, 1e-3, -3), yfov_deg=80.0))   # grazing the floor
    return s


@pytest.mark.parametrize("clamp", [0.0, 4.0])
def test_no_nan_or_inf_in_hostile_cases_and_clamp_caps(gpu, clamp):
    color = render_pt(hostile_scene(), frames=2, size=(16, 16), samples_per_pixel=2, max_bounces=6, clamp=clamp)
    assert np.isfinite(color).all() and (color >= 0).all()
    assert color.max() > 0
    if clamp:
        assert color.max() <= clamp * (1 + 1e-6)


def test_bad_properties_name_the_pass_and_property():
    with pytest.raises(OptionError, match="'mode'.*'full' or 'gbuffer'"):
        PathTracer(mode="hybrid")
    with pytest.raises(OptionError, match="samples_per_pixel"):
        PathTracer(samples_per_pixel=0)
    with pytest.raises(OptionError, match="background"):
        PathTracer(background=[1, 2])
