"""rv.Renderer: frames driven by a sink, run-time effect changes (recompile only when the set of
used effects changes), outputs, profile and report; rv.graphs.hybrid(preset="raw") round-trips through JSON."""
import numpy as np
import pytest

import rayvr as rv
from rayvr.errors import OptionError
from rayvr.renderer import Renderer
from rayvr.scene import builtin
from rayvr.xr.cameras import default_views


def test_frames_drive_the_headset_and_effects_switch_at_run_time(gpu):
    scene = builtin.cornell_box()
    for m in scene.materials:
        m.effect = rv.Effect.RASTER
    headset = rv.xr.SimulatedHeadset(preset="index", size=(24, 20), frames=4)
    orders = []
    with Renderer(scene, rv.graphs.hybrid(preset="raw"), sink=headset) as r:
        assert "Shadows" in r.compiled.plan.pruned
        for frame in r.frames():
            if frame.index == 1:
                frame.materials["Floor"].effect = rv.Effect.REFLECTIONS
            if frame.index == 2:
                frame.materials["Floor"].base_color = (0.1, 0.9, 0.1, 1.0)   # same effects: no recompile
            orders.append((frame.index, r.compiles))
            assert frame.views is not None and len(frame.views) == 2
        final_order = list(r.compiled.plan.order)
        final_pruned = dict(r.compiled.plan.pruned)
        out = r.read_output()
        prof = r.profile()
    assert [i for i, _ in orders] == [0, 1, 2, 3]
    assert r.compiles == 2                      # the RASTER -> REFLECTIONS switch only
    assert {"Shadows", "Reflections"} <= set(final_order)
    # both ray passes run over the whole image (nothing is PATH_TRACED): nobody reads the lists
    assert "inputs their passes leave unused: Shadows.pixels" in final_pruned["Compaction"]
    assert headset.stats()["frames"] == 4
    assert out.shape == (2, 20, 24, 4) and out.dtype == np.uint8
    assert set(prof.passes) >= {"GBuffer", "Reflections", "ToneMap"}


def test_material_colour_change_reaches_the_pixels_without_recompiling(gpu):
    scene = builtin.plane_with_point_light()
    with Renderer(scene, rv.graphs.hybrid(preset="raw", tonemap="linear"), views=1, size=(16, 16)) as r:
        r.render()
        before = r.read_output("Composite.color").astype(np.float64)
        scene.materials["Plane"].base_color = (0.4, 0.4, 0.4, 1.0)
        r.render()
        after = r.read_output("Composite.color").astype(np.float64)
        assert r.compiles == 1
    diffuse_ratio = after[..., 0].mean() / before[..., 0].mean()
    assert 0.45 < diffuse_ratio < 0.55      # half the albedo: about half the radiance (plus a fixed specular)


def test_report_names_pruned_passes_and_the_scene(gpu):
    scene = builtin.cornell_box()
    with Renderer(scene, rv.graphs.hybrid(preset="raw"), views=2, size=(16, 16)) as r:
        text = str(r.report())
    assert "Reflections: no material uses REFLECTIONS" in text
    assert "cornell_box" in text


def test_render_rejects_views_of_another_size(gpu):
    scene = builtin.quad()
    with Renderer(scene, rv.graphs.hybrid(preset="raw"), views=1, size=(16, 16)) as r:
        other = default_views(scene, 1, (8, 8))
        with pytest.raises(OptionError, match="compiled for 1 of \\(16, 16\\)"):
            r.render(other)


def test_hybrid_graph_round_trips_through_json(tmp_path):
    g = rv.graphs.hybrid(preset="raw", max_bounces=2, tonemap="reinhard")
    path = g.save(tmp_path / "hybrid.json")
    h = rv.RenderGraph.load(path)
    assert list(h.passes) == list(g.passes)
    assert h.get_pass("Reflections").get_properties()["max_bounces"] == 2
    assert h.get_pass("ToneMap").get_properties()["operator"] == "reinhard"
    assert [str(e) for e in h.edges] == [str(e) for e in g.edges]


