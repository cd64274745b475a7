"""Light-field output: Looking Glass quilts composed on the GPU from a texture array of views.

A quilt tiles N views into one image, `cols` x `rows`, view 0 at the bottom-left, going right
then up (Looking Glass Factory, "Quilt" documentation). The views themselves lie on one
horizontal line of cameras, view 0 leftmost (a Looking Glass shows horizontal parallax only):
`quilt_views()`. Looking Glass Bridge reads the layout from the file name suffix
`_qs{cols}x{rows}a{aspect}` (`quilt_filename()`).
"""
from __future__ import annotations

import dataclasses
import re
from pathlib import Path

import moderngl

from ..errors import OptionError, XrError
from ..gpu.shaders import compute_program

_SHADER = Path(__file__).with_name("quilt.comp")
RGBA_IMAGE_FORMATS = {"f1": "rgba8", "f2": "rgba16f", "f4": "rgba32f"}   # moderngl dtype -> GLSL image format


@dataclasses.dataclass(frozen=True)
class QuiltLayout:
    """A display's quilt: tiles, the aspect (width/height) of each view, the full quilt size."""

    cols: int
    rows: int
    aspect: float
    quilt_size: tuple[int, int]

    @property
    def views(self) -> int:
        """Tiles in the quilt: the most views it holds."""
        return self.cols * self.rows

    @property
    def view_size(self) -> tuple[int, int]:
        """(width, height) of one tile in pixels."""
        return self.quilt_size[0] // self.cols, self.quilt_size[1] // self.rows


# Looking Glass Factory's recommended quilt settings per display (docs.lookingglassfactory.com,
# "Quilt settings by device").
LOOKING_GLASS = {
    "portrait": QuiltLayout(8, 6, 0.75, (3360, 3360)),
    "go": QuiltLayout(11, 6, 0.5625, (4092, 4092)),
    "16in_landscape": QuiltLayout(7, 7, 16 / 9, (5999, 5999)),
    "32in_landscape": QuiltLayout(7, 7, 16 / 9, (8190, 8190)),
}


def looking_glass(name: str) -> QuiltLayout:
    """The quilt layout of a Looking Glass display by name (a key of LOOKING_GLASS)."""
    try:
        return LOOKING_GLASS[name]
    except KeyError:
        raise OptionError(f"unknown Looking Glass display '{name}'; choose one of {', '.join(LOOKING_GLASS)}") from None


def parse_grid(text: str) -> tuple[int, int]:
    """'8x6' -> (8, 6), as `rayvr render --grid` takes it."""
    m = re.fullmatch(r"\s*(\d+)\s*[xX]\s*(\d+)\s*", str(text))
    if not m or int(m.group(1)) < 1 or int(m.group(2)) < 1:
        raise OptionError(f"--grid '{text}' is not COLSxROWS (e.g. 8x6)")
    return int(m.group(1)), int(m.group(2))


def quilt_filename(path: str | Path, cols: int, rows: int, aspect: float) -> Path:
    """`path` with Looking Glass's `_qs{cols}x{rows}a{aspect}` suffix before the extension."""
    path = Path(path)
    return path.with_name(f"{path.stem}_qs{cols}x{rows}a{aspect:.4g}{path.suffix}")


def quilt_views(scene, cols: int, rows: int, size, view_cone_deg: float = 40.0, focus: float | None = None):
    """The cols * rows views of a quilt from the scene's camera: one horizontal row of sheared
    cameras (`lightfield_row`), view 0 leftmost, spanning `view_cone_deg` as seen from the focal
    plane at `focus` metres (default: the scene's centre, where `default_views` converges)."""
    from .cameras import lightfield_row, scene_frustum

    pose, fov, near, far, focal = scene_frustum(scene, size)
    return lightfield_row(cols * rows, view_cone_deg, focus or focal, fov, size, center_pose=pose,
                          near=near, far=far)


def compose_quilt(gl: moderngl.Context, texture_array, cols: int, rows: int, out=None) -> moderngl.Texture:
    """Tile the layers of `texture_array` into one RGBA texture of (cols * w, rows * h).

    One compute dispatch on the GPU. Pass last frame's result as `out` to reuse it.
    """
    n = texture_array.layers
    if cols < 1 or rows < 1:
        raise OptionError(f"compose_quilt: cols and rows must be >= 1, got {cols}x{rows}")
    if n > cols * rows:
        raise OptionError(f"compose_quilt: {n} views do not fit a {cols}x{rows} quilt; "
                          f"use a grid with at least {n} tiles")
    fmt = RGBA_IMAGE_FORMATS.get(texture_array.dtype)
    if fmt is None:
        raise XrError(f"compose_quilt: views of dtype '{texture_array.dtype}' cannot be tiled; use f1, f2 or f4")
    w, h = texture_array.width, texture_array.height
    size = (cols * w, rows * h)
    if out is None or out.size != size or out.dtype != texture_array.dtype or out.components != 4:
        out = gl.texture(size, 4, dtype=texture_array.dtype)
    prog = compute_program(gl, _SHADER, {"QUILT_IMAGE_FORMAT": fmt})
    prog["grid"] = (cols, rows)
    prog["view_count"] = n
    texture_array.use(0)
    out.bind_to_image(0, read=False, write=True)
    prog.run((w + 7) // 8, (h + 7) // 8, cols * rows)
    gl.memory_barrier()
    return out


def read_quilt(texture, encode_srgb: bool = False):
    """The quilt as uint8 (height, width, 4), top row first: ready for PIL / imageio."""
    from .readback import read_layers

    return read_layers(texture, encode_srgb)[0]


def write_quilt_png(texture, path: str | Path, encode_srgb: bool = False) -> Path:
    """Write the quilt to exactly `path`, PNG or JPEG by its suffix (written to a temporary name
    first, so no half-written file)."""
    from ..fileio import write_image

    return write_image(path, read_quilt(texture, encode_srgb), alpha=True)
