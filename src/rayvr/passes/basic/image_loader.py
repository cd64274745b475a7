"""ImageLoader: an image file (PNG/JPEG via Pillow, EXR via OpenEXR, HDR/PFM via imageio) into an output array.

One `path` fills every view; `paths` gives one file per view (layer i reads paths[min(i, n - 1)]).
The file is decoded once at compile and uploaded once into an internal array; each frame copies
it to `dst` on the GPU (so `dst` may alias with other transients).
"""
from __future__ import annotations

from pathlib import Path

import moderngl
import numpy as np

from ... import images
from ...errors import OptionError
from ...rendergraph.registry import register_pass
from ...rendergraph.render_pass import RenderPass, Reflection
from .compute import program, run_over, storable_format

FLOAT_SUFFIXES = images.FLOAT_SUFFIXES


def _image_size(path: Path, where: str) -> tuple[int, int]:
    if path.suffix.lower() in FLOAT_SUFFIXES:
        h, w = images.read_image(path, where).shape[:2]
        return w, h
    images.require_file(path, where)
    from PIL import Image

    try:
        with Image.open(path) as im:
            return im.size
    except Exception as exc:
        raise OptionError(f"{where}: cannot read '{path}': {exc}") from exc


@register_pass
class ImageLoader(RenderPass):
    """Output `dst` holds the image at its own size, as `format` ('' = rgba8 for 8-bit files,
    rgba32f for EXR/HDR). Rows are stored bottom-up (GL convention), so `read_output(..., flip_y=True)`
    gives the file's rows."""

    DST, IMAGE = "dst", "image"
    PROPERTIES = {"path": "", "paths": [], "format": ""}

    def validate_property(self, key, value):
        if key == "path" and not isinstance(value, (str, Path)):
            raise OptionError(f"pass {self.name}: property 'path' must be a file path, got {value!r}")
        if key == "path":
            return str(value)
        if key == "paths":
            if not isinstance(value, (list, tuple)) or not all(isinstance(p, (str, Path)) for p in value):
                raise OptionError(f"pass {self.name}: property 'paths' must be a list of file paths, got {value!r}")
            return [str(p) for p in value]
        if key == "format" and value != "":
            return storable_format(self.name, key, value)
        return super().validate_property(key, value)

    def files(self) -> list[Path]:
        """The image files: `paths`, else [`path`]; OptionError when neither is set."""
        files = [Path(p) for p in self.paths] or ([Path(self.path)] if self.path else [])
        if not files:
            raise OptionError(f"pass {self.name}: set property 'path' (one image for all views) "
                              f"or 'paths' (one per view)")
        return files

    def _where(self) -> str:
        return f"pass {self.name}: property 'path{'s' if self.paths else ''}'"

    def _natural_format(self) -> str:
        return "rgba32f" if self.files()[0].suffix.lower() in FLOAT_SUFFIXES else "rgba8"

    def reflect(self, cd):
        files = self.files()
        sizes = [_image_size(f, self._where()) for f in files]
        if len(set(sizes)) > 1:
            listing = ", ".join(f"{f.name} {w}x{h}" for f, (w, h) in zip(files, sizes))
            raise OptionError(f"pass {self.name}: property 'paths': images differ in size ({listing}); "
                              f"give images of one size")
        w, h = sizes[0]
        r = Reflection()
        r.add_output(self.DST, "the image, every view").format(self.format or self._natural_format()).texture_size(w, h)
        r.add_internal(self.IMAGE, "the decoded files, one layer each").format(
            self._natural_format()).texture_size(w, h).views(len(files))
        return r

    def compile(self, ctx, cd):
        where = self._where()
        kinds = {f.suffix.lower() in FLOAT_SUFFIXES for f in self.files()}
        if len(kinds) > 1:
            raise OptionError(f"{where}: mix of 8-bit and HDR files; give files of one kind")
        layers = [images.read_image(f, where)[::-1] for f in self.files()]   # GL rows are bottom-up
        self._pixels = np.ascontiguousarray(np.stack(layers)).tobytes()
        self._uploaded_to = None
        self._prog = program(ctx.gl, "blit.comp", self.format or self._natural_format())
        self._sampler = self.own(ctx.gl.sampler(filter=(moderngl.NEAREST, moderngl.NEAREST), repeat_x=False,
                                                repeat_y=False))

    def execute(self, ctx, data):
        image = data[self.IMAGE]
        if self._uploaded_to is not image:   # once per compile (internal pins never alias)
            image.write(self._pixels)
            self._uploaded_to = image
        run_over(self._prog, data[self.DST], image, self._sampler)
