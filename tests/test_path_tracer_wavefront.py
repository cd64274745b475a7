"""The path tracer's wavefront form (each vertex's rays in a dispatch of their own, pt_wave_*.comp;
what kernel="auto" picks on GPUs) against its megakernel (llvmpipe's pick): both run path.glsl's steps on the same random numbers, so they trace the
same paths and their images agree to float rounding, in every mode: from the camera or the
G-buffer (over the whole image or the compaction's pixel list), with the lobes split for SVGF,
several samples a frame, alphaMode BLEND's stochastic decisions and glass; and in every form of
the wavefront: its paths compacted into queues per bounce, its workgroups of other tiles and
view groups."""
import numpy as np
import pytest

import rayvr as rv
from rayvr.errors import OptionError
from rayvr.scene import builtin

SIZE = (24, 24)


def images(scene, graph, outputs, kernel, frames=2, views=2, size=SIZE):
    graph.get_pass("PathTracer").set_properties({"kernel": kernel})
    with rv.Renderer(scene, graph, size=size, views=views) as r:
        for _ in range(frames):
            r.render()
        report = str(r.report())
        return [np.asarray(r.read_output(o))[..., :3].astype(np.float64) for o in outputs], report


def assert_same(scene, make_graph, outputs, wave_props=None, **kw):
    mega, _ = images(scene, make_graph(), outputs, "megakernel", **kw)
    graph = make_graph()
    graph.get_pass("PathTracer").set_properties(wave_props or {})
    wave, report = images(scene, graph, outputs, "wavefront", **kw)
    for name, a, b in zip(outputs, mega, wave):
        assert np.isfinite(b).all()
        assert a.mean() > 0.0, f"{name}: nothing rendered"
        np.testing.assert_allclose(b, a, rtol=1e-5, atol=1e-6 * max(a.max(), 1e-6), err_msg=name)
    return report


def glossy_cornell():
    s = builtin.cornell_box()
    floor = s.materials["Floor"]
    floor.roughness, floor.metallic, floor.specular = 0.3, 0.5, 1.0
    return s


def glass_and_blend_scene():
    s = builtin.cornell_box()
    glass = s.materials["TallBox"]
    glass.transmission, glass.roughness, glass.base_color = 1.0, 0.2, (1.0, 1.0, 1.0, 0.5)
    glass.alpha_mode = "BLEND"
    return s


COMPACT = {"compact": True}
PERSISTENT = {"persistent": True}   # the trace kernel's lanes take the queue's paths as they finish
SORTED = {"sort_directions": True}  # each bounce's queue sorted by its rays' octants
# the wavefront's forms: as it is; paths compacted per bounce; workgroups of one warp over one view
# or over several views (view_group: frames of 4 views and more)
FORMS = [None, COMPACT, {"tile": [8, 4], "view_group": 1}, {**COMPACT, "tile": [4, 4], "view_group": 4}]


@pytest.mark.parametrize("spp, bounces, form", [(s, b, f) for s, b in [(1, 4), (3, 2), (1, 0), (2, 1)]
                                                for f in (None, COMPACT)] + [(2, 3, PERSISTENT), (2, 3, SORTED)])
def test_full_screen_paths_are_the_megakernels(gpu, spp, bounces, form):
    assert_same(builtin.cornell_box(), lambda: rv.graphs.path_traced(samples_per_pixel=spp, max_bounces=bounces),
                ["Accumulate.dst"], form)


@pytest.mark.parametrize("form", FORMS[2:])
@pytest.mark.parametrize("views, size", [(4, SIZE), (5, (23, 19))])
def test_workgroup_shapes_trace_the_megakernels_paths(gpu, form, views, size):
    """Tiles and view groups change which slot a path has, not the path; edge workgroups of an
    odd image and a partial view group hold slots past the image."""
    assert_same(glossy_cornell(), lambda: rv.graphs.path_traced(samples_per_pixel=2, max_bounces=3),
                ["Accumulate.dst"], form, views=views, size=size)


LOBES = ["PathTracer.color", "PathTracer.diffuse", "PathTracer.specular"]


def lobes_graph():
    g = rv.graphs.path_traced(denoise="svgf", max_bounces=3)
    for pin in LOBES:
        g.mark_output(pin)
    return g


@pytest.mark.parametrize("form", [None, COMPACT])
def test_lobes_for_svgf_are_the_megakernels(gpu, form):
    assert_same(glossy_cornell(), lobes_graph, LOBES, form, frames=1)


@pytest.mark.parametrize("form", [None, COMPACT, PERSISTENT, {**SORTED, **PERSISTENT}])
def test_glass_and_stochastic_transparency_are_the_megakernels(gpu, form):
    assert_same(glass_and_blend_scene(), lambda: rv.graphs.path_traced(samples_per_pixel=2, max_bounces=6),
                ["Accumulate.dst"], form)


@pytest.mark.parametrize("listed, size, form", [(listed, size, form) for listed, size in [(True, SIZE), (False, SIZE),
                                                                                          (False, (23, 19))]
                                                 for form in (None, COMPACT)] + [(True, SIZE, PERSISTENT),
                                                                                 (False, (23, 19), PERSISTENT),
                                                                                 (True, SIZE, SORTED)])
