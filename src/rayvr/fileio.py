"""Writing output files so that a failure never leaves a half-written file behind.

Everything rayvr writes (images, graphs, reports, plots) goes through `atomic_write`: the data is
written to a temporary file in the target's folder, then renamed over the target. A report of
many files goes through `atomic_folder`: written into a temporary folder beside the target,
which replaces the target only once every file is there.
"""
from __future__ import annotations

import contextlib
import io
import os
import shutil
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


def png_bytes(pixels: np.ndarray) -> bytes:
    """An (h, w, c) uint8 image encoded as PNG bytes (for data URIs)."""
    from PIL import Image

    out = io.BytesIO()
    Image.fromarray(np.ascontiguousarray(pixels)).save(out, format="PNG")
    return out.getvalue()


def check_folder_target(path) -> Path:
    """`path` for `atomic_folder`: an OptionError now, before any work, if it cannot be one."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise OptionError(f"{path}: exists and is not a folder; name a folder for the report")
    parent = path.parent if str(path.parent) else Path(".")
    probe = parent
    while not probe.exists():
        probe = probe.parent
    if not os.access(probe, os.W_OK):
        raise OptionError(f"{path}: cannot write in {probe}; choose a folder you can write to")
    return path


@contextlib.contextmanager
def atomic_folder(path):
    """Yield a temporary folder beside `path`; when the block ends normally it becomes `path`
    (an existing folder there is replaced), and when it raises (Ctrl-C included) it is removed,
    so `path` is either the old folder or the complete new one, never a half."""
    path = check_folder_target(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{path.name}.", dir=path.parent))
    try:
        yield tmp
        old = None
        if path.exists():
            old = Path(tempfile.mkdtemp(prefix=f".{path.name}.old.", dir=path.parent))
            os.replace(path, old / path.name)
        os.replace(tmp, path)
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return path


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