def test_graph_options_are_checked():
    with pytest.raises(OptionError, match="operator"):
        rv.graphs.hybrid(preset="raw", tonemap="sepia")
    with pytest.raises(OptionError, match="multiview"):
        rv.passes.GBufferRaster(multiview="sometimes")


def test_swapping_effects_between_materials_moves_ray_work_without_recompiling(gpu):
    from rayvr.passes.compaction import read_pixel_list

    scene = builtin.cornell_box()
    scene.materials["Floor"].effect = rv.Effect.REFLECTIONS
    g = rv.graphs.hybrid(preset="raw")
    g.mark_output("Compaction.reflectionPixels")
    g.mark_output("GBuffer.effect")
    names = [m.name for m in scene.materials]
    with Renderer(scene, g, views=2, size=(24, 24)) as r:
        lists = []
        for reflective in ("Floor", "BackWall"):
            for m in ("Floor", "BackWall"):
                scene.materials[m].effect = rv.Effect.REFLECTIONS if m == reflective else rv.Effect.SHADOWS
            r.render()
            n, xyz = read_pixel_list(r.compiled.get_output("Compaction.reflectionPixels"))
            ids = r.read_output("GBuffer.effect")[..., 0]
            listed = ids[xyz[:, 2], xyz[:, 1], xyz[:, 0]] >> 8
            assert n > 0 and set(listed.tolist()) == {names.index(reflective)}
            lists.append(n)
        assert r.compiles == 1


def test_sample_index_restarts_when_the_head_only_translates(gpu):
    import dataclasses

    from rayvr.xr.views import Pose, ViewSet

    scene = builtin.cornell_box()
    views = default_views(scene, 2, (8, 8))
    with Renderer(scene, rv.graphs.hybrid(preset="raw"), views=views) as r:
        r.render(views)
        r.render(views)
        assert r.sample_index == 1
        # both eyes move together: the render-space matrices are unchanged, the world is not
        moved = ViewSet([dataclasses.replace(v, pose=Pose(v.pose.position + [0.2, 0.0, 0.0], v.pose.orientation))
                         for v in views.views])
        r.render(moved)
        assert r.sample_index == 0
        r.render(moved)
        assert r.sample_index == 1


def test_sample_index_restarts_when_an_instance_moves_a_light_changes_or_a_material(gpu):
    scene = builtin.cornell_box()
    scene.lights.append(rv.scene.Light("point", position=(0.0, 1.0, 0.5), intensity=0.5))
    with Renderer(scene, rv.graphs.hybrid(preset="raw"), views=1, size=(8, 8)) as r:
        counts = []
        for edit in (None, None, "instance", None, "light", "light again", None, "material", None):
            if edit == "instance":
                moved = scene.instances[0].transform.copy()
                moved[0, 3] += 0.01
                scene.instances[0].transform = moved
            elif edit in ("light", "light again"):
                scene.lights[-1].intensity += 0.25
            elif edit == "material":
                scene.materials["Floor"].base_color = (0.2, 0.3, 0.4, 1.0)
            r.render()
            counts.append(r.sample_index)
    # two edits on consecutive frames restart twice: each frame with an edit is sample 0
    assert counts == [0, 1, 0, 1, 0, 0, 1, 0, 1]


def test_renderers_share_one_loaded_scene_and_render_what_their_own_would(gpu):
    from rayvr.scene.gpu_scene import GpuScene

    scene = rv.scenes.cornell_box()
    loaded = GpuScene(gpu, scene)

    def image(**kw):
        with rv.Renderer(scene, rv.graphs.hybrid(preset="raw"), size=(16, 16), gpu=gpu, **kw) as r:
            r.render()
            return r.read_output("Composite.color")
    own = image()
    shared = [image(gpu_scene=loaded) for _ in range(2)]     # close() leaves the shared scene loaded
    assert all(np.array_equal(own, s) for s in shared)
    with pytest.raises(rv.OptionError, match="gpu_scene was loaded from another scene"):
        rv.Renderer(rv.scenes.cornell_box(), rv.graphs.hybrid(preset="raw"), size=(16, 16), gpu=gpu, gpu_scene=loaded)
    loaded.release()
