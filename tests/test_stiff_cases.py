"""Stiff and extreme cases through the hybrid graph and the path tracer, each against a closed form
or a float64 reference computed here: z-fighting, far from the origin, grazing views, near-delta
roughness, extreme emitter strengths, tiny area lights, extreme clip planes, Russian roulette,
long paths in a closed box, delta-delta connections, cameras inside meshes, single- and
double-sided emitters, flipped normals, 10,000 instances, empty scenes, total internal
reflection, degenerate triangles, tiny scales, lights on and inside surfaces, black scenes,
index-matched glass, and the G-buffer's normal precision. Every output is finite and >= 0.

Most scenes are Lambert planes (rayvr.scene.builtin.lambert: f = rho / pi exactly) under a
directional light of illuminance E, whose radiance is rho / pi * E * cos(theta_light) wherever
the light is unoccluded, seen from any angle. Albedos are multiples of 1/255 (0.2, 0.4, 0.6, 0.8):
the G-buffer keeps the base colour in rgba8, and the hybrid would otherwise differ from the path
tracer by that rounding.
"""
import math

import numpy as np
import pytest

import rayvr as rv
from rayvr.materials.material import Material
from rayvr.renderer import Renderer
from rayvr.scene.builtin import box, cornell_box, lambert, quad_mesh
from rayvr.scene.model import Environment, Light, Mesh, Scene
from rayvr.xr.cameras import default_views, look_at
from rayvr.xr.views import Fov, View, ViewSet

SIZE = 24
HYBRID = "Composite.color"        # rgba16f
PT = "Accumulate.dst"             # rgba32f
HALF_RTOL = 2e-3                  # float16 targets round to 11 significant bits


# ---- helpers -------------------------------------------------------------------------------------
def view_set(eye, target, fov=40.0, size=SIZE, near=0.01, far=100.0, up=(0.0, 1.0, 0.0)) -> ViewSet:
    return ViewSet([View(look_at(eye, target, up=up), Fov.symmetric(fov, 1.0), size, size, near, far)])


def hybrid(**kw):
    return rv.graphs.hybrid(**{"preset": "raw", **kw})


def path_traced(spp=1, bounces=1, rr_start=3, jitter=False):
    """The path tracer; without jitter its camera rays go through the pixel centres like the
    G-buffer's, so both graphs see the same points."""
    g = rv.graphs.path_traced(samples_per_pixel=spp, max_bounces=bounces, rr_start=rr_start)
    g.update_pass("PathTracer", {"pixel_jitter": jitter})
    return g


def render(scene, graph, views, pin, frames=1, average=False):
    """Output `pin` of every view after `frames` frames, float64 (views, h, w, 4); with `average`
    the mean of the frames' images (for outputs that do not accumulate, such as the hybrid's).
    Each frame is checked finite and >= 0."""
    total = 0.0
    with Renderer(scene, graph, views=views) as r:
        for _ in range(frames):
            r.render()
            if average:
                total = total + sane(r.read_output(pin).astype(np.float64), f"{graph.name} {pin}")
        img = r.read_output(pin).astype(np.float64)
    return total / frames if average else img


def sane(img, what=""):
    """Every value finite and >= 0; returns the rgb channels."""
    bad = ~np.isfinite(img)
    assert not bad.any(), f"{what}: {int(bad.sum())} non-finite values, first at {np.argwhere(bad)[0]}"
    assert (img >= 0).all(), f"{what}: negative value {img.min()} at {np.argwhere(img < 0)[0]}"
    return img[..., :3]


def set_effect(scene, effect):
    for m in scene.materials:
        m.effect = effect
    return scene


def plane_scene(rho=0.4, half=2.0, y=0.0, material=None, sun=(0.0, -1.0, 0.0), illuminance=2.0) -> Scene:
    """A Lambert square at height y facing +Y under a directional light."""
    s = Scene("plane")
    s.add_material(material or lambert("Plane", (rho,) * 3))
    s.add_object("Plane", *quad_mesh([[-half, y, -half], [half, y, -half], [half, y, half], [-half, y, half]],
                                     facing=(0, 1, 0)), 0)
    if sun is not None:
        s.lights.append(Light("directional", direction=sun, intensity=illuminance))
    return s


def pixel_rays(views, k=0):
    """(h, w, 3) origins and directions of view k's pixel-centre rays (rows bottom-up), float64."""
    v = views[k]
    o = np.zeros((v.height, v.width, 3))
    d = np.zeros((v.height, v.width, 3))
    for j in range(v.height):
        for i in range(v.width):
            o[j, i], d[j, i] = v.primary_ray((i + 0.5, j + 0.5))
    return o, d


def lambert_under_sun(rho, illuminance, sun, normal=(0.0, 1.0, 0.0)) -> float:
    d = -np.asarray(sun, float) / np.linalg.norm(sun)
    return rho / math.pi * illuminance * max(float(np.dot(d, normal)), 0.0)


EFFECTS = (rv.Effect.RASTER, rv.Effect.SHADOWS, rv.Effect.REFLECTIONS, rv.Effect.PATH_TRACED)


# ---- 1. coplanar overlapping surfaces ------------------------------------------------------------
@pytest.mark.parametrize("graph", ["raster", "rt", "pt"])
def test_z_fighting_pixels_are_one_of_the_two_surfaces(gpu, graph):
    """Two coplanar, overlapping Lambert quads of albedo 0.2 and 0.8 (exact in rgba8) under a
    directional light: wherever they overlap the depth test or the closest-hit test may pick
    either, but every pixel is one of the two closed-form radiances, never a mixture, a black
    hole or a NaN."""
    s = Scene("zfight")
    sun = (0.3, -1.0, 0.2)
    for name, rho in (("Dark", 0.2), ("Light", 0.8)):
        s.add_material(lambert(name, (rho,) * 3, effect=rv.Effect.SHADOWS))
    s.add_object("Dark", *quad_mesh([[-2, 0, -2], [1, 0, -2], [1, 0, 2], [-2, 0, 2]], (0, 1, 0)), "Dark")
    s.add_object("Light", *quad_mesh([[-1, 0, -2], [2, 0, -2], [2, 0, 2], [-1, 0, 2]], (0, 1, 0)), "Light")
    s.lights.append(Light("directional", direction=sun, intensity=3.0))
    views = view_set((0.1, 2.0, 0.05), (0.0, 0.0, 0.0), fov=60.0, up=(0, 0, -1))
    if graph == "pt":
        img = sane(render(s, path_traced(), views, PT))
    else:
        img = sane(render(s, hybrid(gbuffer=graph), views, HYBRID))
    want = [lambert_under_sun(rho, 3.0, sun) for rho in (0.2, 0.8)]
    err = np.min([np.abs(img - w) / w for w in want], axis=0)
    assert err.max() < HALF_RTOL, f"pixels off both closed forms by up to {err.max():.2e}"
    # both surfaces show (the light one at least where it alone is)
    for w in want:
        assert (np.abs(img[..., 0] - w) / w < HALF_RTOL).sum() > 20


