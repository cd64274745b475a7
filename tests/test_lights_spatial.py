"""Spatial light selection (light_table.pack_emissive, glsl/lights.glsl sample_light_spatial):
the emissive clusters' layout, a Lambert plane under a bright point light and a small lamp against
Lambert's closed form for a polygon's irradiance, the lamp's noise against selection by power,
and the path tracer's MIS (light samples and BSDF rays that hit a lamp) against selection by
power, on a glossy plane."""
import math

import numpy as np
import pytest

import rayvr as rv
from rayvr.scene import light_table as lt
from rayvr.scene.builtin import lambert, quad_mesh
from rayvr.errors import OptionError
from rayvr.scene.gpu_scene import GpuScene
from rayvr.scene.model import Light, Material, Scene
from rayvr.xr.cameras import look_at
from rayvr.xr.views import Fov, View, ViewSet
from test_lights_environment import down_view, plane_points

LAMP = np.array([[-0.9, 0.4, -0.3], [-0.3, 0.4, -0.3], [-0.3, 0.4, 0.3], [-0.9, 0.4, 0.3]])   # facing down
LAMP_L = 5.0


def test_each_emissive_instance_is_a_cluster_with_its_own_alias_table():
    rng = np.random.default_rng(5)
    powers = rng.exponential(size=7)
    ids = np.arange(28, dtype=np.uint32).reshape(7, 4)
    tri = rng.normal(size=(3, 3, 3))
    clusters = [lt.emissive_cluster(4, tri, 0, powers[:3]), lt.emissive_cluster(9, tri[:1], 3, powers[3:])]
    assert clusters[0].power == pytest.approx(powers[:3].sum())
    v = tri.reshape(-1, 3)
    assert np.linalg.norm(v - clusters[0].centre, axis=1).max() == pytest.approx(clusters[0].radius)
    transforms = np.tile(np.eye(4), (10, 1, 1))
    transforms[4, :3, :3] = np.diag([2.0, 1.0, 0.5])   # instance 4: scaled and moved
    transforms[4, :3, 3] = [10.0, 0.0, -3.0]
    anchor = np.array([9.0, 1.0, 0.0])
    head = lt.pack_clusters(clusters, transforms, anchor)
    rows = lt.pack_emissive(ids, powers, clusters, head)
    bits = rows.view(np.uint32)
    assert bits[0, 0] == 2
    np.testing.assert_allclose(rows[1, :3], np.diag([2.0, 1.0, 0.5]) @ clusters[0].centre + [1.0, -1.0, -3.0],
                               rtol=1e-6)   # anchor space: world minus the anchor
    assert rows[1, 3] == pytest.approx(2.0 * clusters[0].radius)   # the largest axis scale
    np.testing.assert_array_equal(bits[2, :3], [4, 0, 3])
    np.testing.assert_array_equal(bits[4, :3], [9, 3, 4])
    assert rows[4, 3] == pytest.approx(powers[3:].sum(), rel=1e-6)
    first = lt.CLUSTER_ROWS
    tri_rows = bits[first::2]
    np.testing.assert_array_equal(tri_rows[:, :3], ids[:, :3])
    for c in clusters:   # each triangle's alias stays in its cluster and draws it by its power share
        sl = slice(c.first, c.first + c.count)
        alias = tri_rows[sl, 3].astype(np.int64) - c.first
        assert alias.min() >= 0 and alias.max() < c.count
        p = lt.alias_probabilities(rows[first + 1::2][sl, 0].astype(np.float64), alias)
        np.testing.assert_allclose(p, powers[sl] / powers[sl].sum(), rtol=1e-6)
    assert lt.pack_clusters(clusters, transforms, anchor, spatial=False).view(np.uint32)[0, 0] == 0
    many = [lt.emissive_cluster(k % 10, tri[:1], k, powers[:1]) for k in range(lt.EMISSIVE_CLUSTERS_MAX + 1)]
    assert lt.pack_clusters(many, transforms, anchor).view(np.uint32)[0, 0] == 0   # too many: by power


