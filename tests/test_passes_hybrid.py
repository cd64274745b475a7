"""The scene-independent hybrid passes on synthetic inputs: tone mapping, effect compaction, composite."""
import numpy as np
import pytest

from rayvr.errors import OptionError
from rayvr.materials.effect import Effect
from rayvr.passes.compaction import EffectCompaction, pixel_list_bytes, read_pixel_list
from rayvr.passes.composite import HybridComposite
from rayvr.passes.tonemap import ToneMapper
from rayvr.rendergraph.render_pass import CompileData, RenderContext, RenderData

NO_GEOMETRY = 0xFF
PIXEL_LISTS = ("shadowPixels", "reflectionPixels", "pathPixels")


def srgb(x):
    x = np.clip(x, 0, 1)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * x ** (1 / 2.4) - 0.055)


def run_pass(gpu, p, inputs, outputs, size, views, scene=None):
    gl = gpu.gl
    # input_formats names the bound inputs, as the compiler fills it (formats are not checked here)
    cd = CompileData(size=size, views=views, scene=scene, caps=gpu.caps, input_formats=dict.fromkeys(inputs))
    ctx = RenderContext(gl, gpu.caps)
    p.compile(ctx, cd)
    p.execute(ctx, RenderData({**inputs, **outputs}, size, views))
    gl.finish()


def hdr_texture(gl, pixels):
    v, h, w, _ = pixels.shape
    return gl.texture_array((w, h, v), 4, pixels.astype("f4").tobytes(), dtype="f4")


def test_tonemap_operators_match_their_formulas(gpu):
    gl = gpu.gl
    values = np.array([0.0, 0.05, 0.18, 1.0, 4.0, 50.0], dtype="f4")
    px = np.zeros((2, 1, len(values), 4), "f4")
    px[..., 0] = values
    px[..., 1] = values * 0.5
    px[..., 2] = values * 2.0
    src = hdr_texture(gl, px)
    expected = {
        "linear": lambda x: srgb(x),
        "reinhard": lambda x: srgb(x / (1 + x)),
        "aces": lambda x: srgb(np.clip((0.6 * x * (2.51 * 0.6 * x + 0.03)) / (0.6 * x * (2.43 * 0.6 * x + 0.59) + 0.14), 0, 1)),
    }
    for op, f in expected.items():
        for stops in (0.0, 1.0):
            dst = gl.texture_array((len(values), 1, 2), 4, dtype="f1")
            run_pass(gpu, ToneMapper(operator=op, exposure=stops), {"src": src}, {"dst": dst}, (len(values), 1), 2)
            got = np.frombuffer(dst.read(), np.uint8).reshape(2, 1, len(values), 4)
            want = np.round(f(px[..., :3] * 2.0 ** stops) * 255)
            assert np.abs(got[..., :3].astype(int) - want).max() <= 1, (op, stops)
            assert (got[..., 3] == 255).all()


def test_tonemap_auto_exposure_maps_mean_log_luminance_to_key(gpu):
    gl = gpu.gl
    px = np.full((2, 8, 8, 4), 2.0, "f4")   # luminance 2 everywhere: scale = 0.18 / 2
    src = hdr_texture(gl, px)
    dst = gl.texture_array((8, 8, 2), 4, dtype="f1")
    tm = ToneMapper(operator="linear", auto_exposure=True, srgb=False)
    run_pass(gpu, tm, {"src": src}, {"dst": dst}, (8, 8), 2)
    assert tm.exposure_scale() == pytest.approx(0.09, rel=1e-3)
    got = np.frombuffer(dst.read(), np.uint8).reshape(2, 8, 8, 4)
    assert np.abs(got[..., :3].astype(int) - round(0.18 * 255)).max() <= 1


def test_tonemappers_sharing_a_program_keep_their_own_exposure(gpu):
    # Programs are cached per source and defines: a second ToneMapper compiled later must not
    # change the first one's uniforms.
    gl = gpu.gl
    src = hdr_texture(gl, np.full((1, 1, 1, 4), 0.25, "f4"))
    first, second = ToneMapper(operator="linear", srgb=False), ToneMapper(operator="linear", srgb=False, exposure=1.0)
    cd = CompileData(size=(1, 1), views=1, scene=None, caps=gpu.caps, input_formats={"src": "rgba32f"})
    ctx = RenderContext(gl, gpu.caps)
    first.compile(ctx, cd)
    second.compile(ctx, cd)
    dst = gl.texture_array((1, 1, 1), 4, dtype="f1")
    first.execute(ctx, RenderData({"src": src, "dst": dst}, (1, 1), 1))
    gl.finish()
    assert np.frombuffer(dst.read(), np.uint8)[0] == round(0.25 * 255)


