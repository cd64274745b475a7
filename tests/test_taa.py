"""TAA: a static input converges to itself, motion vectors carry the history along, colour-box
clamping stops ghosting, per-view history, a still view's exact running mean, Halton jitter,
option errors. Radiance is compared in rgb: the history's alpha holds the frames of its mean."""
import numpy as np
import pytest

from rayvr.errors import OptionError
from rayvr.passes.taa import TAA, halton, halton_jitter
from rayvr.xr.jitter import JITTER_SEQUENCE_LENGTH
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

    def __call__(self, color, motion=None, sample_index=None):
        self.ctx.sample_index = sample_index   # > 0: a still frame (rayvr.passes.history)
        self.tex["color"].write(np.ascontiguousarray(color, np.float32).tobytes())
        if motion is not None:
            self.tex["motion"].write(np.ascontiguousarray(motion, np.float16).tobytes())
        self.taa.execute(self.ctx, RenderData(self.tex, (W, H), self.views))
        dtype = np.float32 if self.taa.format == "rgba32f" else np.float16
        return np.frombuffer(self.tex["dst"].read(), dtype).reshape(self.views, H, W, 4).astype(np.float64)[..., :3]


def image(views=1, seed=0):
    rng = np.random.default_rng(seed)
    return rng.uniform(0.0, 4.0, (views, H, W, 4)).astype(np.float32)


def rgb(img):
    return np.asarray(img, np.float64)[..., :3]


def test_static_input_without_jitter_stays_the_input(gpu):
    run = Frames(gpu, TAA(format="rgba32f"))
    img = image()
    for _ in range(4):
        out = run(img)
    np.testing.assert_allclose(out, rgb(img), rtol=1e-6, atol=1e-6)   # YCoCg round trip


def test_history_blends_with_alpha_when_not_clamped(gpu):
    run = Frames(gpu, TAA(alpha=0.25, clamp=False, format="rgba32f"))
    a, b = image(seed=1), image(seed=2)
    np.testing.assert_allclose(run(a), rgb(a), rtol=1e-6)   # first frame: no history yet
    np.testing.assert_allclose(run(b), rgb(0.75 * a + 0.25 * b), rtol=1e-5)
    run.taa.reset()
    np.testing.assert_allclose(run(b), rgb(b), rtol=1e-6)


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
    np.testing.assert_allclose(out[0, 5, 8], (8.0, 4.0, 2.0), rtol=1e-6)  # history agrees
    assert np.abs(out[0, 3, 5]).max() == 0.0                                    # no ghost left behind
    # without motion vectors the same frames ghost: half of the old pixel stays
    still = Frames(gpu, TAA(alpha=0.5, clamp=False, format="rgba32f"))
    still(first)
    ghost = still(second)
    np.testing.assert_allclose(ghost[0, 3, 5], (4.0, 2.0, 1.0), rtol=1e-6)
    np.testing.assert_allclose(ghost[0, 5, 8], (4.0, 2.0, 1.0), rtol=1e-6)


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
    np.testing.assert_allclose(out, rgb(0.5 * (a.astype(np.float64) + b)), rtol=2e-3)   # rgba16f output


def test_halton_jitter_is_the_2_3_sequence_centred():
    assert [halton(i, 2) for i in range(1, 5)] == [0.5, 0.25, 0.75, 0.125]
    assert halton(1, 3) == pytest.approx(1 / 3) and halton(2, 3) == pytest.approx(2 / 3)
    assert halton_jitter(0) == (0.0, pytest.approx(1 / 3 - 0.5))
    js = np.array([halton_jitter(i) for i in range(16)])
    assert (np.abs(js) < 0.5).all() and abs(js.mean(0)).max() < 0.05
    assert halton_jitter(JITTER_SEQUENCE_LENGTH) == halton_jitter(0)
    # the long cycle stratifies the pixel: every cell of a 16x16 grid holds 4 of its 1024 points
    js = np.array([halton_jitter(i) for i in range(JITTER_SEQUENCE_LENGTH)]) + 0.5
    cells = np.histogram2d(js[:, 0], js[:, 1], bins=16, range=[[0, 1], [0, 1]])[0]
    assert JITTER_SEQUENCE_LENGTH == 1024 and cells.min() >= 2 and cells.max() <= 6


def test_a_still_view_keeps_the_exact_running_mean(gpu):
    run = Frames(gpu, TAA(alpha=0.1, format="rgba32f"), motion=True)
    still = np.zeros((1, H, W, 2), np.float32)
    frames = [image(seed=10 + i) for i in range(12)]
    run(frames[0], still, sample_index=0)
    for i, f in enumerate(frames[1:], start=1):
        out = run(f, still, sample_index=i)
    # unclamped, weight 1/n: the mean of all twelve frames (the clamp would have pulled noise in)
    np.testing.assert_allclose(out, rgb(np.mean(frames, axis=0)), rtol=1e-5)
    assert run.taa.still_frames == 12
    # the view moves: TAA's own blend, from the still mean
    moved = run(frames[0], still, sample_index=0)
    assert run.taa.still_frames == 1
    assert not np.allclose(moved, rgb(np.mean(frames + frames[:1], axis=0)), rtol=1e-3)


def test_a_still_frame_continues_the_moving_history_then_converges(gpu):
    run = Frames(gpu, TAA(alpha=0.5, clamp=False, format="rgba32f"), motion=True)
    zero = np.zeros((1, H, W, 2), np.float32)
    a, b = image(seed=20), image(seed=21)
    run(a, zero)            # moving: the history stands for 1 frame
    run(a, zero)            # then 2 (alpha 0.5's window)
    out = run(b, zero, sample_index=1)   # still: weight 1/3 for the new frame
    np.testing.assert_allclose(out, rgb((2 * a + b) / 3.0), rtol=1e-5)
    # a pixel that moved on a still frame takes the moving blend
    motion = zero.copy()
    motion[0, 2, 3] = (1.0, 0.0)
    out = run(a, motion, sample_index=2)
    np.testing.assert_allclose(out[0, 5, 5], rgb(((2 * a + b) / 3.0 * 3 + a) / 4.0)[0, 5, 5], rtol=1e-5)
    assert not np.allclose(out[0, 2, 3], rgb(((2 * a + b) / 3.0 * 3 + a) / 4.0)[0, 2, 3], rtol=1e-3)


def test_bad_properties_name_the_pass_and_property():
    with pytest.raises(OptionError, match="'alpha'"):
        TAA(alpha=0.0)
    with pytest.raises(OptionError, match="'format'.*rgba16f"):
        TAA(format="rgba8")