def test_a_moving_lamp_takes_its_cluster_along(gpu):
    """The clusters' spheres follow their instances (and the render origin): after the lamp moves
    the buffer holds its new centre, as the renderer's frame update writes it."""
    scene = lamp_scene(lambert("White", (0.8,) * 3), 4.0)
    with rv.Renderer(scene, rv.graphs.hybrid(preset="raw"), views=down_view()) as r:
        r.render()
        gs = r.gpu_scene
        lamp = next(i for i, inst in enumerate(scene.instances) if inst.name == "Lamp")
        t = scene.instances[lamp].transform.copy()
        t[:3, 3] += [0.5, 0.2, 0.0]
        scene.instances[lamp].transform = t
        r.render()
        head = np.frombuffer(gs.buffers["emissive_triangles"].read(), np.float32)[:lt.CLUSTER_ROWS * 4].reshape(-1, 4)
        centre = LAMP.mean(axis=0) + [0.5, 0.2, 0.0]
        np.testing.assert_allclose(head[1, :3], centre - gs.frame.anchor, atol=1e-5)
        assert gs.emissive_clusters == 1


def lamp_scene(material: Material, point_intensity: float, spatial: bool = True) -> Scene:
    s = Scene("lamp")
    s.light_selection = "spatial" if spatial else "power"
    s.add_material(material)
    s.add_material(lambert("Lamp", (0.0, 0.0, 0.0), emissive=(LAMP_L,) * 3))
    s.add_object("Plane", *quad_mesh([[-2, 0, -2], [2, 0, -2], [2, 0, 2], [-2, 0, 2]], facing=(0, 1, 0)),
                 material.name)
    s.add_object("Lamp", *quad_mesh(LAMP, facing=(0, -1, 0)), "Lamp")
    s.lights = [Light("point", position=(1.2, 1.5, 0.0), intensity=point_intensity)]
    return s


def polygon_irradiance(x: np.ndarray, n: np.ndarray, poly: np.ndarray, radiance: float) -> np.ndarray:
    """Lambert's closed form: irradiance at points x (..., 3) with normal n of a Lambertian polygon
    of `radiance` (unoccluded, wholly above the points' horizon)."""
    total = np.zeros(x.shape[:-1])
    for k in range(len(poly)):
        a = poly[k] - x
        b = poly[(k + 1) % len(poly)] - x
        a /= np.linalg.norm(a, axis=-1, keepdims=True)
        b /= np.linalg.norm(b, axis=-1, keepdims=True)
        c = np.cross(a, b)
        theta = np.arccos(np.clip((a * b).sum(-1), -1.0, 1.0))
        total += theta * (c / np.linalg.norm(c, axis=-1, keepdims=True) * n).sum(-1)
    return 0.5 * radiance * np.abs(total)


def through_lamp(pts: np.ndarray, eye: np.ndarray) -> np.ndarray:
    """Whether the segment from each plane point to `eye` crosses the lamp (y = 0.4)."""
    t = (0.4 - pts[..., 1]) / (eye[1] - pts[..., 1])
    q = pts + t[..., None] * (eye - pts)
    return (q[..., 0] > -0.9) & (q[..., 0] < -0.3) & (np.abs(q[..., 2]) < 0.3)


def frames_of(scene, graph, views, pin, frames) -> np.ndarray:
    with rv.Renderer(scene, graph, views=views) as r:
        out = []
        for _ in range(frames):
            r.render()
            out.append(r.read_output(pin)[0, ..., :3].astype(np.float64))
    return np.array(out)




def lamp_plane_radiance(pts: np.ndarray) -> np.ndarray:
    """Closed form of the white (0.8) Lambert plane's radiance under the point light (intensity 4;
    the lamp shadows it) and the lamp (Lambert's polygon formula)."""
    up = np.array([0.0, 1.0, 0.0])
    to = np.array([1.2, 1.5, 0.0]) - pts
    d2 = (to ** 2).sum(-1)
    e_point = 4.0 * to[..., 1] / d2 ** 1.5 * ~through_lamp(pts, np.array([1.2, 1.5, 0.0]))
    return 0.8 / math.pi * (e_point + polygon_irradiance(pts, up, LAMP, LAMP_L))