def test_tonemap_rejects_unknown_operator():
    with pytest.raises(OptionError, match="operator.*aces"):
        ToneMapper(operator="filmic")


def effect_texture(gl, ids):
    v, h, w = ids.shape
    return gl.texture_array((w, h, v), 1, ids.astype("u4").tobytes(), dtype="u4")


@pytest.mark.parametrize("path_list", [False, True])
def test_compaction_lists_exactly_the_pixels_each_effect_needs(gpu, path_list):
    gl = gpu.gl
    rng = np.random.default_rng(1)
    size, views = (37, 29), 2
    effects = rng.choice([0, 1, 2, 3, NO_GEOMETRY], size=(views, size[1], size[0]))
    materials = rng.integers(0, 1000, size=effects.shape)
    tex = effect_texture(gl, (materials << 8) | effects)
    lists = [gl.buffer(reserve=pixel_list_bytes(size, views)) for _ in range(3)]
    p = EffectCompaction(path_list=path_list)
    for _ in range(2):   # the second frame must start from empty lists
        run_pass(gpu, p, {"effect": tex}, dict(zip(PIXEL_LISTS, lists)), size, views)
    geo = effects != NO_GEOMETRY
    path = (effects == Effect.PATH_TRACED) & path_list
    wanted = [(effects >= Effect.SHADOWS) & geo & ~path, (effects >= Effect.REFLECTIONS) & geo & ~path, path]
    for buf, want in zip(lists, wanted):
        n, xyz = read_pixel_list(buf)
        v, y, x = np.nonzero(want)
        assert n == len(v)
        got = sorted(map(tuple, xyz.tolist()))
        assert got == sorted(zip(x.tolist(), y.tolist(), v.tolist()))
        args = np.frombuffer(buf.read(16), np.uint32)
        assert list(args[1:]) == [(n + 63) // 64, 1, 1]


def test_compaction_of_raster_only_pixels_dispatches_nothing(gpu):
    gl = gpu.gl
    size, views = (16, 16), 2
    tex = effect_texture(gl, np.zeros((views, 16, 16), np.uint32))
    lists = [gl.buffer(reserve=pixel_list_bytes(size, views)) for _ in range(3)]
    run_pass(gpu, EffectCompaction(path_list=True), {"effect": tex}, dict(zip(PIXEL_LISTS, lists)), size, views)
    for buf in lists:
        assert list(np.frombuffer(buf.read(16), np.uint32)) == [0, 0, 1, 1]


def test_composite_picks_lighting_by_effect(gpu):
    gl = gpu.gl
    size, views = (4, 1), 2
    ids = np.array([[[0, 1, 2, NO_GEOMETRY]]] * views, np.uint32)
    tex = effect_texture(gl, ids)
    def const(c):
        return hdr_texture(gl, np.broadcast_to(np.array(c, "f4"), (views, 1, 4, 4)).copy())
    direct, shadowed, refl = const([1, 0, 0, 1]), const([0, 1, 0, 1]), const([0, 0, 1, 1])
    out = gl.texture_array((4, 1, views), 4, dtype="f2")
    run_pass(gpu, HybridComposite(), {"effect": tex, "direct": direct, "shadowed": shadowed, "reflection": refl},
             {"color": out}, size, views)
    got = np.frombuffer(out.read(), np.float16).reshape(views, 1, 4, 4)[..., :3]
    np.testing.assert_array_equal(got[:, 0], [[[1, 0, 0], [0, 1, 0], [0, 1, 1], [1, 0, 0]]] * views)
    # without the optional inputs every pixel keeps the direct light
    run_pass(gpu, HybridComposite(), {"effect": tex, "direct": direct}, {"color": out}, size, views)
    got = np.frombuffer(out.read(), np.float16).reshape(views, 1, 4, 4)[..., :3]
    assert (got == [1, 0, 0]).all()
