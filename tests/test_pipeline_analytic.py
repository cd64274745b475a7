"""The hybrid pipeline against analytic values: Lambert shading under a point light, a shadow edge
where geometry puts it, a mirror reflecting a known checker, pruning of ray work, no NaN/Inf."""
import numpy as np
import pytest

import rayvr as rv
from rayvr.passes.compaction import read_pixel_list
from rayvr.renderer import Renderer
from rayvr.scene import builtin

SIZE = (40, 40)


def render(scene, extra_outputs=(), size=SIZE, views=1, **graph_kw):
    g = rv.graphs.hybrid(preset="raw", **graph_kw)
    for o in extra_outputs:
        g.mark_output(o)
    r = Renderer(scene, g, views=views, size=size)
    r.render()
    return r


def world_positions(r):
    pos = r.read_output("GBuffer.posW")
    return pos[..., :3].astype(np.float64) + r.view_set.origin(), pos[..., 3] > 0


def material_ids(r):
    e = r.read_output("GBuffer.effect")[..., 0]
    return np.where((e & 0xFF) == 0xFF, -1, (e >> 8).astype(np.int64))


def lambert_point(p, light, intensity, albedo, normal=(0, 1, 0), eye=None):
    """Radiance of a Lambertian surface (rayvr.scenes' lambert materials: no specular layer) under
    a point light: albedo / pi * I cos / r^2, whatever the eye (`eye` kept for the callers' record)."""
    n = np.asarray(normal, dtype=np.float64)
    to = light - p
    d2 = (to ** 2).sum(-1)
    l = to / np.sqrt(d2)[..., None]
    cos = np.clip((l * n).sum(-1), 0, None)
    return albedo / np.pi * intensity * cos / d2


@pytest.mark.parametrize("effect", [rv.Effect.RASTER, rv.Effect.SHADOWS])
def test_lambert_plane_under_point_light_matches_cos_over_r2(gpu, effect):
    scene = builtin.plane_with_point_light(height=1.0, intensity=1.0, albedo=0.8)
    scene.materials["Plane"].effect = effect
    with render(scene, ["GBuffer.posW"]) as r:
        color = r.read_output("Composite.color")[..., :3].astype(np.float64)
        p, hit = world_positions(r)
    assert hit.all()
    want = lambert_point(p, np.array([0.0, 1.0, 0.0]), 1.0, 0.8, eye=r.view_set[0].pose.position)
    np.testing.assert_allclose(color[..., 0], want, rtol=5e-3, atol=1e-4)
    np.testing.assert_allclose(color[..., 1], color[..., 0], rtol=1e-3)


def segment_hits_box(p, light, lo, hi):
    d = light - p
    with np.errstate(divide="ignore", invalid="ignore"):
        t0 = (lo - p) / d
        t1 = (hi - p) / d
    tmin = np.nanmax(np.minimum(t0, t1), axis=-1)
    tmax = np.nanmin(np.maximum(t0, t1), axis=-1)
    return (tmax >= np.maximum(tmin, 0)) & (tmin <= 1)


def test_shadow_edge_lands_where_geometry_says(gpu):
    from rayvr.scene.model import Camera

    scene = builtin.box_on_plane(light_height=1.0)
    scene.cameras[:] = [Camera.look_at((0.0, 4.0, 0.001), (0.0, 0.0, 0.0))]
    light = np.array([0.0, 1.0, 0.0])
    with render(scene, ["GBuffer.posW", "GBuffer.effect"], size=(64, 64)) as r:
        color = r.read_output("Composite.color")[0, ..., 0].astype(np.float64)
        p, _ = world_positions(r)
        mats = material_ids(r)[0]
        eye = r.view_set[0].pose.position
    p = p[0]
    names = [m.name for m in scene.materials]
    plane = mats == names.index("Plane")
    lo, hi = np.array([-0.25, 0.0, -0.25]), np.array([0.25, 0.5, 0.25])
    surely_shadowed = segment_hits_box(p, light, lo + 2e-3, hi - 2e-3) & plane
    surely_lit = ~segment_hits_box(p, light, lo - 2e-3, hi + 2e-3) & plane
    assert surely_shadowed.sum() > 40 and surely_lit.sum() > 1000
    assert np.all(color[surely_shadowed] == 0.0)
    want = lambert_point(p, light, 10.0, 0.8, eye=eye)
    np.testing.assert_allclose(color[surely_lit], want[surely_lit], rtol=5e-3)
    # the shadow's extent is the light's projection of the box top: half-size 0.25 * 1 / 0.5
    dark = plane & (color < 1e-6) & (np.abs(p[..., 2]) < 0.1)
    assert np.abs(p[..., 0][dark]).max() == pytest.approx(0.5, abs=4.0 / 64)


