"""Accumulate: the running mean equals numpy's mean of the frames, resets (explicit, views, scene,
sample index), max_frames, and a progressive path-traced render that converges."""
import numpy as np
import pytest

from rayvr.errors import OptionError
from rayvr.passes.accumulate import Accumulate
from rayvr.rendergraph.render_pass import CompileData, RenderContext, RenderData

W, H = 8, 4


class Frames:
    """Runs an Accumulate pass by hand on textures filled from numpy (layers, h, w, 4) arrays."""

    def __init__(self, gpu, acc, views=1):
        self.gl, self.acc, self.views = gpu.gl, acc, views
        self.ctx = RenderContext(gpu.gl, gpu.caps)
        acc.compile(self.ctx, CompileData(size=(W, H), views=views, input_formats={"src": "rgba32f"}))
        self.tex = {k: gpu.gl.texture_array((W, H, views), 4, dtype="f4")
                    for k in ("src", "dst", "sum", "compensation")}

    def __call__(self, frame, **ctx):
        self.tex["src"].write(np.ascontiguousarray(frame, np.float32).tobytes())
        for k, v in ctx.items():
            setattr(self.ctx, k, v)
        self.acc.execute(self.ctx, RenderData(self.tex, (W, H), self.views))
        return np.frombuffer(self.tex["dst"].read(), np.float32).reshape(self.views, H, W, 4)


def frames(n, views=1, seed=0, offset=1000.0):
    """Noisy frames around a large offset: a naive float32 running sum would drift."""
    rng = np.random.default_rng(seed)
    return (offset + rng.normal(0.0, 1.0, (n, views, H, W, 4))).astype(np.float32)


def test_mean_equals_numpy_mean_of_the_frames(gpu):
    run = Frames(gpu, Accumulate(), views=2)
    xs = frames(64, views=2)
    for k, x in enumerate(xs, 1):
        out = run(x)
        if k in (1, 2, 7, 64):
            np.testing.assert_allclose(out, xs[:k].astype(np.float64).mean(0), rtol=2e-7, atol=0)
    assert run.acc.frame_count == 64


def test_reset_starts_the_mean_again(gpu):
    run = Frames(gpu, Accumulate())
    xs = frames(5, seed=1)
    for x in xs[:3]:
        run(x)
    run.acc.reset()
    np.testing.assert_array_equal(run(xs[3]), xs[3])
    np.testing.assert_allclose(run(xs[4]), xs[3:5].astype(np.float64).mean(0), rtol=2e-7)


def test_sample_index_zero_restarts(gpu):
    run = Frames(gpu, Accumulate())
    xs = frames(5, seed=2)
    run(xs[0], sample_index=0)
    run(xs[1], sample_index=1)
    np.testing.assert_array_equal(run(xs[2], sample_index=0), xs[2])   # the renderer's restart signal
    np.testing.assert_array_equal(run(xs[3], sample_index=0), xs[3])   # twice in a row: again
    np.testing.assert_allclose(run(xs[4], sample_index=1), xs[3:5].astype(np.float64).mean(0), rtol=2e-7)


def test_view_change_resets(gpu):
    from rayvr.scene import builtin
    from rayvr.scene.model import Camera
    from rayvr.xr.cameras import default_views

    scene = builtin.quad()
    a = default_views(scene, 1, (W, H))
    scene.cameras[:] = [Camera.look_at((0.1, 0, 2), (0, 0, 0))]
    b = default_views(scene, 1, (W, H))
    run = Frames(gpu, Accumulate())
    xs = frames(4, seed=3)
    run(xs[0], view_set=a)
    run(xs[1], view_set=a)
    assert run.acc.frame_count == 2
    np.testing.assert_array_equal(run(xs[2], view_set=b), xs[2])
    assert run.acc.frame_count == 1


def test_max_frames_freezes_the_mean(gpu):
    run = Frames(gpu, Accumulate(max_frames=3))
    xs = frames(6, seed=4)
    for x in xs:
        out = run(x)
    np.testing.assert_allclose(out, xs[:3].astype(np.float64).mean(0), rtol=2e-7)
    assert run.acc.frame_count == 3


def test_disabled_passes_the_frame_through(gpu):
    run = Frames(gpu, Accumulate(enabled=False))
    xs = frames(2, seed=5)
    run(xs[0])
    np.testing.assert_array_equal(run(xs[1]), xs[1])


@pytest.mark.parametrize("sampler", ["pcg", "sobol"])
def test_progressive_path_tracing_converges_like_one_over_sqrt_n(gpu, sampler):
    """Against the 64-frame mean, the k-frame mean's RMS error is sigma * sqrt(1/k - 1/64) for
    independent samples (PCG): 4 frames are sqrt((1/4 - 1/64) / (1/16 - 1/64)) = 2.24 times worse
    than 16. Owen-scrambled Sobol converges faster than that (quasi-Monte Carlo): at least as fast."""
    from rayvr.graphs import path_traced
    from rayvr.renderer import Renderer
    from rayvr.scene import builtin

    means = {}
    graph = path_traced(max_bounces=2)
    graph.update_pass("PathTracer", {"sampler": sampler})
    with Renderer(builtin.cornell_box(), graph, size=(16, 16)) as r:
        for k in range(1, 65):
            r.render()
            if k in (4, 16, 64):
                means[k] = r.read_output("Accumulate.dst")[..., :3].astype(np.float64)
        assert r.compiled.passes["Accumulate"].frame_count == 64
    assert np.isfinite(means[64]).all() and means[64].mean() > 0
    rms = {k: np.sqrt(((means[k] - means[64]) ** 2).mean()) for k in (4, 16)}
    if sampler == "pcg":
        assert 1.6 < rms[4] / rms[16] < 3.2
    else:
        assert rms[4] / rms[16] > 2.24


def test_bad_max_frames_names_the_property():
    with pytest.raises(OptionError, match="'max_frames'"):
        Accumulate(max_frames=-1)
