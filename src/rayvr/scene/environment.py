"""Environments from what a user gives: a uniform radiance ("1,1,1", a number, an RGB triple) or
an equirectangular HDR file (EXR, Radiance HDR, PFM; PNG/JPEG as sRGB-encoded 8-bit), 2:1."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..errors import OptionError, SceneError
from .model import Environment


def parse_color(text: str, where: str) -> tuple[float, float, float] | None:
    """'r,g,b' or 'v' as linear RGB; None when `text` is not numbers."""
    parts = [p.strip() for p in str(text).split(",")]
    try:
        values = [float(p) for p in parts]
    except ValueError:
        return None
    if len(values) == 1:
        values *= 3
    if len(values) != 3 or not all(math.isfinite(v) and v >= 0 for v in values):
        raise OptionError(f"{where} {text}: give a radiance r,g,b of three non-negative numbers (e.g. 1,1,1) "
                          f"or an equirectangular image file")
    return tuple(values)


def load_environment(spec, where: str = "--environment", strength: float = 1.0) -> Environment:
    """An Environment from a colour ('1,1,1', 0.5, (r, g, b)) or an image file path."""
    from .. import images

    if isinstance(spec, (tuple, list)) or isinstance(spec, (int, float)):
        values = [float(spec)] * 3 if isinstance(spec, (int, float)) else [float(v) for v in spec]
        return Environment(tuple(v * strength for v in values), name=f"uniform {values}")
    color = parse_color(spec, where)
    if color is not None:
        return Environment(tuple(v * strength for v in color), name=f"uniform {','.join(f'{v:g}' for v in color)}")
    path = Path(spec)
    if not path.is_file():
        raise OptionError(f"{where} {spec}: no such file, and not a colour; give r,g,b or an EXR/HDR panorama")
    image = images.read_image(path, f"{where} {path}")
    if image.dtype == np.uint8:   # an 8-bit panorama is display-encoded
        image = images.srgb_to_linear(image[..., :3].astype(np.float64) / 255.0).astype(np.float32)
    h, w = image.shape[:2]
    if w != 2 * h:
        raise SceneError(f"{where} {path}: {w}x{h} is not an equirectangular panorama (width = 2 x height); "
                         f"give a 2:1 image")
    try:
        return Environment((strength,) * 3, image[..., :3].astype(np.float32), name=path.name)
    except SceneError as exc:
        raise SceneError(f"{where} {path}: {exc}") from None
