"""Reading image files into numpy: PNG/JPEG (Pillow), EXR (OpenEXR), HDR/PFM (imageio). The one
reader of every image rayvr takes as input (ImageLoader's files, environment maps)."""
from __future__ import annotations

import functools
from pathlib import Path

import numpy as np

from .errors import OptionError

FLOAT_SUFFIXES = {".exr", ".hdr", ".pfm"}


def require_file(path: Path, where: str) -> None:
    if not path.is_file():
        raise OptionError(f"{where}: file '{path}' not found; give an existing PNG, JPEG or EXR path")


def read_image(path: Path, where: str) -> np.ndarray:
    """(h, w, 4) uint8 for 8-bit files, float32 for HDR files; rows top-down as in the file.
    Decoded once per file version (reflect and compile both ask); do not modify the result."""
    require_file(path, where)
    st = path.stat()
    return _decode(path.resolve(), st.st_mtime_ns, st.st_size, where)


@functools.lru_cache(maxsize=8)
def _decode(path: Path, mtime_ns: int, size: int, where: str) -> np.ndarray:
    try:
        if path.suffix.lower() == ".exr":
            a = read_exr(path, where)
        elif path.suffix.lower() in FLOAT_SUFFIXES:
            import imageio.v3 as iio

            a = np.asarray(iio.imread(path), dtype=np.float32)
        else:
            from PIL import Image

            with Image.open(path) as im:
                a = np.asarray(im.convert("RGBA"))
    except OptionError:
        raise
    except Exception as exc:
        raise OptionError(f"{where}: cannot read '{path}': {exc}") from exc
    if a.dtype not in (np.uint8, np.float32):
        a = a.astype(np.float32)
    if a.ndim == 2:
        a = a[:, :, None]
    if a.shape[2] < 4:   # grey -> rgb, rgb -> rgba with alpha 1
        rgb = np.repeat(a[:, :, :1], 3, axis=2) if a.shape[2] < 3 else a[:, :, :3]
        one = np.full(a.shape[:2] + (1,), 1.0 if a.dtype == np.float32 else 255, a.dtype)
        a = np.concatenate([rgb, one], axis=2)
    return np.ascontiguousarray(a[:, :, :4])


def read_exr(path: Path, where: str) -> np.ndarray:
    try:
        import OpenEXR
    except ImportError:
        raise OptionError(f"{where}: reading '{path}' needs the OpenEXR bindings: pip install openexr") from None
    with OpenEXR.File(str(path)) as f:   # pixels must be read while the file is open
        channels = {k: np.array(c.pixels, dtype=np.float32) for k, c in f.channels().items()}
    for group in ("RGBA", "RGB"):
        if group in channels:
            return channels[group]
    names = [c for c in ("R", "G", "B", "A", "Y") if c in channels]
    if not names:
        raise OptionError(f"{where}: '{path}' has no R/G/B/A/Y channels (it has {', '.join(channels)})")
    return np.stack([channels[c] for c in names], axis=2)


def srgb_encode(x) -> np.ndarray:
    """Linear values clipped to [0, 1] and sRGB-encoded (tonemap.comp's srgb_encode), in `x`'s
    float dtype (float64 for other input)."""
    x = np.asarray(x)
    x = np.clip(x if x.dtype.kind == "f" else x.astype(np.float64), 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def srgb_to_linear(x: np.ndarray) -> np.ndarray:
    """sRGB-encoded values in [0, 1] to linear (float64)."""
    x = np.asarray(x, dtype=np.float64)
    return np.where(x <= 0.04045, x / 12.92, ((x + 0.055) / 1.055) ** 2.4)