# ---- 3. grazing view angles ----------------------------------------------------------------------
@pytest.mark.parametrize("angle", [80.0, 85.0, 89.0, 89.9])
def test_grazing_views_of_a_lambert_plane_see_its_closed_form_radiance(gpu, angle):
    """A camera 1 m above a 20 km Lambert plane looking at it `angle` degrees from its normal:
    Lambertian radiance does not depend on the view, so every pixel that sees the plane is
    rho / pi * E * cos(theta_light), in the raster, shadow, reflection and path-traced passes and
    the path tracer; the sky above the horizon is black (the scene has a light, so no default
    environment)."""
    sun = (0.4, -1.0, 0.3)
    want = lambert_under_sun(0.4, 2.0, sun)
    s = plane_scene(half=1e4, sun=sun)
    a = math.radians(angle)
    views = view_set((0.0, 1.0, 0.0), (0.0, 1.0 - math.cos(a), -math.sin(a)), fov=2.0 * (90.0 - angle) + 1.0,
                     near=0.01, far=1e5)
    images = {"path tracer": render(s, path_traced(), views, PT)}
    for effect in EFFECTS:
        images[effect.name] = render(set_effect(s, effect), hybrid(), views, HYBRID)
    for what, img in images.items():
        img = sane(img, what)[0, ..., 0]
        seen = img > 0
        assert seen.sum() >= SIZE * 3, f"{what}: the plane covers {seen.sum()} pixels"
        err = np.abs(img[seen] - want).max() / want
        assert err < HALF_RTOL, f"{what} at {angle} deg: relative error {err:.2e}"


# ---- 11, 12, 13: which side of a surface is seen --------------------------------------------------
def emitter_scene(double_sided: bool, walls: bool = False) -> Scene:
    """A 1 m emissive square at z = 0 whose winding faces +Z (radiance 3) under a black sky; with
    `walls`, Lambert walls at z = 1 and z = -1 facing it, lit by nothing else."""
    s = Scene("emitter")
    s.add_material(lambert("Emitter", (0.0, 0.0, 0.0), emissive=(1.0, 1.0, 1.0), emissive_strength=3.0,
                           double_sided=double_sided))
    s.add_object("Emitter", *quad_mesh([[-0.5, -0.5, 0], [0.5, -0.5, 0], [0.5, 0.5, 0], [-0.5, 0.5, 0]], (0, 0, 1)), 0)
    if walls:
        s.add_material(lambert("Wall", (0.4,) * 3))
        for z in (1.0, -1.0):
            s.add_object(f"Wall{z:+.0f}", *quad_mesh([[-3, -3, z], [3, -3, z], [3, 3, z], [-3, 3, z]], (0, 0, -z)), "Wall")
    s.environment = Environment((0.0, 0.0, 0.0), name="black")
    return s


def square_irradiance(points, normal, radiance, half=0.5, n=64):
    """Irradiance at `points` (..., 3) with `normal` from a Lambertian square [-half, half]^2 at
    z = 0 of `radiance`, by a float64 midpoint rule: L sum cos cos' / r^2 dA."""
    u = (np.arange(n) + 0.5) / n * 2 * half - half
    q = np.stack(np.meshgrid(u, u, [0.0], indexing="ij"), -1).reshape(-1, 3)
    d = q[None] - points.reshape(-1, 1, 3)
    r2 = (d ** 2).sum(-1)
    cos_w = np.maximum((d * normal).sum(-1), 0) / np.sqrt(r2)
    cos_e = np.abs(d[..., 2]) / np.sqrt(r2)
    return (radiance * cos_w * cos_e / r2).sum(-1).reshape(points.shape[:-1]) * (2 * half / n) ** 2


