"""Screenshots: the window as drawn (the frame with its UI) to PNG, the graph's HDR output to EXR.
Both go through rayvr.fileio (atomic writes); an unwritable path is one OptionError line."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import OptionError


def read_framebuffer(framebuffer, size) -> np.ndarray:
    """The framebuffer's RGB pixels as (h, w, 3) uint8, rows top-down (an image's order)."""
    w, h = size
    data = framebuffer.read(viewport=(0, 0, w, h), components=3, alignment=1)
    return np.frombuffer(data, np.uint8).reshape(h, w, 3)[::-1].copy()


def hdr_output(renderer) -> str | None:
    """The first marked output of the compiled graph in a float format (the linear radiance), or None."""
    plan = renderer.compiled.plan
    for ref in plan.outputs:
        res = plan.resources.get(ref)
        if res is not None and res.fmt and "f" in res.fmt and res.kind.value == "texture":
            return ref
    return None


def _write(path: Path, write) -> Path:
    try:
        return write()
    except OSError as exc:
        raise OptionError(f"{path}: cannot write it: {exc.strerror or exc}; choose a writable path") from None


def save_png(path, pixels: np.ndarray) -> Path:
    """Write window pixels (h, w, 3) top-down as PNG."""
    from ..fileio import write_png

    path = Path(path)
    return _write(path, lambda: write_png(path, pixels))


def save_hdr(path, renderer) -> Path:
    """Write the graph's HDR output (views side by side, linear) as EXR."""
    from ..fileio import write_exr

    path = Path(path)
    ref = hdr_output(renderer)
    if ref is None:
        raise OptionError(f"{path}: the graph marks no float (HDR) output to write as EXR; "
                          f"mark one, e.g. graph.mark_output('Composite.color')")
    pixels = renderer.read_output(ref, flip_y=True)
    return _write(path, lambda: write_exr(path, np.concatenate(list(pixels), axis=1)))