def test_raster_material_gets_no_shadow_and_no_ray_work(gpu):
    scene = builtin.box_on_plane(light_height=3.0)
    for m in scene.materials:
        m.effect = rv.Effect.RASTER
    with render(scene, ["GBuffer.posW"]) as r:
        report = r.report()
        color = r.read_output("Composite.color")[0, ..., 0].astype(np.float64)
        p, _ = world_positions(r)
        assert {"Compaction", "Shadows", "Reflections"} <= set(r.compiled.plan.pruned)
        assert "Shadows" not in r.compiled.plan.order
    assert "every material is RASTER" in str(report)
    on_plane = np.abs(p[0][..., 1]) < 1e-4
    want = lambert_point(p[0], np.array([0.0, 3.0, 0.0]), 10.0, 0.8, eye=r.view_set[0].pose.position)
    np.testing.assert_allclose(color[on_plane], want[on_plane], rtol=5e-3)


def test_shadows_without_reflections_list_no_reflection_pixels(gpu):
    scene = builtin.box_on_plane()
    with render(scene, ["Compaction.shadowPixels", "Compaction.reflectionPixels"]) as r:
        n_shadow, _ = read_pixel_list(r.compiled.get_output("Compaction.shadowPixels"))
        n_refl, _ = read_pixel_list(r.compiled.get_output("Compaction.reflectionPixels"))
        assert "Reflections" in r.compiled.plan.pruned
    assert n_shadow == SIZE[0] * SIZE[1]
    assert n_refl == 0


@pytest.mark.parametrize("views", [1, 2])
def test_mirror_reflects_the_checker(gpu, views):
    """Each view's reflection rays start at that view's own eye (stereo registration of rays)."""
    tiles = 4
    scene = builtin.mirror_and_checker(tiles=tiles)
    with render(scene, ["GBuffer.posW", "GBuffer.effect"], size=(48, 48), views=views) as r:
        colors = r.read_output("Composite.color")[..., 0].astype(np.float64)
        positions, _ = world_positions(r)
        all_mats = material_ids(r)
        eyes = [v.pose.position for v in r.view_set.views]
    for color, p, mats, eye in zip(colors, positions, all_mats, eyes):
        mirror = mats == 0
        assert mirror.sum() > 100
        d = p - eye
        d[..., 2] *= -1                                   # reflect about the mirror plane z = 0
        t = (2.0 - p[..., 2]) / d[..., 2]
        q = p + d * t[..., None]                          # where the reflected ray meets the checker
        step = 2.0 / tiles
        fx, fy = (q[..., 0] + 1) / step, (q[..., 1] + 1) / step
        inside = (fx > 0) & (fx < tiles) & (fy > 0) & (fy < tiles)
        away_from_edges = (np.abs(fx - np.round(fx)) > 0.08) & (np.abs(fy - np.round(fy)) > 0.08)
        white = (np.floor(fx) + np.floor(fy)) % 2 == 0
        albedo = np.where(white, 0.9, 0.05)
        # the checker is seen from the mirror image of the eye
        mirrored_eye = eye * np.array([1.0, 1.0, -1.0])
        want = lambert_point(q, np.array([0.0, 0.0, 1.5]), 2.0, albedo, normal=(0, 0, -1), eye=mirrored_eye)
        sel = mirror & inside & away_from_edges
        assert sel.sum() > 100 and white[sel].any() and (~white[sel]).any()
        np.testing.assert_allclose(color[sel], want[sel], rtol=1e-2)