@pytest.mark.parametrize("double_sided", [False, True])
@pytest.mark.parametrize("gbuffer", ["raster", "rt"])
def test_an_emitter_shows_its_radiance_from_its_front_and_only_double_sided_from_its_back(gpu, double_sided,
                                                                                           gbuffer):
    """One rule in every pass: a single-sided emitter is dark seen from behind, in the hybrid (the
    G-buffer's emission) as in the path tracer; a double-sided one shows its radiance from both."""
    s = emitter_scene(double_sided)
    for side, z in (("front", 2.0), ("back", -2.0)):
        views = view_set((0.0, 0.0, z), (0.0, 0.0, 0.0), fov=20.0)
        centre = slice(SIZE // 2 - 3, SIZE // 2 + 3)
        want = 3.0 if side == "front" or double_sided else 0.0
        images = {"path tracer": render(s, path_traced(), views, PT)}
        for effect in EFFECTS:
            images[effect.name] = render(set_effect(s, effect), hybrid(gbuffer=gbuffer), views, HYBRID)
        for what, img in images.items():
            got = sane(img, what)[0, centre, centre]
            np.testing.assert_allclose(got, want, atol=1e-6, err_msg=f"{what}, {side}, double-sided {double_sided}")


@pytest.mark.parametrize("double_sided", [False, True])
def test_a_double_sided_emitter_lights_both_sides_and_a_single_sided_one_only_its_front(gpu, double_sided):
    """Walls on both sides of the emissive square, each seen from between it and the wall: the
    wall its front faces gets rho / pi * E (E the square's irradiance, float64 quadrature), the
    wall behind it the same when it is double-sided and exactly 0 otherwise (light sampling, in
    the shadow pass and the path tracer, follows the G-buffer's rule). Means over 16 frames."""
    s = set_effect(emitter_scene(double_sided, walls=True), rv.Effect.SHADOWS)
    for side, z in (("front", 1.0), ("back", -1.0)):
        views = view_set((0.0, 0.0, z / 2), (0.0, 0.0, z), fov=60.0)
        o, d = pixel_rays(views)
        p = o + d * ((z - o[..., 2:3]) / d[..., 2:3])
        want = 0.4 / math.pi * square_irradiance(p, np.array([0.0, 0.0, -z]), 3.0)
        if side == "back" and not double_sided:
            want = np.zeros_like(want)
        for what, graph, pin in (("path tracer", path_traced(jitter=False), PT), ("SHADOWS", hybrid(), HYBRID)):
            img = sane(render(s, graph, views, pin, frames=16, average=pin == HYBRID), what)[0, ..., 0]
            if want.max() == 0:
                assert img.max() == 0.0, f"{what}: the back of a single-sided emitter lit the wall"
            else:
                assert img.mean() == pytest.approx(want.mean(), rel=0.02), f"{what}, {side}"
                np.testing.assert_allclose(img, want, rtol=0.25, err_msg=f"{what}, {side}")


@pytest.mark.parametrize("gbuffer", ["raster", "rt"])
def test_vertex_normals_against_the_winding_shade_as_the_correct_ones(gpu, gbuffer):
    """A double-sided Lambert plane whose vertex normals point against its winding (an exporter's
    flipped normals): every pass turns the shading normal to the side of the geometric one, so
    it is lit exactly as with correct normals, rho / pi * E * cos."""
    sun = (0.3, -1.0, 0.2)
    want = lambert_under_sun(0.4, 2.0, sun)
    views = view_set((0.2, 2.0, 0.3), (0.0, 0.0, 0.0), fov=50.0)
    for flipped in (False, True):
        s = Scene("flipped")
        s.add_material(lambert("Plane", (0.4,) * 3, double_sided=True))
        pos, idx = quad_mesh([[-2, 0, -2], [2, 0, -2], [2, 0, 2], [-2, 0, 2]], (0, 1, 0))
        s.add_object("Plane", pos, idx, 0, normals=np.tile([0.0, -1.0 if flipped else 1.0, 0.0], (4, 1)))
        s.lights.append(Light("directional", direction=sun, intensity=2.0))
        images = {"path tracer": render(s, path_traced(bounces=2), views, PT)}
        for effect in EFFECTS:
            images[effect.name] = render(set_effect(s, effect), hybrid(gbuffer=gbuffer), views, HYBRID)
        for what, img in images.items():
            got = sane(img, what)
            np.testing.assert_allclose(got, want, rtol=HALF_RTOL, err_msg=f"{what}, flipped normals {flipped}")


@pytest.mark.parametrize("gbuffer", ["raster", "rt"])
def test_a_camera_inside_a_closed_box_sees_its_lit_inside_faces(gpu, gbuffer):
    """The camera and a point light inside a closed box whose single-sided faces point outwards:
    every pixel sees an inside (back) face, shaded on the side facing the viewer as
    rho / pi * I cos / d^2 (direct light only: the path tracer with one bounce)."""
    s = Scene("inside")
    s.add_material(lambert("Box", (0.4,) * 3))
    s.add_object("Box", *box((-1, -1, -1), (1, 1, 1)), 0)
    light = np.array([0.3, 0.5, -0.2])
    s.lights.append(Light("point", position=light, intensity=2.0))
    views = view_set((0.0, 0.0, 0.5), (0.2, -0.3, -1.0), fov=90.0)
    o, d = pixel_rays(views)
    t = np.min(np.where(d != 0, (np.sign(d) - o) / np.where(d != 0, d, 1), np.inf), axis=-1)   # exit the cube
    p = o + d * t[..., None]
    axis = np.argmax(np.abs(p), axis=-1)
    n = -np.eye(3)[axis] * np.sign(np.take_along_axis(p, axis[..., None], -1))   # inward
    to = light - p
    dist2 = (to ** 2).sum(-1)
    want = 0.4 / math.pi * 2.0 * np.maximum((to * n).sum(-1), 0) / dist2 ** 1.5
    interior = np.abs(np.abs(p).max(-1) - np.sort(np.abs(p), -1)[..., 1]) > 0.02   # off the cube's edges
    images = {"path tracer": render(s, path_traced(), views, PT)}
    for effect in EFFECTS[:3]:
        images[effect.name] = render(set_effect(s, effect), hybrid(gbuffer=gbuffer), views, HYBRID)
    for what, img in images.items():
        got = sane(img, what)[0, ..., 0]
        np.testing.assert_allclose(got[interior], want[interior], rtol=3e-3, err_msg=what)


# ---- 16, 21: glass -------------------------------------------------------------------------------
def fresnel_dielectric(cos_i, eta):
    """Unpolarised Fresnel reflectance, eta = n_transmitted / n_incident (1 beyond the critical angle)."""
    s2 = (1 - cos_i ** 2) / eta ** 2
    if s2 >= 1:
        return 1.0
    ct = math.sqrt(1 - s2)
    rs, rp = (cos_i - eta * ct) / (cos_i + eta * ct), (eta * cos_i - ct) / (eta * cos_i + ct)
    return 0.5 * (rs * rs + rp * rp)


def glass_slab_under_a_sky(ior=1.5, thickness=1.0, base=(1.0, 1.0, 1.0), top=0.5, bottom=-0.5) -> Scene:
    """A 200 m wide smooth glass slab between heights `bottom` and `top` (a volume when
    `thickness` > 0), an emissive ceiling of radiance 1 at y = 2 facing down, black elsewhere."""
    s = Scene("slab")
    s.add_material(Material("Glass", base_color=(*base, 1.0), metallic=0.0, roughness=0.0, transmission=1.0,
                            ior=ior, thickness=thickness))
    s.add_material(lambert("Sky", (0.0, 0.0, 0.0), emissive=(1.0, 1.0, 1.0)))
    s.add_object("Slab", *box((-100, bottom, -100), (100, top, 100)), "Glass")
    s.add_object("Sky", *quad_mesh([[-1e3, 2, -1e3], [1e3, 2, -1e3], [1e3, 2, 1e3], [-1e3, 2, 1e3]], (0, -1, 0)), "Sky")
    return s


@pytest.mark.parametrize("angle", [30.0, 60.0])
def test_a_ray_inside_glass_beyond_the_critical_angle_stays_inside(gpu, angle):
    """The camera inside a glass slab (ior 1.5) looks up at its top face `angle` degrees from the
    normal. Beyond the critical angle (41.8 deg) total internal reflection keeps every path
    inside, bouncing between the faces, so nothing of the emissive sky above arrives: the image is
    exactly 0. Below it, the sky's radiance arrives scaled by n^2 (radiance / n^2 is invariant),
    1 - F at each exit and F^2 for each round trip: 2.25 (1 - F) sum_k F^2k over the round trips
    the bounce limit allows. The hybrid's G-buffer must know that it sees the face from inside."""
    s = glass_slab_under_a_sky()
    a = math.radians(angle)
    views = view_set((0.0, 0.0, 0.0), (math.sin(a), math.cos(a), 0.0), fov=4.0, up=(0, 0, 1))
    f = fresnel_dielectric(math.cos(a), 1 / 1.5)
    frames = 8

    def closed_form(exits):
        return 2.25 * (1 - f) * sum(f ** (2 * k) for k in range(exits))

    for what, graph, pin, exits in (("path tracer", path_traced(bounces=6), PT, 3),
                                    ("hybrid", hybrid(max_bounces=4), HYBRID, 2)):
        set_effect(s, rv.Effect.REFLECTIONS)
        img = sane(render(s, graph, views, pin, frames=frames, average=pin == HYBRID), what)
        got = img.mean()
        if angle > 41.9:
            assert np.max(img) == 0.0, f"{what}: light left the glass past the critical angle"
        else:
            assert got == pytest.approx(closed_form(exits), rel=0.02), what


@pytest.mark.parametrize("volume", [False, True])
def test_index_matched_glass_passes_light_straight_through_tinted_by_its_base_colour(gpu, volume):
    """Glass of ior exactly 1 has no Fresnel reflection and bends nothing: an emissive wall seen
    through a thin sheet of it is the wall times the base colour, through a slab (a volume: two
    crossings) times its square. The lobe choice keeps a small share for the (empty) reflection,
    so this holds for the mean over frames, which the noise of that choice bounds."""
    base = np.array([0.8, 0.6, 0.4])
    s = Scene("matched")
    s.add_material(Material("Glass", base_color=(*base, 1.0), metallic=0.0, roughness=0.0, transmission=1.0,
                            ior=1.0, thickness=0.4 if volume else 0.0, effect=rv.Effect.REFLECTIONS))
    s.add_material(lambert("Wall", (0.0, 0.0, 0.0), emissive=(1.0, 1.0, 1.0)))
    s.add_object("Wall", *quad_mesh([[-3, -3, -1], [3, -3, -1], [3, 3, -1], [-3, 3, -1]], (0, 0, 1)), "Wall")
    if volume:
        s.add_object("Glass", *box((-0.3, -0.3, -0.2), (0.3, 0.3, 0.2)), "Glass")
    else:
        s.add_object("Glass", *quad_mesh([[-0.3, -0.3, 0], [0.3, -0.3, 0], [0.3, 0.3, 0], [-0.3, 0.3, 0]], (0, 0, 1)),
                     "Glass")
    s.environment = Environment((0.0, 0.0, 0.0), name="black")
    views = view_set((0.0, 0.0, 2.0), (0.0, 0.0, 0.0), fov=30.0)
    behind = slice(SIZE // 2 - 4, SIZE // 2 + 4)   # through the glass
    want = base ** (2 if volume else 1)
    frames = 16
    for what, graph, pin in (("path tracer", path_traced(bounces=3), PT),
                             ("hybrid", hybrid(max_bounces=2), HYBRID)):
        img = sane(render(s, graph, views, pin, frames=frames, average=pin == HYBRID), what)[0]
        np.testing.assert_allclose(img[behind, behind].mean(axis=(0, 1)), want, rtol=0.04, err_msg=what)
        np.testing.assert_allclose(img[:2, :2], 1.0, rtol=HALF_RTOL, err_msg=f"{what}: the wall beside the glass")


# ---- 15, 20: empty and black scenes --------------------------------------------------------------
@pytest.mark.filterwarnings("ignore:empty has no light")
@pytest.mark.parametrize("env", [None, (2.0, 1.0, 0.5)])
def test_an_empty_scene_and_a_one_triangle_scene_show_the_environment_where_nothing_is_hit(gpu, env):
    """No mesh at all, then one triangle: every ray that hits nothing brings the environment (the
    scene's, or the neutral white default when nothing lights it), exactly; the triangle, a
    Lambert surface under a uniform environment, has radiance rho L (its mean over frames)."""
    sky = np.array(env or (1.0, 1.0, 1.0))
    views = view_set((0.0, 0.0, 2.0), (0.0, 0.0, 0.0), fov=40.0)
    for triangles in (0, 1):
        s = Scene("empty")
        s.add_material(lambert("White", (0.4,) * 3))
        if triangles:
            s.add_object("Triangle", np.array([[-0.5, -0.5, 0], [0.5, -0.5, 0], [0, 0.5, 0]], np.float32),
                         np.array([[0, 1, 2]], np.uint32), 0)
        if env:
            s.environment = Environment(env, name="uniform")
        images = {"path tracer": render(s, path_traced(bounces=2), views, PT, frames=8)}
        for effect in EFFECTS:
            images[effect.name] = render(set_effect(s, effect), hybrid(), views, HYBRID, frames=8, average=True)
        for what, img in images.items():
            img = sane(img, f"{what}, {triangles} triangles")[0]
            corner = img[:4, :4].reshape(-1, 3)
            np.testing.assert_allclose(corner, np.broadcast_to(sky, corner.shape), rtol=HALF_RTOL, err_msg=what)
            if not triangles:
                np.testing.assert_allclose(img.reshape(-1, 3), np.broadcast_to(sky, (SIZE * SIZE, 3)), rtol=HALF_RTOL)
            else:
                centre = img[SIZE // 2 - 2:SIZE // 2 + 2, SIZE // 2 - 2:SIZE // 2 + 2].mean(axis=(0, 1))
                np.testing.assert_allclose(centre, 0.4 * sky, rtol=0.05, err_msg=f"{what}: the triangle")


def black_scenes():
    """A Cornell box lit by nothing: a zero-intensity point light, the ceiling light at strength 0,
    base colour 0 under a bright light, all under a black environment."""
    out = []
    s = cornell_box()
    s.materials["Light"].emissive_strength = 0.0
    s.lights.append(Light("point", position=(0.0, 0.4, 0.0), intensity=0.0))
    out.append(("zero-intensity lights", s))
    s = cornell_box()
    for m in s.materials:
        m.base_color = (0.0, 0.0, 0.0, 1.0)
    s.materials["Light"].emissive_strength = 0.0
    s.lights.append(Light("point", position=(0.0, 0.4, 0.0), intensity=50.0))
    s.lights.append(Light("directional", direction=(0.2, -1.0, 0.1), intensity=50.0))
    out.append(("base colour 0", s))
    for _, s in out:
        s.environment = Environment((0.0, 0.0, 0.0), name="black")
    return out


@pytest.mark.parametrize("index", [0, 1])
def test_a_scene_without_light_or_without_albedo_is_exactly_black(gpu, index):
    """Nothing emits, or nothing reflects: exactly 0 everywhere, in every pass, no NaN from the
    0 / 0 of an empty light table or a black BSDF's lobe probabilities."""
    what, s = black_scenes()[index]
    images = {"path tracer": render(s, path_traced(spp=2, bounces=4), default_views(s, 2, (16, 16)),
                                    PT, frames=2)}
    for effect in EFFECTS:
        images[effect.name] = render(set_effect(s, effect), hybrid(max_bounces=2, gi=None),
                                     default_views(s, 2, (16, 16)), HYBRID, frames=2)
    for name, img in images.items():
        assert (sane(img, f"{what}, {name}") == 0).all(), f"{what}, {name}: max {img.max()}"


# ---- 10. delta lights through a mirror -----------------------------------------------------------
@pytest.mark.parametrize("light", ["point", "directional"])
def test_a_delta_light_seen_only_through_a_perfect_mirror_shows_nothing(gpu, light):
    """A perfect mirror (roughness 0) and a point or directional light placed where the mirror
    would show it: a delta light through a delta lobe cannot be sampled (light sampling meets a
    zero BSDF, BSDF sampling a light no ray can hit), so the mirror shows exactly 0 in every pass
    and the path tracer, and nothing blows up. A nearly perfect mirror (roughness 1e-3, the
    smallest non-delta one: alpha 1e-6) shows the light as a highlight of peak F D E / (4 n.v),
    D = 1 / (pi alpha^2), some 4.5e11 for the point light: the path tracer's central pixel (its
    ray exact to float32 rounding) reaches it, and so does the hybrid with the ray-traced G-buffer
    (its float16 roughness keeps the material on the rough side of the delta threshold), where the
    float16 targets saturate at 65504; elsewhere values stay finite and below the peak."""
    views = view_set((0.0, 1.0, 1.0), (0.0, 0.0, 0.0), fov=30.0, size=25)
    # the mirror reflection of the eye's central ray (pixel 12, 12 of 25) goes to (0, 1, -1)
    lights = {"point": Light("point", position=(0.0, 1.0, -1.0), intensity=10.0),
              "directional": Light("directional", direction=(0.0, -1.0, 1.0), intensity=10.0)}
    irradiance = 10.0 / 2.0 if light == "point" else 10.0
    f = 0.8 + 0.2 * (1 - math.cos(math.pi / 4)) ** 5
    peak = f / (math.pi * 1e-12) / (4 * math.cos(math.pi / 4)) * irradiance
    for roughness in (0.0, 1e-3):
        s = plane_scene(material=Material("Mirror", base_color=(0.8, 0.8, 0.8, 1.0), metallic=1.0,
                                          roughness=roughness), sun=None)
        s.lights.append(lights[light])
        images = {"path tracer": render(s, path_traced(bounces=3), views, PT, frames=2)}
        for gbuffer in ("raster", "rt"):
            for effect in EFFECTS:
                images[f"{effect.name} ({gbuffer})"] = render(set_effect(s, effect), hybrid(gbuffer=gbuffer), views,
                                                              HYBRID, frames=2)
        for what, img in images.items():
            img = sane(img, f"{what}, roughness {roughness}")[0]
            if roughness == 0.0:
                assert img.max() == 0.0, f"{what}: a delta-delta connection showed {img.max()}"
            elif what == "path tracer":
                assert img[12, 12, 0] == pytest.approx(peak, rel=0.05)
                assert img.max() <= peak * 1.01
            else:   # the float16 composite saturates at the largest half, never Inf
                assert img.max() <= 65504.0, what
                if "(rt)" in what:   # the ray-traced G-buffer's point is as exact: a near mirror there too
                    assert img[12, 12, 0] == 65504.0, f"{what}: {img[12, 12, 0]}"


# ---- 4. roughness 0 to 1 on metal ----------------------------------------------------------------
def schlick(f0, cos):
    return f0 + (1 - f0) * (1 - cos) ** 5


@pytest.mark.parametrize("roughness", [0.0, 1e-7, 1e-4])
def test_mirror_metal_equals_the_exact_reflection(gpu, roughness):
    """Roughness below the delta threshold is a mirror: a metal floor (base 0.6) reflecting an
    emissive ceiling panel (radiance 2) in a uniform sky (radiance 0.5) shows, per pixel,
    Schlick's F(cos) times whichever the exact mirror ray (float64, here) meets, in the hybrid's
    reflection and path-traced passes and the path tracer."""
    s = plane_scene(material=Material("Mirror", base_color=(0.6, 0.6, 0.6, 1.0), metallic=1.0, roughness=roughness),
                    sun=None, half=50.0)
    s.add_material(lambert("Panel", (0.0, 0.0, 0.0), emissive=(1.0, 1.0, 1.0), emissive_strength=2.0))
    s.add_object("Panel", *quad_mesh([[-0.5, 1.5, -2.5], [0.5, 1.5, -2.5], [0.5, 1.5, -1], [-0.5, 1.5, -1]], (0, -1, 0)),
                 "Panel")
    s.environment = Environment((0.5, 0.5, 0.5))
    views = view_set((0.0, 1.0, 1.0), (0.0, 0.0, -1.0), fov=50.0)
    o, d = pixel_rays(views)
    p = o + d * (-o[..., 1:2] / d[..., 1:2])                 # on the floor
    r = d * [1, -1, 1]                                        # mirrored
    q = p + r * ((1.5 - p[..., 1:2]) / r[..., 1:2])           # at the panel's height
    in_panel = (np.abs(q[..., 0]) < 0.5) & (q[..., 2] > -2.5) & (q[..., 2] < -1)
    near_edge = (np.abs(np.abs(q[..., 0]) - 0.5) < 0.03) | (np.abs(q[..., 2] + 2.5) < 0.03) | (np.abs(q[..., 2] + 1) < 0.03)
    want = schlick(0.6, -d[..., 1]) * np.where(in_panel, 2.0, 0.5)
    assert in_panel.sum() > 20
    images = {"path tracer": render(s, path_traced(bounces=2), views, PT)}
    for effect in EFFECTS[2:]:
        images[effect.name] = render(set_effect(s, effect), hybrid(), views, HYBRID)
    for what, img in images.items():
        got = sane(img, what)[0, ..., 0]
        np.testing.assert_allclose(got[~near_edge], want[~near_edge], rtol=3e-3, err_msg=what)


@pytest.mark.parametrize("roughness", [1e-3, 0.05, 1.0])
def test_rough_metal_in_a_furnace_is_bounded_by_it(gpu, roughness):
    """A white metal plane under a uniform sky of radiance 1, nothing else: it can reflect at most
    what arrives, and with the energy compensation of single-scatter GGX it reflects all of it,
    at every roughness from the smallest non-delta one (1e-3: alpha 1e-6) to 1: the mean over
    frames is 1 within the noise and no pixel's mean exceeds the bound by more than it."""
    s = plane_scene(material=Material("Metal", base_color=(1.0, 1.0, 1.0, 1.0), metallic=1.0, roughness=roughness),
                    sun=None)
    s.environment = Environment((1.0, 1.0, 1.0))
    views = view_set((0.0, 1.0, 1.0), (0.0, 0.0, 0.0), fov=30.0)
    images = {"path tracer": render(s, path_traced(bounces=2), views, PT, frames=16)}
    for effect in EFFECTS[2:]:   # PATH_TRACED pixels accumulate in the hybrid: its last frame is their mean
        images[effect.name] = render(set_effect(s, effect), hybrid(), views, HYBRID, frames=16,
                                     average=effect != rv.Effect.PATH_TRACED)
    for what, img in images.items():
        img = sane(img, what)[0, ..., 0]
        assert img.mean() == pytest.approx(1.0, abs=0.01), what
        assert img.max() < 1.15, f"{what}: a pixel's mean {img.max():.3f} above the furnace"


# ---- 5. emitter strength -------------------------------------------------------------------------
def test_the_image_scales_linearly_with_the_emitters_strength(gpu):
    """The Cornell box's light at strength 1e-8 and 1e9 instead of 17: the light table's shares,
    the light samples' pdfs and the MIS weights do not depend on the scale, so with the same random
    numbers the path tracer's rgba32f image is the unit image times the strength, to float32
    rounding; the hybrid's float16 composite saturates at 65504 for the blinding one, never Inf."""
    views = default_views(cornell_box(), 2, (16, 16))
    images = {}
    for strength in (17.0, 1e-8, 1e9):
        s = cornell_box()
        s.materials["Light"].emissive_strength = strength
        images[strength] = sane(render(s, path_traced(spp=2, bounces=3, jitter=True), views, PT, frames=2),
                                f"strength {strength}") / strength
        hyb = sane(render(set_effect(s, rv.Effect.REFLECTIONS), hybrid(), views, HYBRID), f"hybrid, {strength}")
        assert hyb.max() <= 65504.0
    ref = images[17.0]
    assert ref.min() >= 0 and ref.mean() > 1e-3
    for strength in (1e-8, 1e9):
        np.testing.assert_allclose(images[strength], ref, rtol=1e-5, atol=0, err_msg=str(strength))


# ---- 6. a tiny area light ------------------------------------------------------------------------
def test_a_micrometre_area_light_lights_as_the_point_light_of_its_intensity(gpu):
    """An emissive square of side 1e-6 m and radiance 1e12 facing down 1 m above a Lambert plane:
    a Lambertian emitter of intensity L A cos(theta_l) along theta_l, so the plane's radiance is
    rho / pi * L A cos(theta_l) cos(theta) / d^2 (float64, per pixel), what a point light of
    intensity I = L A gives times cos(theta_l): the light sample's area pdf and d^2 / cos stay
    exact at A = 1e-12 m^2, in the shadow pass and the path tracer."""
    a, radiance, h = 1e-6, 1e12, 1.0
    views = view_set((0.0, 3.0, 0.0), (0.0, 0.0, 0.0), fov=60.0, up=(0, 0, -1))
    o, d = pixel_rays(views)
    p = o + d * (-o[..., 1:2] / d[..., 1:2])
    to = np.array([0.0, h, 0.0]) - p
    dist = np.linalg.norm(to, axis=-1)
    cos = to[..., 1] / dist                    # at the plane and at the light (both face each other)
    want = 0.4 / math.pi * radiance * a * a * cos * cos / dist ** 2
    point = 0.4 / math.pi * radiance * a * a * cos / dist ** 2
    for kind in ("area", "point"):
        s = plane_scene(sun=None)
        if kind == "area":
            s.add_material(lambert("Tiny", (0.0, 0.0, 0.0), emissive=(1.0, 1.0, 1.0), emissive_strength=radiance))
            s.add_object("Tiny", *quad_mesh([[-a / 2, h, -a / 2], [a / 2, h, -a / 2], [a / 2, h, a / 2],
                                             [-a / 2, h, a / 2]], (0, -1, 0)), "Tiny")
        else:
            s.lights.append(Light("point", position=(0.0, h, 0.0), intensity=radiance * a * a))
        for what, graph, pin in (("path tracer", path_traced(), PT),
                                 ("SHADOWS", hybrid(), HYBRID)):
            img = sane(render(set_effect(s, rv.Effect.SHADOWS), graph, views, pin), f"{kind}, {what}")[0, ..., 0]
            np.testing.assert_allclose(img, want if kind == "area" else point, rtol=2e-3, err_msg=f"{kind}, {what}")


# ---- 7. extreme clip planes ----------------------------------------------------------------------
@pytest.mark.parametrize("gbuffer", ["raster", "rt"])
def test_extreme_near_and_far_planes_render_the_moderate_image(gpu, gbuffer):
    """The Cornell box in stereo with near 1e-4 and far 1e6 (a depth range of 1e10) against near
    0.05 and far 100: the raster's depth test still separates surfaces centimetres apart at a
    metre, and the ray-traced G-buffer's clip distances stay exact, so the image is the same but
    for a few silhouette pixels."""
    images = []
    for near, far in ((0.05, 100.0), (1e-4, 1e6)):
        s = set_effect(cornell_box(), rv.Effect.REFLECTIONS)
        s.cameras[0].znear, s.cameras[0].zfar = near, far
        views = default_views(s, 2, (SIZE, SIZE))
        images.append(sane(render(s, hybrid(gbuffer=gbuffer), views, HYBRID), f"near {near}, far {far}"))
    ref, got = images
    same = np.all(np.abs(got - ref) <= HALF_RTOL * np.maximum(ref, 1e-3), axis=-1)
    assert same.mean() > 0.99, f"{(~same).sum()} of {same.size} pixels differ"


# ---- 8, 9: long paths in a closed box ------------------------------------------------------------
def closed_box(rho, emitting_walls=True) -> Scene:
    """A closed 2 m cube seen from inside (faces wound inwards) of Lambert albedo rho: every wall
    emitting radiance 1 (a furnace: the radiance everywhere is sum_k rho^k over the bounces a path
    may take, exactly), or only a 0.2 m square light under the ceiling."""
    s = Scene("closed_box")
    wall = lambert("Wall", (rho,) * 3, emissive=(1.0, 1.0, 1.0) if emitting_walls else (0.0, 0.0, 0.0))
    s.add_material(wall)
    pos, idx = box((-1, -1, -1), (1, 1, 1))
    s.add_object("Box", pos, idx[:, ::-1].copy(), 0)
    if not emitting_walls:
        s.add_material(lambert("Light", (rho,) * 3, emissive=(1.0, 1.0, 1.0)))
        s.add_object("Light", *quad_mesh([[-0.1, 0.99, -0.1], [0.1, 0.99, -0.1], [0.1, 0.99, 0.1], [-0.1, 0.99, 0.1]],
                                         (0, -1, 0)), "Light")
    return s


def frame_means(scene, graph, views, frames):
    """Each frame's image mean of the path tracer's own (unaccumulated) output: independent
    estimates whose spread gives the standard error."""
    graph.mark_output("PathTracer.color")
    means = []
    with Renderer(scene, graph, views=views) as r:
        for _ in range(frames):
            r.render()
            means.append(sane(r.read_output("PathTracer.color").astype(np.float64)).mean())
    return np.array(means)


INSIDE = view_set((0.2, -0.1, 0.6), (-0.3, 0.2, -1.0), fov=80.0, size=16)


@pytest.mark.parametrize("rho", [0.999, 0.01])
def test_russian_roulette_from_the_first_bounce_is_unbiased(gpu, rho):
    """The furnace (closed_box) at albedo 0.999, where a path's throughput stays near 1 and
    roulette rarely ends it, and at 0.01, where it falls to 0.01 a bounce and roulette (survival
    clamped at 0.05) ends most paths at once but boosts the survivors: with roulette from bounce 0
    and without it, 30 bounces, both means agree with each other and with the closed form
    sum_{k<=30} rho^k within four standard errors."""
    bounces, frames = 30, 8
    want = sum(rho ** k for k in range(bounces + 1))
    stats = {}
    for what, rr_start in (("roulette from bounce 0", 0), ("no roulette", 1000)):
        m = frame_means(closed_box(rho), path_traced(bounces=bounces, rr_start=rr_start, jitter=True), INSIDE, frames)
        stats[what] = (m.mean(), m.std(ddof=1) / math.sqrt(frames))
    (a, sa), (b, sb) = stats.values()
    assert abs(a - b) < 4 * math.hypot(sa, sb) + 1e-6 * want, stats
    for what, (m, se) in stats.items():
        assert abs(m - want) < 4 * se + 1e-4 * want, (what, m, se, want)


def test_a_closed_box_of_albedo_0999_with_100_bounces_stays_finite_and_bounded(gpu):
    """Albedo 0.999 and 100 bounces: as a furnace the radiance is sum_{k<=100} 0.999^k = 96.08
    exactly (mean over the image within 2%); with one small light instead no pixel exceeds the
    analytic bound L_e / (1 - rho) = 1000 (radiance is at most L_e + rho max L), nor its
    100-bounce truncation, and every value stays finite. The light's power pi L_e A_l, kept at
    rho a bounce, leaves the box's surfaces A as pi L_e A_l sum_k rho^k in all: their mean
    radiance is L_e A_l sum_k rho^k / A, and at albedo 0.999 interreflection makes the radiance
    so uniform that the image's mean is it within 5%."""
    want = sum(0.999 ** k for k in range(101))
    img = sane(render(closed_box(0.999), path_traced(bounces=100, jitter=True), INSIDE, PT, frames=4))
    assert img.mean() == pytest.approx(want, rel=0.02)
    img = sane(render(closed_box(0.999, emitting_walls=False), path_traced(bounces=100, jitter=True), INSIDE, PT,
                      frames=4))
    assert img.max() < want < 1.0 / (1 - 0.999)
    area_mean = 0.2 * 0.2 * want / (6 * 4 + 2 * 0.2 * 0.2)   # walls and both sides of the light
    assert img.mean() == pytest.approx(area_mean, rel=0.05)


# ---- 14. 10,000 instances ------------------------------------------------------------------------
def test_ten_thousand_instances_cover_exactly_the_pixels_their_quads_cover(gpu):
    """A 100 x 100 grid of instances of one unit quad, each scaled to 12 mm in its 20 mm cell and
    lit from above: every pixel centre whose ray meets a quad (float64 coverage, here) has the
    Lambert closed form, every other one is black (the scene has a light: no environment), in
    the raster and ray-traced G-buffers and the path tracer; centres within 0.2 mm of an edge
    are left out."""
    cells, cell, side = 100, 0.02, 0.012
    sun = (0.2, -1.0, 0.1)
    s = Scene("instances")
    s.add_material(lambert("Tile", (0.6,) * 3))
    mesh = s.add_mesh(Mesh("Tile", *quad_mesh([[-0.5, 0, -0.5], [0.5, 0, -0.5], [0.5, 0, 0.5], [-0.5, 0, 0.5]], (0, 1, 0)),
                           np.uint32(0)))
    centres = (np.arange(cells) - (cells - 1) / 2) * cell
    for x in centres:
        for z in centres:
            t = np.diag([side, 1.0, side, 1.0])
            t[:3, 3] = (x, 0.0, z)
            s.add_instance(mesh, t)
    s.lights.append(Light("directional", direction=sun, intensity=2.0))
    views = view_set((0.013, 2.2, 0.007), (0.013, 0.0, 0.007), fov=50.0, size=32, up=(0, 0, -1))
    o, d = pixel_rays(views)
    p = o + d * (-o[..., 1:2] / d[..., 1:2])
    local = (p[..., [0, 2]] - centres[0]) / cell
    off = np.abs(local - np.round(local)) * cell                      # distance from the nearest cell centre
    inside = np.all(off < side / 2, axis=-1) & np.all(np.abs(p[..., [0, 2]]) < cells * cell / 2, axis=-1)
    clear = np.all(np.abs(off - side / 2) > 2e-4, axis=-1)
    want = np.where(inside, lambert_under_sun(0.6, 2.0, sun), 0.0)
    assert 100 < inside.sum() < inside.size - 100
    images = {"path tracer": render(s, path_traced(), views, PT)}
    for gbuffer in ("raster", "rt"):
        images[f"SHADOWS ({gbuffer})"] = render(set_effect(s, rv.Effect.SHADOWS), hybrid(gbuffer=gbuffer), views,
                                                HYBRID)
    for what, img in images.items():
        got = sane(img, what)[0, ..., 0]
        np.testing.assert_allclose(got[clear], want[clear], rtol=HALF_RTOL, atol=0, err_msg=what)


# ---- 17. degenerate triangles --------------------------------------------------------------------
def test_degenerate_triangles_change_nothing(gpu):
    """Zero-area triangles (a repeated vertex, three collinear points, an emissive one), a 1e-12 m
    triangle and a 1e-12 m wide needle mixed into the Cornell box as meshes of their own: no ray can meet them, so the image is the box's, bit for bit but for
    rounding, in both graphs, and nothing is NaN (their normals, BVH boxes and light-table areas)."""
    tri = np.array([[0.1, 0.2, 0.1], [0.1, 0.2, 0.1], [0.2, 0.3, 0.1],          # repeated vertex
                    [-0.1, 0.1, 0.0], [0.0, 0.2, 0.0], [0.1, 0.3, 0.0],         # collinear
                    [0.0, 0.0, 0.0], [1e-12, 0.0, 0.0], [0.0, 1e-12, 0.0],      # 1e-12 m
                    [-0.2, 0.3, 0.2], [0.0, 0.3, 0.2], [-0.2, 0.3 + 1e-12, 0.2]], np.float32)   # needle
    views = default_views(cornell_box(), 2, (16, 16))
    images = {}
    for degenerate in (False, True):
        s = set_effect(cornell_box(), rv.Effect.REFLECTIONS)
        if degenerate:
            s.add_material(lambert("Sliver", (0.6,) * 3))
            s.add_material(lambert("DarkEmitter", (0.6,) * 3, emissive=(1.0, 1.0, 1.0)))
            s.add_object("Slivers", tri, np.arange(12, dtype=np.uint32).reshape(4, 3), "Sliver")
            s.add_object("Flat", tri[:3], np.array([[0, 1, 2]], np.uint32), "DarkEmitter")
            assert np.isfinite(s.meshes[-1].normals).all() and np.isfinite(s.meshes[-2].normals).all()
        images[degenerate] = (sane(render(s, path_traced(spp=2, bounces=3), views, PT), f"pt, {degenerate}"),
                              sane(render(s, hybrid(), views, HYBRID), f"hybrid, {degenerate}"))
    np.testing.assert_allclose(images[True][0], images[False][0], rtol=1e-5, atol=1e-7)
    np.testing.assert_allclose(images[True][1], images[False][1], rtol=HALF_RTOL, atol=1e-6)


# ---- 18. tiny and huge scenes (test_stability has 1e-3 and 1e4 with the raster G-buffer) ----------
@pytest.mark.parametrize("scale, gbuffer", [(1e-4, "raster"), (1e-4, "rt"), (1e4, "rt")])
def test_a_tenth_of_a_millimetre_and_a_ten_kilometre_cornell_box_render_the_unit_image(gpu, scale, gbuffer):
    """Radiance from an area light depends on solid angles only: the Cornell box and its camera
    scaled by 1e-4 (0.06 mm) or 1e4 render the unit box's image, in the hybrid with either
    G-buffer and in the path tracer (ray offsets and clip planes scale with the scene)."""
    from test_stability import transformed_cornell

    views = {}
    for k in (1.0, scale):
        s = set_effect(transformed_cornell(k), rv.Effect.REFLECTIONS)
        v = default_views(s, 1, (16, 16))   # mono: a stereo pair's IPD would not scale
        views[k] = (sane(render(s, hybrid(gbuffer=gbuffer), v, HYBRID), f"hybrid at {k}"),
                    sane(render(s, path_traced(spp=2, bounces=3), v, PT), f"path tracer at {k}"))
    for got, ref, what in zip(views[scale], views[1.0], ("hybrid", "path tracer")):
        diff = np.abs(got - ref).mean() / ref.mean()
        assert diff < 1e-3, f"{what} at scale {scale}: mean relative difference {diff:.6f}"


# ---- 2. a stereo pair far from the origin --------------------------------------------------------
@pytest.mark.parametrize("offset", [(1e5, 0.0, -1e5), (1e7, 3e6, 1e7)])
def test_a_stereo_pair_far_from_the_origin_renders_the_image_at_the_origin(gpu, offset):
    """The Cornell box and a stereo camera moved 1e5 m and 1e7 m (where float32 world positions
    are 1 m apart): the scene is re-anchored at the eyes (render space, scene/gpu_frame.py), so
    both eyes see the image at the origin, in the hybrid with either G-buffer and the path tracer."""
    from test_stability import transformed_cornell

    images = {}
    for where in ((0.0, 0.0, 0.0), offset):
        s = set_effect(transformed_cornell(1.0, where), rv.Effect.REFLECTIONS)
        v = default_views(s, 2, (16, 16))
        images[where] = [sane(render(s, hybrid(gbuffer=g), v, HYBRID), f"{g} at {where}") for g in ("raster", "rt")]
        images[where].append(sane(render(s, path_traced(spp=2, bounces=3), v, PT), f"path tracer at {where}"))
    for got, ref, what in zip(images[offset], images[(0.0, 0.0, 0.0)], ("raster", "rt", "path tracer")):
        diff = np.abs(got - ref).mean() / ref.mean()
        assert diff < 1e-3, f"{what} {offset} m away: mean relative difference {diff:.5f}"


# ---- 19. lights on and inside surfaces -----------------------------------------------------------
def test_a_point_light_on_a_surface_or_inside_a_closed_box_stays_finite(gpu):
    """A point light exactly on a Lambert plane (distance 0 from the point below it): every point
    of the plane sees it at cos = 0, so the plane stays black (the 1 / d^2 at d = 0 meets a zero
    cosine, never 0 * Inf); the same light 1 m up gives the closed form. A point light inside a
    closed box on the plane: the box and the plane are exactly dark where shadows are traced
    (the box's outer faces turn away from it, the box occludes the plane)."""
    views = view_set((0.3, 2.0, 1.5), (0.0, 0.0, 0.0), fov=50.0)
    for height in (0.0, 1.0):
        s = plane_scene(sun=None, half=20.0)
        s.lights.append(Light("point", position=(0.0, height, 0.0), intensity=2.0))
        o, d = pixel_rays(views)
        p = o + d * (-o[..., 1:2] / d[..., 1:2])
        dist2 = ((p - [0.0, height, 0.0]) ** 2).sum(-1)
        want = 0.4 / math.pi * 2.0 * height / dist2 ** 1.5
        images = {"path tracer": render(s, path_traced(), views, PT)}
        for effect in EFFECTS[:3]:
            images[effect.name] = render(set_effect(s, effect), hybrid(), views, HYBRID)
        for what, img in images.items():
            got = sane(img, f"{what}, light at {height} m")[0, ..., 0]
            np.testing.assert_allclose(got, want, rtol=3e-3, atol=1e-6, err_msg=f"{what}, light at {height} m")
    s = plane_scene(sun=None)
    s.add_material(lambert("Box", (0.6,) * 3))
    s.add_object("Box", *box((-0.3, 0.0, -0.3), (0.3, 0.6, 0.3)), "Box")
    s.lights.append(Light("point", position=(0.0, 0.3, 0.0), intensity=2.0))
    images = {"path tracer": render(s, path_traced(bounces=3), views, PT)}
    for effect in EFFECTS[1:]:
        images[effect.name] = render(set_effect(s, effect), hybrid(max_bounces=2), views, HYBRID)
    for what, img in images.items():
        assert sane(img, what).max() == 0.0, f"{what}: light escaped the box ({img.max()})"


# ---- the G-buffer's normal precision -------------------------------------------------------------
def smooth_sphere(radius=100.0, material=None) -> Scene:
    """An icosphere of radius `radius` m whose vertex normals are its vertices' directions: the
    interpolated normal at a point of a facet is then exactly the direction of that point from
    the centre, a float64 reference for every pixel."""
    import trimesh

    ico = trimesh.creation.icosphere(subdivisions=3, radius=radius)
    s = Scene("sphere")
    # albedo 0.5: exact in every base-colour format (0.6 is 0.6001 in the G-buffer's float16)
    s.add_material(material or lambert("Sphere", (0.5,) * 3, effect=rv.Effect.RASTER))
    s.add_object("Sphere", ico.vertices, ico.faces, 0, normals=ico.vertices / radius)
    return s


@pytest.mark.parametrize("gbuffer", ["raster", "rt"])
def test_the_gbuffers_shading_normals_are_as_precise_as_float32(gpu, gbuffer):
    """A 100 m smooth sphere seen from 300 m: the G-buffer's shading normal against the float64
    normal at its own position is within 1e-5 rad (float16 normals: up to 3.3e-4 rad), and its
    Lambert radiance near the terminator, lit from the side, is rho / pi * E * n.l of the float64
    normal within 0.15% from n.l = 0.01 (float16 normals: 0.19% here, 0.5% at 64 x 64 pixels). Pixels on
    facets that face away from the light are dark (the light sample's side test takes the
    geometric normal) and left out. The face normal, which only picks sides and offsets rays,
    keeps float16."""
    s = smooth_sphere()
    sun = np.array([-1.0, 0.0, -0.25])
    s.lights.append(Light("directional", direction=sun, intensity=2.0))
    views = view_set((0.0, 0.0, 300.0), (0.0, 0.0, 0.0), fov=45.0, size=32, far=1e4)
    g = hybrid(gbuffer=gbuffer)
    for pin in ("GBuffer.posW", "GBuffer.normW", "GBuffer.faceNormalW"):
        g.mark_output(pin)
    with Renderer(s, g, views=views) as r:
        r.render()
        origin = r.view_set.origin()
        img = sane(r.read_output(HYBRID).astype(np.float64))[0, ..., 0]
        pos = r.read_output("GBuffer.posW")[0].astype(np.float64)
        n = r.read_output("GBuffer.normW")[0, ..., :3].astype(np.float64)
        ng = r.read_output("GBuffer.faceNormalW")[0, ..., :3].astype(np.float64)
    hit = pos[..., 3] > 0
    assert hit.sum() > 200
    want = pos[hit, :3] + origin
    want /= np.linalg.norm(want, axis=-1, keepdims=True)

    def angle(a):
        a = a[hit] / np.linalg.norm(a[hit], axis=-1, keepdims=True)
        return np.arccos(np.clip((a * want).sum(-1), -1.0, 1.0))

    assert angle(n).max() < 1e-5, f"shading normals off by up to {angle(n).max():.2e} rad"
    assert angle(ng).max() < 0.1   # a facet's normal: the tessellation's angle, not rounding
    cos = want @ (-sun / np.linalg.norm(sun))
    band = (cos > 0.01) & (cos < 0.3) & (img[hit] > 0)
    assert band.sum() >= 20
    err = np.abs(img[hit][band] / (0.5 / math.pi * 2.0 * cos[band]) - 1.0)
    assert err.max() < 1.5e-3, f"radiance near the terminator off by up to {err.max():.2%}"


@pytest.mark.parametrize("roughness", [0.05, 0.01])
def test_a_near_mirrors_highlight_in_the_hybrid_is_the_path_tracers(gpu, roughness):
    """A tilted smooth metal plane (its normal one that float16 rounds by 3.9e-4 rad) whose
    mirror direction at the central pixel points at a directional light: the highlight's peak,
    D = 1 / (pi alpha^2) wide of alpha = roughness^2, depends on the normal to a fraction of
    alpha. The hybrid (ray-traced G-buffer: the same points as the path tracer's pixel-centre
    rays) equals the path tracer within 0.5% of the peak (float16 normals: within it at roughness
    0.05, 9.7% at 0.01)."""
    n = np.array([-0.57739167, 0.60865618, 0.54420264])
    t1 = np.cross(n, [0.0, 0.0, 1.0])
    t1 /= np.linalg.norm(t1)
    t2 = np.cross(n, t1)
    s = Scene("tilted")
    s.add_material(Material("Metal", base_color=(0.6, 0.6, 0.6, 1.0), metallic=1.0, roughness=roughness,
                            effect=rv.Effect.RASTER))
    s.add_object("Plane", *quad_mesh([5 * (a * t1 + b * t2) for a, b in ((-1, -1), (1, -1), (1, 1), (-1, 1))], n), 0)
    eye = 2.0 * n + t1
    v = eye / np.linalg.norm(eye)
    s.lights.append(Light("directional", direction=-(2 * np.dot(v, n) * n - v), intensity=2.0 * roughness ** 4))
    views = view_set(eye, (0.0, 0.0, 0.0), fov=10.0, size=25)
    got = sane(render(s, hybrid(gbuffer="rt"), views, HYBRID))[0, ..., 0]
    want = sane(render(s, path_traced(), views, PT))[0, ..., 0]
    assert want[12, 12] == want.max() > 0.05
    assert np.abs(got - want).max() < 5e-3 * want.max(), f"{np.abs(got - want).max() / want.max():.2%} of the peak"
