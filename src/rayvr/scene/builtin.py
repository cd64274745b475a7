"""Scenes built in code: the Cornell box, a spheres scene, and the tiny scenes tests need.

All in glTF conventions (metres, +Y up, cameras look down -Z). Triangle counts stay small.
"""
from __future__ import annotations

import math

import numpy as np

from ..materials.effect import Effect
from ..materials.material import Material
from .model import Camera, Light, Mesh, Scene


def quad_mesh(corners, facing=None):
    """Positions (4, 3) and indices (2, 3) of a planar quad; wound so its normal points along `facing`."""
    p = np.asarray(corners, dtype=np.float64)
    idx = np.array([[0, 1, 2], [0, 2, 3]], dtype=np.uint32)
    if facing is not None and np.dot(np.cross(p[1] - p[0], p[2] - p[0]), facing) < 0:
        idx = idx[:, ::-1].copy()
    return p.astype(np.float32), idx


def merge(parts):
    """Concatenate (positions, indices) pairs into one mesh."""
    pos, idx, base = [], [], 0
    for p, i in parts:
        pos.append(p)
        idx.append(i + base)
        base += len(p)
    return np.concatenate(pos).astype(np.float32), np.concatenate(idx).astype(np.uint32)


def box(lo, hi):
    """An axis-aligned box with outward normals: positions (24, 3), indices (12, 3)."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    return prism([(lo[0], lo[2]), (hi[0], lo[2]), (hi[0], hi[2]), (lo[0], hi[2])], lo[1], hi[1])


def prism(footprint_xz, y0, y1):
    """A vertical prism over a convex xz polygon (the Cornell blocks), outward normals."""
    fp = np.asarray(footprint_xz, dtype=np.float64)
    centre = np.array([fp[:, 0].mean(), (y0 + y1) / 2, fp[:, 1].mean()])
    top = [(x, y1, z) for x, z in fp]
    bottom = [(x, y0, z) for x, z in fp]
    parts = [quad_mesh(top, (0, 1, 0)), quad_mesh(bottom, (0, -1, 0))]
    n = len(fp)
    for i in range(n):
        j = (i + 1) % n
        side = [bottom[i], bottom[j], top[j], top[i]]
        mid = np.mean(side, axis=0)
        parts.append(quad_mesh(side, mid - centre))
    return merge(parts)


def lambert(name, rgb, **kw) -> Material:
    """A Lambertian material of linear colour rgb: non-metallic, fully rough, and without the
    dielectric's specular layer (KHR_materials_specular's factor 0), so f = rgb / pi exactly."""
    return Material(name, base_color=(*rgb, 1.0), metallic=0.0, roughness=1.0, specular=0.0, **kw)


def _cornell(x, z):
    """Cornell data (mm, camera looking +z) to glTF metres: a 180 degree turn about +Y, centred."""
    return (278.0 - x) / 1000.0, (279.6 - z) / 1000.0


def cornell_box() -> Scene:
    """The classic Cornell box (Cornell University's measured geometry and common RGB colours),
    its ceiling light an emissive quad (emission (17, 12, 4))."""
    s = Scene("cornell_box")
    white, red, green = (0.725, 0.71, 0.68), (0.63, 0.065, 0.05), (0.14, 0.45, 0.091)
    for name, rgb in [("Floor", white), ("Ceiling", white), ("BackWall", white), ("LeftWall", red),
                      ("RightWall", green), ("ShortBox", white), ("TallBox", white)]:
        s.add_material(lambert(name, rgb))
    s.add_material(lambert("Light", (0.78, 0.78, 0.78), emissive=(1.0, 12 / 17, 4 / 17),
                           emissive_strength=17.0))

    def p(x, y, z):
        cx, cz = _cornell(x, z)
        return cx, y / 1000.0, cz

    walls = {
        "Floor": ([p(552.8, 0, 0), p(0, 0, 0), p(0, 0, 559.2), p(549.6, 0, 559.2)], (0, 1, 0)),
        "Ceiling": ([p(556, 548.8, 0), p(556, 548.8, 559.2), p(0, 548.8, 559.2), p(0, 548.8, 0)], (0, -1, 0)),
        "BackWall": ([p(549.6, 0, 559.2), p(0, 0, 559.2), p(0, 548.8, 559.2), p(556, 548.8, 559.2)], (0, 0, 1)),
        "LeftWall": ([p(552.8, 0, 0), p(549.6, 0, 559.2), p(556, 548.8, 559.2), p(556, 548.8, 0)], (1, 0, 0)),
        "RightWall": ([p(0, 0, 559.2), p(0, 0, 0), p(0, 548.8, 0), p(0, 548.8, 559.2)], (-1, 0, 0)),
    }
    for name, (corners, facing) in walls.items():
        pos, idx = quad_mesh(corners, facing)
        s.add_object(name, pos, idx, name)
    short = [_cornell(130, 65), _cornell(82, 225), _cornell(240, 272), _cornell(290, 114)]
    tall = [_cornell(423, 247), _cornell(265, 296), _cornell(314, 456), _cornell(472, 406)]
    s.add_object("ShortBox", *prism(short, 0.0, 0.165), "ShortBox")
    s.add_object("TallBox", *prism(tall, 0.0, 0.330), "TallBox")
    light = [p(343, 548.7, 227), p(343, 548.7, 332), p(213, 548.7, 332), p(213, 548.7, 227)]
    s.add_object("Light", *quad_mesh(light, (0, -1, 0)), "Light")
    s.cameras.append(Camera.look_at((0.0, 0.273, 1.0796), (0.0, 0.273, 0.0), yfov_deg=39.3, name="Camera"))
    return s


def spheres(n: int = 3, subdivisions: int = 2) -> Scene:
    """An n x n grid of spheres over a floor, metallic along x and roughness along z, under a
    directional light; each sphere its own mesh and material."""
    import trimesh

    s = Scene("spheres")
    s.add_material(lambert("Floor", (0.5, 0.5, 0.5)))
    s.add_object("Floor", *quad_mesh([(-4, 0, -4), (4, 0, -4), (4, 0, 4), (-4, 0, 4)], (0, 1, 0)), "Floor")
    ico = trimesh.creation.icosphere(subdivisions=subdivisions, radius=0.4)
    for i in range(n):
        for j in range(n):
            name = f"Sphere_{i}_{j}"
            m = s.add_material(Material(name, base_color=(0.9, 0.6, 0.2, 1.0),
                                        metallic=i / max(n - 1, 1), roughness=max(j / max(n - 1, 1), 0.05)))
            t = np.eye(4)
            t[:3, 3] = ((i - (n - 1) / 2) * 1.0, 0.4, (j - (n - 1) / 2) * 1.0)
            s.add_object(name, ico.vertices, ico.faces, m, t, normals=ico.vertex_normals)
    s.lights.append(Light("directional", direction=(-0.3, -1.0, -0.4), intensity=3.0, name="Sun"))
    s.cameras.append(Camera.look_at((0, 2.5, n + 1.5), (0, 0.3, 0), name="Camera"))
    return s


def quad(size: float = 1.0, material: Material | None = None) -> Scene:
    """One square quad in the z = 0 plane facing +Z, centred at the origin; camera on +Z."""
    s = Scene("quad")
    s.add_material(material or lambert("Quad", (0.8, 0.8, 0.8)))
    h = size / 2
    s.add_object("Quad", *quad_mesh([(-h, -h, 0), (h, -h, 0), (h, h, 0), (-h, h, 0)], (0, 0, 1)), 0,
                 uvs=np.array([[0, 0], [1, 0], [1, 1], [0, 1]], np.float32))
    s.cameras.append(Camera.look_at((0, 0, 2), (0, 0, 0), name="Camera"))
    return s


def plane_with_point_light(height: float = 1.0, intensity: float = 1.0, albedo: float = 0.8) -> Scene:
    """A 4 x 4 m Lambert plane at y = 0 under a point light at (0, height, 0) of `intensity` cd.

    Analytic: irradiance E(x, z) = I * h / (x^2 + z^2 + h^2)^1.5, outgoing radiance albedo/pi * E."""
    s = Scene("plane_with_point_light")
    s.add_material(lambert("Plane", (albedo, albedo, albedo)))
    s.add_object("Plane", *quad_mesh([(-2, 0, -2), (2, 0, -2), (2, 0, 2), (-2, 0, 2)], (0, 1, 0)), "Plane")
    s.lights.append(Light("point", position=(0.0, height, 0.0), intensity=intensity, name="Point"))
    s.cameras.append(Camera.look_at((0, 3, 0.001), (0, 0, 0), name="Top"))
    return s


def box_on_plane(light_height: float = 3.0) -> Scene:
    """A 0.5 m box standing on a Lambert plane under a point light straight above it: the box's
    shadow on the plane is the light's projection of its top face (analytic)."""
    s = plane_with_point_light(height=light_height, intensity=10.0)
    s.name = "box_on_plane"
    s.add_material(lambert("Box", (0.8, 0.2, 0.2)))
    s.add_object("Box", *box((-0.25, 0.0, -0.25), (0.25, 0.5, 0.25)), "Box")
    return s


def mirror_and_checker(tiles: int = 4) -> Scene:
    """A perfect mirror (metallic 1, roughness 0, effect REFLECTIONS) at z = 0 facing +Z, and a
    tiles x tiles black/white checker (per-triangle materials) at z = 2 facing it; camera between."""
    s = Scene("mirror_and_checker")
    s.add_material(Material("Mirror", base_color=(1, 1, 1, 1), metallic=1.0, roughness=0.0,
                            effect=Effect.REFLECTIONS))
    white = s.add_material(lambert("CheckerWhite", (0.9, 0.9, 0.9)))
    black = s.add_material(lambert("CheckerBlack", (0.05, 0.05, 0.05)))
    s.add_object("Mirror", *quad_mesh([(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)], (0, 0, 1)), "Mirror")
    parts, mats, step = [], [], 2.0 / tiles
    for i in range(tiles):
        for j in range(tiles):
            x0, y0 = -1 + i * step, -1 + j * step
            parts.append(quad_mesh([(x0, y0, 2), (x0, y0 + step, 2), (x0 + step, y0 + step, 2), (x0 + step, y0, 2)],
                              (0, 0, -1)))
            mats += [white if (i + j) % 2 == 0 else black] * 2
    pos, idx = merge(parts)
    m = s.add_mesh(Mesh("Checker", pos, idx, np.array(mats, np.uint32)))
    s.add_instance(m, name="Checker")
    s.lights.append(Light("point", position=(0, 0, 1.5), intensity=2.0, name="Point"))
    s.cameras.append(Camera.look_at((0, 0, 1.0), (0, 0, 0), name="Camera"))
    return s


def instanced_boxes(n: int = 4) -> Scene:
    """n unit-ish boxes sharing one mesh at different transforms (tests instancing and the TLAS)."""
    s = Scene("instanced_boxes")
    s.add_material(lambert("Box", (0.7, 0.7, 0.7)))
    m = s.add_mesh(Mesh("Box", *box((-0.5, -0.5, -0.5), (0.5, 0.5, 0.5)), np.uint32(0)))
    for i in range(n):
        a = 2 * math.pi * i / n
        t = np.eye(4)
        t[:3, :3] = [[math.cos(a), 0, math.sin(a)], [0, 1, 0], [-math.sin(a), 0, math.cos(a)]]
        t[:3, :3] *= 0.5 + 0.25 * i
        t[:3, 3] = (3 * math.cos(a), 0.5 * i, 3 * math.sin(a))
        s.add_instance(m, t, f"Box_{i}")
    s.cameras.append(Camera.look_at((0, 6, 8), (0, 0, 0), name="Camera"))
    return s


# The built-in scenes by name, as the CLI and benchmarks accept them.
SCENES = {f.__name__: f for f in (cornell_box, spheres, quad, plane_with_point_light, box_on_plane,
                                  mirror_and_checker, instanced_boxes)}

__all__ = ["SCENES", "cornell_box", "spheres", "quad", "plane_with_point_light", "box_on_plane",
           "mirror_and_checker", "instanced_boxes", "box", "prism", "quad_mesh", "merge", "lambert"]
