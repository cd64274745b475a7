"""What a compiled graph allocates, it frees: passes' own GPU objects (RenderPass.own/release),
resources and timers, on recompile and on close."""
import numpy as np
import pytest

import rayvr as rv
from rayvr.gpu.objects import live_gl_objects
from rayvr.scene import GpuScene, builtin
from rayvr.xr.cameras import default_views


def hybrid_everything():
    """A graph whose passes all make objects of their own in compile(): TAA (a sampler), auto
    exposure (two buffers), the raster G-buffer (a framebuffer and a depth array), Blit (a sampler)."""
    g = rv.graphs.hybrid_taa(preset="raw", auto_exposure=True, gbuffer="raster")
    g.add_pass(rv.passes.Blit({"format": "rgba16f"}), "Copy")
    g.add_edge("TAA.dst", "Copy.src")
    g.mark_output("Copy.dst")
    return g


def test_two_hundred_recompiles_keep_the_gl_object_count_flat(gpu):
    scene = builtin.cornell_box()
    for m in scene.materials:
        m.effect = rv.Effect.REFLECTIONS
    gpu_scene = GpuScene(gpu, scene)
    views = default_views(scene, 2, (16, 16))
    graph = hybrid_everything()
    counts = []
    try:
        for i in range(200):
            compiled = graph.compile(scene=scene, size=(16, 16), views=2, gpu=gpu, gpu_scene=gpu_scene)
            if i % 50 == 0:   # a frame, so that per-frame state (the G-buffer's framebuffer) exists
                gpu_scene.update(views.origin())
                buf = gpu.gl.buffer(views.pack(views.origin()))
                compiled.execute(compiled.make_context(scene=gpu_scene, views_buffer=buf, view_set=views))
                gpu.gl.finish()
                buf.release()
            compiled.release()
            if i in (0, 1, 199):
                counts.append(live_gl_objects())
    finally:
        gpu_scene.release()
    # programs are cached per source and defines: compiled once, kept; everything else comes back
    assert counts[0] == counts[1] == counts[2], counts


def test_renderer_close_frees_what_it_allocated(gpu):
    scene = builtin.cornell_box()
    before = live_gl_objects()
    with rv.Renderer(scene, hybrid_everything(), views=2, size=(16, 16), gpu=gpu) as r:
        r.render()
        during = live_gl_objects()
    after = live_gl_objects()
    assert during["textures"] > before["textures"] and during["buffers"] > before["buffers"]
    # programs are cached per source and defines; timer queries are pooled for the next graph
    leaked = {k: after[k] - before[k] for k in after if k not in ("programs", "queries") and after[k] != before[k]}
    assert not leaked, leaked


@pytest.mark.parametrize("components, dtype", [(4, "f2"), (2, "f4"), (1, "f4"), (4, "u4"), (4, "f1")])
def test_zero_texture_clears_what_was_there(gl, components, dtype):
    """Graph textures start as zeros on every driver (GL leaves new memory undefined: NVIDIA
    returns old bits, NaN patterns included): zero_texture clears a texture holding 7s."""
    from rayvr.gpu.textures import zero_texture

    np_dtype = {"f2": np.float16, "f4": np.float32, "u4": np.uint32, "f1": np.uint8}[dtype]
    t = gl.texture_array((4, 3, 2), components, dtype=dtype)
    t.write(np.full(4 * 3 * 2 * components, 7, np_dtype).tobytes())
    zero_texture(t)
    assert not np.frombuffer(t.read(), np_dtype).any()
    t.release()