def test_a_small_lamp_beside_a_bright_point_light_is_drawn_where_it_lights(gpu):
    """A white Lambert plane under a point light of 60 times the lamp's power and a 0.6 m lamp
    0.4 m above it: the mean of 64 one-sample frames is the closed form (point light + Lambert's
    polygon formula) everywhere, and under the lamp, where it gives most of the light, the frames'
    variance is a fraction of what drawing by power alone leaves (1.7% of the samples, each 60x).
    Before the shadow rays were aimed from their offset origin, that lamp hid its own light."""
    views = down_view()
    pts = plane_points(views)
    want = lamp_plane_radiance(pts)
    seen = ~through_lamp(pts, np.array([0.0, 3.0, 0.0]))   # the camera sees the lamp's dark back
    under = (np.abs(pts[..., 0] + 0.6) < 0.4) & (np.abs(pts[..., 2]) < 0.4) & seen
    assert under.sum() >= 9 and seen.mean() > 0.9
    var = {}
    for spatial in (True, False):
        scene = lamp_scene(lambert("White", (0.8,) * 3), 4.0, spatial)
        scene.materials["White"].effect = rv.Effect.SHADOWS
        f = frames_of(scene, rv.graphs.hybrid(preset="raw"), views, "Composite.color", 64)[..., 0]
        var[spatial] = f[:, under].var(0).mean()
        if spatial:
            got = f.mean(0)[seen]
            err = np.abs(got - want[seen]) / np.sqrt(f.var(0)[seen] / len(f) + 1e-8)
            assert np.sqrt((err ** 2).mean()) < 2.0
            assert abs(got.sum() / want[seen].sum() - 1.0) < 0.01
    assert var[True] < 0.2 * var[False], var


@pytest.mark.parametrize("spatial", [True, False])
def test_the_path_tracer_lights_the_plane_from_the_near_lamp_as_the_closed_form_says(gpu, spatial):
    """The same plane path traced (light samples and BSDF rays that hit the lamp, by MIS), either
    light selection: the converged mean is the closed form."""
    views = down_view()
    pts = plane_points(views)
    want = lamp_plane_radiance(pts)
    seen = ~through_lamp(pts, np.array([0.0, 3.0, 0.0]))
    scene = lamp_scene(lambert("White", (0.8,) * 3), 4.0, spatial)
    scene.materials["White"].effect = rv.Effect.PATH_TRACED
    g = rv.graphs.path_traced(samples_per_pixel=16, max_bounces=2)
    g.update_pass("PathTracer", {"pixel_jitter": False})   # the closed form is at pixel centres
    g.mark_output("PathTracer.color")
    f = frames_of(scene, g, views, "PathTracer.color", 24)[..., 0]
    got = f.mean(0)[seen]
    err = (got - want[seen]) / np.sqrt(f.var(0)[seen] / len(f) + 1e-8)
    assert np.sqrt((err ** 2).mean()) < 2.0
    assert abs(got.sum() / want[seen].sum() - 1.0) < 0.01


def test_path_traced_mis_on_a_glossy_plane_agrees_with_selection_by_power(gpu):
    """A glossy plane (roughness 0.25) seen at an angle under a lamp and a point light: BSDF rays
    that hit the lamp are weighted by the lamp's light-sampling pdf at their origin, which the
    spatial selection makes depend on the point. Any mismatch between the pdf it draws with and
    the one MIS evaluates shows as a difference from selection by power alone (which tests of
    the path tracer check against closed forms): the two converged means agree within noise."""
    views = ViewSet([View(look_at((0.0, 1.5, 2.5), (-0.3, 0.0, 0.0)), Fov.symmetric(50.0, 1.0), 16, 16, 0.01, 10.0)])
    means = {}
    for spatial in (True, False):
        scene = lamp_scene(Material("Gloss", base_color=(0.8, 0.8, 0.8, 1.0), metallic=0.0, roughness=0.25), 2.0,
                           spatial)
        scene.materials["Gloss"].effect = rv.Effect.PATH_TRACED
        g = rv.graphs.path_traced(samples_per_pixel=16, max_bounces=3)
        g.mark_output("PathTracer.color")
        f = frames_of(scene, g, views, "PathTracer.color", 48)
        means[spatial] = (f.mean(0), f.var(0) / len(f))
    (m1, v1), (m0, v0) = means[True], means[False]
    ok = (v0 + v1) > 1e-10
    z = (m1 - m0)[ok] / np.sqrt((v0 + v1)[ok])
    assert ok.mean() > 0.5
    assert np.sqrt((z ** 2).mean()) < 1.6, np.sqrt((z ** 2).mean())
    assert abs(m1.sum() / m0.sum() - 1.0) < 0.01


def test_a_light_selection_that_does_not_exist_is_refused_naming_the_field(gpu):
    scene = lamp_scene(lambert("White", (0.8,) * 3), 4.0)
    scene.light_selection = "nearest"
    with pytest.raises(OptionError, match=r"scene 'lamp'.light_selection: 'nearest'; use one of power, spatial"):
        GpuScene(gpu, scene)
