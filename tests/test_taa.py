"""TAA: a static input converges to itself, motion vectors carry the history along, colour-box
clamping stops ghosting, per-view history, Halton jitter, option errors."""
import numpy as np
import pytest

from rayvr.errors import OptionError
from rayvr.passes.taa import TAA, halton, halton_jitter
from rayvr.rendergraph.render_pass import CompileData, RenderContext, RenderData

W, H = 16, 8


class Frames:
    """Runs a TAA pass by hand on textures filled from numpy (layers, h, w, 4) arrays."""

    def __init__(self, gpu, taa, views=1, motion=False):
        self.gl, self.taa, self.views = gpu.gl, taa, views
        cd = CompileData(size=(W, H), views=views, input_formats={"color": "rgba32f", **({"motion": "rg16f"} if motion else {})})
        self.ctx = RenderContext(gpu.gl, gpu.caps)
        taa.compile(self.ctx, cd)
        arr = lambda comps, dtype: self.gl.texture_array((W, H, views), comps, dtype=dtype)
        self.tex = {"color": arr(4, "f4"), "dst": arr(4, "f4" if taa.format == "rgba32f" else "f2"),
                    "history0": arr(4, "f4"), "history1": arr(4, "f4")}
        if motion:
            self.tex["motion"] = arr(2, "f2")

    def __call__(self, color, motion=None):
        self.tex["color"].write(np.ascontiguousarray(color, np.float32).tobytes())
        if motion is not None:
            self.tex["motion"].write(np.ascontiguousarray(motion, np.float16).tobytes())
        self.taa.execute(self.ctx, RenderData(self.tex, (W, H), self.views))
        dtype = np.float32 if self.taa.format == "rgba32f" else np.float16
        return np.frombuffer(self.tex["dst"].read(), dtype).reshape(self.views, H, W, 4).astype(np.float64)


def image(views=1, seed=0):
    rng = np.random.default_rng(seed)
    return rng.uniform(0.0, 4.0, (views, H, W, 4)).astype(np.float32)


def test_static_input_without_jitter_stays_the_input(gpu):
    run = Frames(gpu, TAA(format="rgba32f"))
    img = image()
    for _ in range(4):
        out = run(img)
    np.testing.assert_allclose(out, img, rtol=1e-6, atol=1e-6)   # YCoCg round trip


def test_history_blends_with_alpha_when_not_clamped(gpu):
    run = Frames(gpu, TAA(alpha=0.25, clamp=False, format="rgba32f"))
    a, b = image(seed=1), image(seed=2)
    np.testing.assert_allclose(run(a), a, rtol=1e-6)   # first frame: no history yet
    np.testing.assert_allclose(run(b), 0.75 * a + 0.25 * b, rtol=1e-5)
    run.taa.reset()
    np.testing.assert_allclose(run(b), b, rtol=1e-6)


def test_motion_vectors_reproject_the_history(gpu):
    run = Frames(gpu, TAA(alpha=0.5, clamp=False, format="rgba32f"), motion=True)
    first = np.zeros((1, H, W, 4), np.float32)
    first[0, 3, 5] = (8.0, 4.0, 2.0, 1.0)
    run(first, np.zeros((1, H, W, 2)))
    # the bright pixel moved 3 px right and 2 px up: motion = now - before = (3, 2)
    second = np.zeros_like(first)
    second[0, 5, 8] = (8.0, 4.0, 2.0, 1.0)
    motion = np.broadcast_to(np.array([3.0, 2.0]), (1, H, W, 2))
    out = run(second, motion)
    np.testing.assert_allclose(out[0, 5, 8], (8.0, 4.0, 2.0, 1.0), rtol=1e-6)  # history agrees
    assert np.abs(out[0, 3, 5]).max() == 0.0                                    # no ghost left behind
    # without motion vectors the same frames ghost: half of the old pixel stays
    still = Frames(gpu, TAA(alpha=0.5, clamp=False, format="rgba32f"))
    still(first)
    ghost = still(second)
    np.testing.assert_allclose(ghost[0, 3, 5], (4.0, 2.0, 1.0, 0.5), rtol=1e-6)
    np.testing.assert_allclose(ghost[0, 5, 8], (4.0, 2.0, 1.0, 0.5), rtol=1e-6)


def test_subpixel_motion_reads_history_bilinearly(gpu):
    run = Frames(gpu, TAA(alpha=0.5, clamp=False, format="rgba32f"), motion=True)
    ramp = np.zeros((1, H, W, 4), np.float32)
    ramp[..., :] = np.arange(W, dtype=np.float32)[None, None, :, None]
    run(ramp, np.zeros((1, H, W, 2)))
    out = run(ramp, np.broadcast_to(np.array([0.5, 0.0]), (1, H, W, 2)))
    # history at x - 0.5 is the ramp's x - 0.5: out = (x - 0.5 + x) / 2
    np.testing.assert_allclose(out[0, 4, 2:-2, 0], np.arange(2, W - 2) - 0.25, rtol=1e-4)


def test_colour_box_clamping_stops_ghosting(gpu):
    run = Frames(gpu, TAA(alpha=0.1, format="rgba32f"))
    grey = np.full((1, H, W, 4), 1.0, np.float32)
    run(grey)
    white = np.full((1, H, W, 4), 3.0, np.float32)
    out = run(white)   # flat neighbourhood: the box is the new colour; the old grey is clamped away
    # (ghosting would leave 2.8; NVIDIA's YCoCg round trip lands 8e-5 off exact)
    np.testing.assert_allclose(out[..., :3], 3.0, rtol=2e-4)
    unclamped = Frames(gpu, TAA(alpha=0.1, clamp=False, format="rgba32f"))
    unclamped(grey)
    np.testing.assert_allclose(unclamped(white)[..., :3], 0.9 * 1.0 + 0.1 * 3.0, rtol=1e-5)


def test_views_keep_their_own_history(gpu):
    run = Frames(gpu, TAA(alpha=0.5, clamp=False), views=2)
    a = image(views=2, seed=3)
    b = image(views=2, seed=4)
    run(a)
    out = run(b)
    np.testing.assert_allclose(out, 0.5 * (a.astype(np.float64) + b), rtol=2e-3)   # rgba16f output


def test_halton_jitter_is_the_2_3_sequence_centred():
    assert [halton(i, 2) for i in range(1, 5)] == [0.5, 0.25, 0.75, 0.125]
    assert halton(1, 3) == pytest.approx(1 / 3) and halton(2, 3) == pytest.approx(2 / 3)
    assert halton_jitter(0) == (0.0, pytest.approx(1 / 3 - 0.5))
    js = np.array([halton_jitter(i) for i in range(16)])
    assert (np.abs(js) < 0.5).all() and abs(js.mean(0)).max() < 0.05
    assert halton_jitter(16) == halton_jitter(0)


def test_bad_properties_name_the_pass_and_property():
    with pytest.raises(OptionError, match="'alpha'"):
        TAA(alpha=0.0)
    with pytest.raises(OptionError, match="'format'.*rgba16f"):
        TAA(format="rgba8")