def test_grazing_views_and_roughness_zero_stay_finite(gpu):
    scene = builtin.mirror_and_checker(tiles=2)
    scene.materials["CheckerWhite"].roughness = 0.0
    scene.materials["CheckerWhite"].metallic = 0.0
    scene.materials["CheckerWhite"].effect = rv.Effect.REFLECTIONS
    scene.materials["Mirror"].roughness = 0.3
    from rayvr.scene.model import Camera
    scene.cameras[:] = [Camera.look_at((0.0, -0.999, 1.0), (0.0, 1.0, 1.0), up=(0, 0, 1))]  # along the planes
    with render(scene, size=(32, 32), max_bounces=2) as r:
        color = r.read_output("Composite.color")
        out = r.read_output()
    assert np.isfinite(color).all()
    assert out.dtype == np.uint8 and out.shape == (1, 32, 32, 4)


def area_light_over_plate():
    """A 0.5 m square emitter at y = 1 facing down, a 0.4 m square plate at y = 0.5, a plane at y = 0."""
    from rayvr.materials.material import Material
    from rayvr.scene.model import Camera, Scene

    s = Scene("area_light_over_plate")
    s.add_material(builtin.lambert("Plane", (0.8, 0.8, 0.8)))
    s.add_material(builtin.lambert("Plate", (0.5, 0.5, 0.5)))
    s.add_material(Material("Emitter", base_color=(0, 0, 0, 1), metallic=0.0, emissive=(10.0, 10.0, 10.0)))
    s.add_object("Plane", *builtin.quad_mesh([(-2, 0, -2), (2, 0, -2), (2, 0, 2), (-2, 0, 2)], (0, 1, 0)), "Plane")
    s.add_object("Plate", *builtin.quad_mesh([(-.2, .5, -.2), (.2, .5, -.2), (.2, .5, .2), (-.2, .5, .2)], (0, 1, 0)), "Plate")
    s.add_object("Emitter", *builtin.quad_mesh([(-.25, 1, -.25), (.25, 1, -.25), (.25, 1, .25), (-.25, 1, .25)],
                                               (0, -1, 0)), "Emitter")
    s.cameras.append(Camera.look_at((1.6, 1.2, 0.0), (0.2, 0.0, 0.0), yfov_deg=50.0))
    return s


def test_area_light_soft_shadow_matches_the_visible_light_fraction(gpu):
    images = {}
    for effect in (rv.Effect.RASTER, rv.Effect.SHADOWS):
        scene = area_light_over_plate()
        for m in scene.materials:
            m.effect = effect
        with render(scene, ["GBuffer.posW", "GBuffer.effect"], size=(32, 32), light_samples=128) as r:
            images[effect] = r.read_output("Composite.color")[0, ..., 0].astype(np.float64)
            p, _ = world_positions(r)
            mats = material_ids(r)[0]
    p = p[0]
    plane = (mats == 0) & (images[rv.Effect.RASTER] > 1e-3)
    ratio = images[rv.Effect.SHADOWS][plane] / images[rv.Effect.RASTER][plane]
    # oracle: integrate the emitter on a grid, weight cos * cos / r^2, visible unless the segment
    # to the emitter point crosses the plate (y = 0.5, |x|, |z| < 0.2)
    g = (np.arange(48) + 0.5) / 48 * 0.5 - 0.25
    lx, lz = [a.ravel() for a in np.meshgrid(g, g)]
    q = p[plane]
    dx, dz = lx[None] - q[:, 0:1], lz[None] - q[:, 2:3]
    r2 = dx * dx + dz * dz + 1.0
    w = 1.0 / (r2 * r2)                      # cos at the plane * cos at the emitter / r^2, height 1
    cx, cz = q[:, 0:1] + 0.5 * dx, q[:, 2:3] + 0.5 * dz   # where the segment crosses y = 0.5
    blocked = (np.abs(cx) < 0.2) & (np.abs(cz) < 0.2)
    visible = (w * ~blocked).sum(1) / w.sum(1)
    penumbra = (visible > 0.15) & (visible < 0.85)
    assert penumbra.sum() >= 10 and (visible < 0.01).sum() >= 5 and (visible > 0.999).sum() >= 50
    err = ratio - visible                    # Monte Carlo noise of 128 light samples, no bias
    assert np.abs(err).max() < 0.2
    assert np.abs(err[penumbra]).mean() < 0.06 and abs(err[penumbra].mean()) < 0.02
    assert (ratio[visible == 0.0] == 0.0).all()   # umbra: every sample blocked


