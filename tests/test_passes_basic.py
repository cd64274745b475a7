"""Clear, Checkerboard, Blit and ImageLoader render exact pixels on the shared GL context."""
import numpy as np
import pytest
from PIL import Image

from rayvr.errors import OptionError
from rayvr.passes.basic import Blit, Checkerboard, Clear, ImageLoader
from rayvr.rendergraph import RenderGraph


def render(gpu, graph, size=(8, 4), views=2):
    cg = graph.compile(size=size, views=views, gpu=gpu)
    cg.execute(cg.make_context())
    return cg


def single(render_pass, name="P", out="dst"):
    g = RenderGraph("T")
    g.add_pass(render_pass, name)
    g.mark_output(f"{name}.{out}")
    return g


def checker_oracle(w, h, layers, cell, a, b):
    y, x = np.mgrid[0:h, 0:w]
    out = []
    for z in range(layers):
        parity = (x // cell + y // cell + z) & 1
        out.append(np.where(parity[..., None] == 0, a, b))
    return np.stack(out)


def test_clear_fills_each_view_with_its_colour_exactly(gpu):
    colors = [[1, 0, 0, 1], [0, 0.5, 0.25, 0.75], [0.125, 0.25, 0.5, 1.0]]
    cg = render(gpu, single(Clear(view_colors=colors, format="rgba16f")), views=3)
    a = cg.read_output("P.dst")
    assert a.shape == (3, 4, 8, 4) and a.dtype == np.float16
    for layer, c in enumerate(colors):
        assert (a[layer] == np.array(c, np.float16)).all()


def test_clear_constant_colour_reaches_every_layer_and_integer_formats(gpu):
    # 128/255, not 0.5: the GL leaves the rounding of a .5 tie to the driver (NVIDIA gives 127)
    a = render(gpu, single(Clear(color=[128 / 255, 0.25, 1.0], format="rgba8")), views=2).read_output("P.dst")
    assert (a == [128, 64, 255, 255]).all()
    u = render(gpu, single(Clear(color=[7, 0, 0, 0], format="r32ui")), views=2).read_output("P.dst")
    assert u.dtype == np.uint32 and (u == 7).all()


def test_checkerboard_matches_numpy_oracle(gpu):
    a = render(gpu, single(Checkerboard(cell=3, color_a=[1, 0, 0, 1], color_b=[0, 0, 1, 1])),
               size=(10, 7), views=2).read_output("P.dst")
    want = checker_oracle(10, 7, 2, 3, [255, 0, 0, 255], [0, 0, 255, 255])
    np.testing.assert_array_equal(a, want)


def test_blit_copies_exactly_and_converts_format(gpu):
    g = RenderGraph("T")
    g.add_pass(Checkerboard(cell=2, color_a=[1, 0.75, 0, 1], color_b=[0, 0, 0.25, 1], format="rgba32f"), "K")
    g.add_pass(Blit(filter="nearest"), "Same")
    g.add_pass(Blit(format="rgba8"), "To8")
    g.add_edge("K.dst", "Same.src")
    g.add_edge("K.dst", "To8.src")
    g.mark_output("Same.dst")
    g.mark_output("To8.dst")
    cg = render(gpu, g, size=(6, 4))
    want = checker_oracle(6, 4, 2, 2, [1, 0.75, 0, 1], [0, 0, 0.25, 1])
    same = cg.read_output("Same.dst")
    assert same.dtype == np.float32
    np.testing.assert_array_equal(same, want)
    np.testing.assert_array_equal(cg.read_output("To8.dst"), np.round(want * 255).astype(np.uint8))


def test_blit_half_scale_averages_2x2_blocks(gpu):
    g = RenderGraph("T")
    g.add_pass(Checkerboard(cell=2, color_a=[1, 1, 1, 1], color_b=[0, 0, 0, 1], format="rgba16f"), "K")
    g.add_pass(Blit(scale=0.5, filter="linear"), "Half")
    g.add_edge("K.dst", "Half.src")
    g.mark_output("Half.dst")
    cg = render(gpu, g, size=(8, 4))
    a = cg.read_output("Half.dst")
    assert a.shape == (2, 2, 4, 4)
    # Every 2x2 block of the source is one cell: its average is that cell's colour.
    np.testing.assert_array_equal(a[..., 0], checker_oracle(4, 2, 2, 1, [1], [0])[..., 0])


def test_image_loader_png_exact_all_views_and_per_view(gpu, tmp_path):
    rng = np.random.default_rng(3)
    imgs = [rng.integers(0, 256, (5, 7, 4), dtype=np.uint8) for _ in range(2)]
    paths = []
    for i, im in enumerate(imgs):
        paths.append(tmp_path / f"v{i}.png")
        Image.fromarray(im, "RGBA").save(paths[-1])
    one = render(gpu, single(ImageLoader(path=str(paths[0]))), size=(16, 16)).read_output("P.dst", flip_y=True)
    assert one.shape == (2, 5, 7, 4)
    np.testing.assert_array_equal(one[0], imgs[0])
    np.testing.assert_array_equal(one[1], imgs[0])
    per_view = render(gpu, single(ImageLoader(paths=[str(p) for p in paths])), size=(16, 16))
    a = per_view.read_output("P.dst", flip_y=True)
    np.testing.assert_array_equal(a[0], imgs[0])
    np.testing.assert_array_equal(a[1], imgs[1])
    # GL order: row 0 of the texture is the bottom row of the file.
    np.testing.assert_array_equal(per_view.read_output("P.dst")[1, 0], imgs[1][-1])


def test_image_loader_exr_float_exact(gpu, tmp_path):
    OpenEXR = pytest.importorskip("OpenEXR")
    rgb = np.random.default_rng(1).random((3, 4, 3)).astype(np.float32) * 10
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    with OpenEXR.File(header, {"RGB": rgb}) as f:
        f.write(str(tmp_path / "hdr.exr"))
    a = render(gpu, single(ImageLoader(path=str(tmp_path / "hdr.exr"))), views=1).read_output("P.dst", flip_y=True)
    assert a.dtype == np.float32
    np.testing.assert_array_equal(a[0, ..., :3], rgb)
    assert (a[0, ..., 3] == 1).all()


def test_basic_pass_errors_name_pass_property_and_fix(gpu, tmp_path):
    with pytest.raises(OptionError, match=r"pass Clear: property 'color' must be \[r, g, b\]"):
        Clear(color=[1, 2])
    with pytest.raises(OptionError, match=r"property 'filter' is 'cubic'; use 'linear' or 'nearest'"):
        Blit(filter="cubic")
    with pytest.raises(OptionError, match=r"unknown format 'rgba17f' \(did you mean 'rgba16f'\?\)"):
        Clear(format="rgba17f")
    missing = tmp_path / "nope.png"
    with pytest.raises(OptionError, match=rf"pass Img: property 'path': file '{missing}' not found"):
        single(ImageLoader(path=str(missing)), name="Img").compile(size=(4, 4), gpu=gpu)
    with pytest.raises(OptionError, match=r"set property 'path'"):
        single(ImageLoader(), name="Img").compile(size=(4, 4), gpu=gpu)
    g = RenderGraph("T")
    g.add_pass(Clear(format="r32ui"), "Ids")
    g.add_pass(Blit(), "Copy")
    g.add_edge("Ids.dst", "Copy.src")
    g.mark_output("Copy.dst")
    with pytest.raises(OptionError, match=r"pass Copy: input 'src' is r32ui, an integer format"):
        g.compile(size=(4, 4), gpu=gpu)
