"""Numerical stability on stiff and extreme cases, end to end through the hybrid and path-traced
graphs: huge and tiny scales, far from the origin, grazing views, roughness 0, degenerate
triangles and blinding emitters. No NaN or Inf anywhere, and the error against the well-posed case
stays bounded.

The Cornell box is lit by an emissive quad, and the radiance an area light sends to a point depends
on solid angles only: scaling the whole scene and the camera by s leaves the image unchanged. So
each extreme variant must render the image of the unit box.
"""
import numpy as np
import pytest

import rayvr as rv
from rayvr.graphs import path_traced
from rayvr.materials.material import Material
from rayvr.renderer import Renderer
from rayvr.scene import builtin
from rayvr.scene.model import Camera

SIZE = (24, 24)


def transformed_cornell(scale: float = 1.0, offset=(0.0, 0.0, 0.0)):
    """The Cornell box scaled by `scale` about the origin, then moved by `offset` (camera too)."""
    scene = builtin.cornell_box()
    m = np.diag([scale, scale, scale, 1.0])
    m[:3, 3] = offset
    for inst in scene.instances:
        inst.transform = m @ inst.transform
    for cam in scene.cameras:
        cam.transform = m @ cam.transform
        cam.transform[:3, :3] /= scale            # keep the camera's rotation orthonormal
        cam.znear, cam.zfar = cam.znear * scale, cam.zfar * scale
    return scene


def render(scene, graph, output, views=1, frames=1):
    with Renderer(scene, graph, views=views, size=SIZE) as r:
        for _ in range(frames):
            r.render()
        return r.read_output(output).astype(np.float64)


def assert_finite(img, what):
    bad = ~np.isfinite(img)
    assert not bad.any(), f"{what}: {int(bad.sum())} non-finite values, first at {np.argwhere(bad)[0]}"


def all_effect(scene, effect):
    for m in scene.materials:
        m.effect = effect
    return scene


HYBRID_OUT = "Composite.color"


@pytest.fixture(scope="module")
def unit_images(gpu):
    hyb = render(all_effect(transformed_cornell(), rv.Effect.REFLECTIONS), rv.graphs.hybrid(preset="raw"), HYBRID_OUT)
    pt = render(transformed_cornell(), path_traced(samples_per_pixel=2, max_bounces=3), "Accumulate.dst")
    return hyb, pt


@pytest.mark.parametrize("scale, offset", [
    (1e-3, (0, 0, 0)),          # a millimetre box
    (1e4, (0, 0, 0)),           # ten kilometres
    (1.0, (1e6, -2e5, 3e5)),    # a thousand kilometres from the origin
    (1e-2, (5e4, 0, 0)),        # small and far: float32 world space would lose it entirely
])
def test_extreme_scales_and_offsets_render_the_unit_image(gpu, unit_images, scale, offset):
    hyb_ref, pt_ref = unit_images
    hyb = render(all_effect(transformed_cornell(scale, offset), rv.Effect.REFLECTIONS), rv.graphs.hybrid(preset="raw"), HYBRID_OUT)
    pt = render(transformed_cornell(scale, offset), path_traced(samples_per_pixel=2, max_bounces=3), "Accumulate.dst")
    for img, ref, what in ((hyb, hyb_ref, "hybrid"), (pt, pt_ref, "path traced")):
        assert_finite(img, f"{what} at scale {scale}, offset {offset}")
        # same random numbers, same solid angles: only rounding and rare path flips differ
        diff = np.abs(img[..., :3] - ref[..., :3]).mean() / ref[..., :3].mean()
        assert diff < 0.05, f"{what} at scale {scale}, offset {offset}: mean relative difference {diff:.3f}"


def test_grazing_mirror_roughness_zero_degenerate_triangles_and_a_blinding_light(gpu):
    scene = builtin.cornell_box()
    floor = scene.materials["Floor"]
    floor.metallic, floor.roughness, floor.effect = 1.0, 0.0, rv.Effect.REFLECTIONS   # a perfect mirror
    scene.materials["Light"].emissive_strength = 1e8                                 # blinding
    scene.add_material(Material("Sliver", base_color=(0.5, 0.5, 0.5, 1.0)))
    # degenerate triangles in view: a zero-area one and a needle of 1e-9 m
    pos = np.array([[0.2, 0.1, 0.2], [0.2, 0.1, 0.2], [0.3, 0.2, 0.2],
                    [0.1, 0.3, 0.3], [0.4, 0.3, 0.3], [0.1 + 1e-9, 0.3, 0.3]], np.float32)
    scene.add_object("Degenerate", pos, np.arange(6, dtype=np.uint32).reshape(2, 3), "Sliver")
    # a camera skimming the mirror floor at ~0.5 degrees
    lo, hi = scene.bounds()
    eye = np.array([0.5 * (lo[0] + hi[0]), lo[1] + 0.004, hi[2] - 0.01])
    scene.cameras[:] = [Camera.look_at(eye, eye + [0.0, -0.0087, -1.0], yfov_deg=40.0)]
    for graph, out in ((rv.graphs.hybrid(preset="raw"), HYBRID_OUT),
                       (path_traced(samples_per_pixel=2, max_bounces=4), "Accumulate.dst")):
        img = render(scene, graph, out, views=2, frames=2)
        assert_finite(img, f"{graph.name} on the grazing mirror")
        assert (img[..., :3] >= 0).all()
        # walls lit by the 1e8 emitter reach ~5e5 (rho/pi * L_e * solid angle * cos): the
        # rgba16f composite saturates at the largest half, the rgba32f accumulation keeps it
        assert img[..., :3].max() >= (65504.0 if out == HYBRID_OUT else 2e5)