def periscope():
    """Two 45-degree mirrors: the camera sees mirror A, which sees mirror B, which sees a lit wall."""
    from rayvr.materials.material import Material
    from rayvr.scene.model import Camera, Light, Scene

    s = Scene("periscope")
    s.add_material(Material("Mirror", base_color=(1, 1, 1, 1), metallic=1.0, roughness=0.0,
                            effect=rv.Effect.REFLECTIONS))
    s.add_material(builtin.lambert("Wall", (0.8, 0.8, 0.8)))
    r2 = np.sqrt(0.5)
    for name, c, n, u in (("A", (0, 0, -2), (r2, 0, r2), (r2, 0, -r2)), ("B", (2, 0, -2), (-r2, 0, r2), (r2, 0, r2))):
        c, u, v = np.array(c, float), 0.8 * np.array(u), np.array([0.0, 0.8, 0.0])
        s.add_object(name, *builtin.quad_mesh([c - u - v, c + u - v, c + u + v, c - u + v], n), "Mirror")
    s.add_object("Wall", *builtin.quad_mesh([(1, -1, .5), (3, -1, .5), (3, 1, .5), (1, 1, .5)], (0, 0, -1)), "Wall")
    s.lights.append(Light("point", position=(2.0, 0.0, -0.5), intensity=1.0))
    s.cameras.append(Camera.look_at((0.0, 0.0, 0.0), (0.0, 0.0, -1.0), yfov_deg=16.0))
    return s


def test_reflections_follow_max_bounces(gpu):
    out = {}
    for bounces in (1, 2):
        with render(periscope(), ["GBuffer.posW"], size=(24, 24), max_bounces=bounces) as r:
            out[bounces] = r.read_output("Composite.color")[0, ..., 0].astype(np.float64)
            p, hit = world_positions(r)
    p, hit = p[0], hit[0]
    assert hit.all()                       # mirror A fills the view
    assert (out[1] == 0).all()             # one bounce reaches mirror B, which is black by itself
    # two bounces: reflect the view ray about A, meet B, reflect about B, meet the wall at z = 0.5
    r2 = np.sqrt(0.5)
    n_a, n_b = np.array([r2, 0, r2]), np.array([-r2, 0, r2])
    d0 = p / np.linalg.norm(p, axis=-1, keepdims=True)
    d1 = d0 - 2 * (d0 @ n_a)[..., None] * n_a
    b = p + d1 * (((np.array([2.0, 0, -2.0]) - p) @ n_b) / (d1 @ n_b))[..., None]
    d2 = d1 - 2 * (d1 @ n_b)[..., None] * n_b
    q = b + d2 * ((0.5 - b[..., 2]) / d2[..., 2])[..., None]
    on_b = (np.abs((b - [2.0, 0, -2.0]) @ np.array([r2, 0, r2])) < 0.78) & (np.abs(b[..., 1]) < 0.78)
    on_wall = (np.abs(q[..., 0] - 2.0) < 0.98) & (np.abs(q[..., 1]) < 0.98)
    sel = on_b & on_wall
    assert sel.mean() > 0.7
    want = lambert_point(q, np.array([2.0, 0.0, -0.5]), 1.0, 0.8, normal=(0, 0, -1), eye=q - d2)
    np.testing.assert_allclose(out[2][sel], want[sel], rtol=2e-2)
