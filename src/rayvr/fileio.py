"""Writing output files so that a failure never leaves a half-written file behind.

Everything rayvr writes (images, graphs, reports, plots) goes through `atomic_write`: the data is
written to a temporary file in the target's folder, then renamed over the target.
"""
from __future__ import annotations

import os
import tempfile
from pathlib import Path

import numpy as np

from .errors import OptionError


def atomic_write(path, write) -> Path:
    """Call `write(tmp_path)` and rename the result to `path` (folders are created)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=path.suffix, dir=path.parent)
    os.close(fd)
    try:
        write(Path(tmp))
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def write_text(path, text: str) -> Path:
    """Write `text` to `path` atomically."""
    return atomic_write(path, lambda tmp: tmp.write_text(text))


def write_png(path, pixels: np.ndarray, alpha: bool = False) -> Path:
    """An (h, w, c) uint8 image, rows top-down; alpha is dropped unless `alpha`."""
    from PIL import Image

    rgb = np.ascontiguousarray(pixels[..., :4 if alpha else 3] if pixels.ndim == 3 else pixels)
    return atomic_write(path, lambda tmp: Image.fromarray(rgb).save(tmp, format="PNG"))


def write_exr(path, pixels: np.ndarray) -> Path:
    """An (h, w, c) float image as a ZIP-compressed scanline EXR (RGB, float32)."""
    try:
        import OpenEXR
    except ImportError:
        raise OptionError(f"{path}: EXR output needs the 'openexr' package: pip install openexr") from None
    rgb = np.ascontiguousarray(pixels[..., :3].astype(np.float32))

    def write(tmp: Path):
        header = {"type": OpenEXR.scanlineimage, "compression": OpenEXR.ZIP_COMPRESSION}
        with OpenEXR.File(header, {"RGB": rgb}) as f:
            f.write(str(tmp))

    return atomic_write(path, write)