def test_gbuffer_paths_are_the_megakernels(gpu, listed, size, form):
    scene = glossy_cornell()
    for name in ("TallBox", "Floor"):
        scene.materials[name].effect = rv.Effect.PATH_TRACED

    def graph():
        g = rv.graphs.hybrid(preset="raw", path_bounces=3)
        g.mark_output("PathTracer.color")
        if not listed:   # the whole image, pixels of other effects left at 0
            g.remove_edge("Compaction.pathPixels", "PathTracer.pixels")
        return g

    # (23, 19): the image-wide dispatch's edge workgroups hold slots past width x height x views
    assert_same(scene, graph, ["PathTracer.color"], form, frames=1, size=size)


def test_the_state_buffer_is_scratch_of_the_wavefront_alone(gpu):
    scene = builtin.cornell_box()
    _, wave = images(scene, rv.graphs.path_traced(), ["Accumulate.dst"], "wavefront", frames=1, views=1)
    _, mega = images(scene, rv.graphs.path_traced(), ["Accumulate.dst"], "megakernel", frames=1, views=1)
    assert "PathTracer.paths" in wave and "PathTracer.paths" not in mega
    g = rv.graphs.path_traced()
    pt = g.get_pass("PathTracer")
    pt.set_properties({"kernel": "wavefront"})
    assert pt.wave_slots(SIZE, 1) >= SIZE[0] * SIZE[1] and pt.wave_slot_bytes() == 176
    pt.set_properties({"lobes": True})
    assert pt.wave_slot_bytes() == 240


def test_compaction_declares_its_queue_and_the_shapes_are_checked(gpu):
    scene = builtin.cornell_box()
    for form in (COMPACT, PERSISTENT, SORTED):
        g = rv.graphs.path_traced()
        g.get_pass("PathTracer").set_properties(form)
        _, report = images(scene, g, ["Accumulate.dst"], "wavefront", frames=1, views=1)
        assert "PathTracer.queue" in report
    g = rv.graphs.path_traced()
    _, report = images(scene, g, ["Accumulate.dst"], "wavefront", frames=1, views=1)
    assert "PathTracer.queue" not in report
    pt = g.get_pass("PathTracer")
    with pytest.raises(OptionError, match="'tile'"):
        pt.set_properties({"tile": [64, 64]})
    with pytest.raises(OptionError, match="'view_group'"):
        pt.set_properties({"view_group": 0})


def test_kernel_property_round_trips_and_rejects_others(tmp_path):
    g = rv.graphs.path_traced()
    pt = g.get_pass("PathTracer")
    pt.set_properties({"kernel": "wavefront"})
    for name in ("g.json", "g.py"):
        assert rv.RenderGraph.load(g.save(tmp_path / name)).get_pass("PathTracer").kernel == "wavefront"
    with pytest.raises(OptionError, match="property 'kernel'.*'auto'.*'wavefront'.*'megakernel'"):
        pt.set_properties({"kernel": "persistent"})


def test_auto_picks_the_wavefront_on_gpus_and_the_megakernel_on_software(gpu):
    """llvmpipe's dispatches cost more than a GPU's, so the megakernel is its faster form; a GPU's
    traversal loses its occupancy to the BSDF's registers in the megakernel."""
    g = rv.graphs.path_traced()
    assert g.get_pass("PathTracer").kernel == "auto"
    with rv.Renderer(builtin.cornell_box(), g, size=SIZE) as r:
        r.render()
        assert r.compiled.passes["PathTracer"].defines()["PT_WAVEFRONT"] == int(not gpu.caps.is_software)
        assert "PathTracer.paths" in str(r.report())


def test_the_state_keeps_a_medium_exactly_where_its_buffer_has_room():
    # the GpuScene keeps the features of its upload; the state's size and the shaders follow the
    # scene as compiled, so a glass removed later cannot make the shaders write past the buffer
    scene = glass_and_blend_scene()
    g = rv.graphs.path_traced(max_bounces=2)
    g.get_pass("PathTracer").set_properties({"kernel": "wavefront"})
    with rv.Renderer(scene, g, size=SIZE, views=1) as r:
        r.render()
        pt = r.compiled.passes["PathTracer"]
        assert pt.defines()["PTW_HAS_MEDIUM"] == 1 and pt.wave_slot_bytes(scene) == 11 * 16
        scene.materials["TallBox"].transmission = 0.0
        scene.materials["TallBox"].alpha_mode = "OPAQUE"
        r.recompile()
        r.render()
        pt = r.compiled.passes["PathTracer"]
        assert "SCENE_HAS_TRANSMISSION" in r.gpu_scene.features                  # the upload's
        assert pt.defines()["PTW_HAS_MEDIUM"] == 0 and pt.wave_slot_bytes(scene) == 10 * 16
        assert np.isfinite(np.asarray(r.read_output("Accumulate.dst"))).all()
