"""Looking Glass quilts: exact tile placement on the GPU, layouts, file names."""
import numpy as np
import pytest

from rayvr.errors import OptionError
from rayvr.xr import LOOKING_GLASS, compose_quilt, read_quilt, write_quilt_png
from rayvr.xr.quilt import parse_grid, quilt_filename


def _views(gl, w, h, n, dtype="f1"):
    data = np.zeros((n, h, w, 4), np.float32)
    for v in range(n):
        data[v, ..., 0] = v / 255.0 * 7                      # the view id
        data[v, ..., 1] = np.arange(w)[None, :] / 255.0      # x within the view
        data[v, ..., 2] = np.arange(h)[:, None] / 255.0      # y within the view (GL: 0 = bottom)
        data[v, ..., 3] = 1.0
    if dtype == "f1":
        raw = np.round(data * 255).astype(np.uint8)
    else:
        raw = data.astype({"f2": np.float16, "f4": np.float32}[dtype])
    return gl.texture_array((w, h, n), 4, raw.tobytes(), dtype=dtype)


@pytest.mark.parametrize("dtype", ["f1", "f2", "f4"])
def test_tiles_are_placed_exactly_view_zero_bottom_left(gl, dtype):
    w, h, n, cols, rows = 6, 4, 7, 3, 3
    quilt = compose_quilt(gl, _views(gl, w, h, n, dtype), cols, rows)
    assert quilt.size == (cols * w, rows * h)
    img = read_quilt(quilt).astype(int)[::-1]                # back to GL order: row 0 at the bottom
    for v in range(cols * rows):
        col, row = v % cols, v // cols
        tile = img[row * h:(row + 1) * h, col * w:(col + 1) * w]
        if v < n:
            assert (tile[..., 0] == v * 7).all(), v
            assert (tile[..., 1] == np.arange(w)[None, :]).all()
            assert (tile[..., 2] == np.arange(h)[:, None]).all()
        else:
            assert (tile[..., :3] == 0).all() and (tile[..., 3] == 255).all()   # unused tiles are black
    top_left_of_png = read_quilt(quilt)[h - 1, 0]            # PNG row h-1: inside the top tile row
    assert top_left_of_png[0] == 6 * 7                       # view 6 = col 0, row 2 (the top row)


def test_reusing_the_output_texture(gl):
    views = _views(gl, 4, 4, 4)
    first = compose_quilt(gl, views, 2, 2)
    assert compose_quilt(gl, views, 2, 2, out=first) is first
    assert compose_quilt(gl, views, 4, 1, out=first) is not first


def test_too_many_views_for_the_grid(gl):
    with pytest.raises(OptionError, match="5 views do not fit a 2x2 quilt"):
        compose_quilt(gl, _views(gl, 2, 2, 5), 2, 2)


def test_write_png_and_looking_glass_names(gl, tmp_path):
    from PIL import Image

    q = compose_quilt(gl, _views(gl, 3, 2, 4), 2, 2)
    layout = LOOKING_GLASS["portrait"]
    assert (layout.cols, layout.rows, layout.views, layout.view_size) == (8, 6, 48, (420, 560))
    path = write_quilt_png(q, quilt_filename(tmp_path / "out.png", 2, 2, 0.75))
    assert path.name == "out_qs2x2a0.75.png"
    assert np.array(Image.open(path)).shape == (4, 6, 4)
    assert not list(tmp_path.glob("*.part"))


def test_parse_grid():
    assert parse_grid("8x6") == (8, 6)
    with pytest.raises(OptionError, match="COLSxROWS"):
        parse_grid("8-6")
