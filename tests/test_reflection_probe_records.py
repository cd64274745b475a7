"""RTReflections with probe GI defers the hits' probe lookups to a second dispatch
(glsl/probe_records.glsl, rt_reflections_probes.comp): the result must equal the lookups done in
the traversal kernel (RTReflections' defer_probes=False, the former way, kept as the reference)
within the float16 rounding of the records, at every bounce, with the list and the whole-image
dispatch; graphs without probes allocate no records."""
import numpy as np
import pytest

import rayvr as rv
from rayvr.passes.rt_reflections.rt_reflections import RECORD_BYTES
from rayvr.renderer import Renderer
from rayvr.scene import builtin
from rayvr.xr.cameras import default_views

PROBES = {"counts": [3, 3, 3], "rays_per_probe": 32, "warmup": 2}
RECORDS = ("Reflections.probeHits", "Reflections.probeFactors")


def reflective_scene():
    """The Cornell box with a glossy dielectric floor (diffuse and specular albedo: hits on it
    carry a diffuse record and go on), a glossy metal tall box and a mirror-like half-metal short
    box: paths of two bounces, diffuse and glossy records at both."""
    s = builtin.cornell_box()
    for m in s.materials:
        m.effect = rv.Effect.SHADOWS
    floor, tall, short = s.materials["Floor"], s.materials["TallBox"], s.materials["ShortBox"]
    for m in (floor, tall, short):
        m.effect = rv.Effect.REFLECTIONS
    floor.metallic, floor.roughness = 0.0, 0.15
    tall.metallic, tall.roughness = 1.0, 0.3
    short.metallic, short.roughness = 0.5, 0.0
    return s


def render(gpu, scene, monkeypatch, *, gi, defer, max_bounces, pixels_2d, frames=2):
    g = rv.graphs.hybrid(preset="raw", max_bounces=max_bounces, gi="probes" if gi else None, probes=PROBES if gi else None)
    g.update_pass("Reflections", {"dispatch_mode": "image" if pixels_2d else "list", "defer_probes": defer})
    g.mark_output("Reflections.reflection")
    views = default_views(scene, 2, (32, 28))
    with Renderer(scene, g, views=views, gpu=gpu) as r:
        for _ in range(frames):
            r.render()
        report = r.compiled.report()
        out = r.read_output("Reflections.reflection").astype(np.float64)[..., :3]
    return out, report


@pytest.mark.parametrize("max_bounces, pixels_2d", [(1, True), (2, False), (2, True)])
def test_deferred_probe_lookups_equal_the_in_kernel_ones(gpu, monkeypatch, max_bounces, pixels_2d):
    scene = reflective_scene()
    deferred, report = render(gpu, scene, monkeypatch, gi=True, defer=True, max_bounces=max_bounces,
                              pixels_2d=pixels_2d)
    names = {r.name for r in report.resources}
    assert set(RECORDS) <= names
    assert "probe_lookups" in report.defines["Reflections"] and "PROBE_GI" not in report.defines["Reflections"]
    reference, ref_report = render(gpu, scene, monkeypatch, gi=True, defer=False, max_bounces=max_bounces,
                                   pixels_2d=pixels_2d)
    assert not set(RECORDS) & {r.name for r in ref_report.resources}
    assert ref_report.defines["Reflections"].get("PROBE_GI") == 1
    without, _ = render(gpu, scene, monkeypatch, gi=False, defer=True, max_bounces=max_bounces, pixels_2d=pixels_2d)
    share = reference - without
    # the probes' light is a good part of the reflections, so a wrong factor or a lost bounce shows
    assert share.mean() > 0.1 * reference.mean() > 0.0
    # float16: the stored factors, the radiance stored before the lookups are added, the output
    tolerance = 4e-3 * reference + 1e-4 * reference.max()
    bad = np.abs(deferred - reference) > tolerance
    assert bad.mean() < 0.002, (bad.sum(), np.abs(deferred - reference).max())
    assert abs(deferred.mean() - reference.mean()) < 1e-3 * reference.mean()


def test_records_only_with_probes_and_their_memory(gpu):
    scene = reflective_scene()
    views, size = 2, (24, 16)
    for gi in (None, "probes"):
        for bounces in (1, 3):
            g = rv.graphs.hybrid(preset="raw", max_bounces=bounces, gi=gi, probes=PROBES if gi else None)
            gpu_scene = rv.scene.GpuScene(gpu, scene)
            compiled = g.compile(scene=scene, size=size, views=views, gpu=gpu, gpu_scene=gpu_scene)
            try:
                report = compiled.report()
                records = {r.name: r for r in report.resources if r.name in RECORDS}
                if gi is None:
                    assert not records and "probeHits" not in str(report)
                    assert "PROBE" not in str(report.defines["Reflections"])
                    continue
                assert set(records) == set(RECORDS)
                for r in records.values():
                    assert r.format == "rgba32ui" and r.layers == views * bounces
                assert sum(r.bytes for r in records.values()) == size[0] * size[1] * views * bounces * RECORD_BYTES \
                    == g.passes["Reflections"].record_bytes(size, views, gpu_scene)
                assert "Reflections.probeHits" in str(report)
            finally:
                compiled.release()
