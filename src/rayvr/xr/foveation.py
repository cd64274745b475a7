"""Foveation's geometry: how far each pixel lies from where the eye looks, and the share of the
rays it gets there.

Eccentricity is the angle between a pixel's ray and the gaze direction, both in the view's eye
space: the eye tracker's gaze where one is known (`ViewSet.gaze`), else the direction through the
image's centre (fixed foveation). The ray budget is 1 within the foveal radius R and falls with
the square of eccentricity e beyond it towards the periphery's share S:

    budget(e) = 1                          e <= R
              = S + (1 - S) (R / e)^2      e > R

(sample density following acuity, whose resolvable angle grows about linearly with e). The
renderer's trace decision evaluates the same formula per pixel on the GPU
(passes/trace_decision/decide.comp); this is its float64 twin, and the error study's fall-off.
"""
from __future__ import annotations

import numpy as np

from ..errors import OptionError

MODES = ("fixed", "gaze")          # foveation's choices; None / "none": off
DEFAULT_RADIUS_DEG = 5.0           # the central 10 degrees at full density
DEFAULT_PERIPHERY_SHARE = 0.25
# The sparsest density a decision reconstructs from: at 1/8 each 5x5 neighbourhood holds a traced
# pixel (an aligned block of 4 of the 64 ranks of an 8x8 ordered dither is a lattice of period 4).
MIN_PERIPHERY_SHARE = 0.125


def check_falloff(radius_deg, share, where: str = "foveation") -> tuple[float, float]:
    """(radius, share) checked: a radius in (0, 90] degrees, a share in [MIN_PERIPHERY_SHARE, 1]."""
    if isinstance(radius_deg, bool) or not isinstance(radius_deg, (int, float)) or not 0.0 < radius_deg <= 90.0:
        raise OptionError(f"{where}: foveal radius must be in (0, 90] degrees, got {radius_deg!r}")
    if isinstance(share, bool) or not isinstance(share, (int, float)) or not MIN_PERIPHERY_SHARE <= share <= 1.0:
        raise OptionError(f"{where}: periphery share must be in [{MIN_PERIPHERY_SHARE}, 1] (the sparsest density "
                          f"the neighbours reconstruct from), got {share!r}")
    return float(radius_deg), float(share)


def budget(eccentricity_deg, radius_deg: float = DEFAULT_RADIUS_DEG,
           share: float = DEFAULT_PERIPHERY_SHARE) -> np.ndarray:
    """The share of rays a pixel at `eccentricity_deg` traces (the module docstring's formula)."""
    e = np.asarray(eccentricity_deg, dtype=np.float64)
    outside = share + (1.0 - share) * (radius_deg / np.maximum(e, 1e-12)) ** 2
    return np.where(e <= radius_deg, 1.0, outside)


def eccentricity_weight(eccentricity_deg, radius_deg: float = DEFAULT_RADIUS_DEG) -> np.ndarray:
    """How much an error at `eccentricity_deg` counts against one at the gaze: the budget's own
    fall-off without a floor, 1 within the foveal radius and (R / e)^2 beyond."""
    return budget(eccentricity_deg, radius_deg, 0.0)


def centre_tangents(view_set) -> np.ndarray:
    """(views, 2) tangents of the direction through each view's image centre (fixed foveation's gaze)."""
    t = np.array([v.fov.tangents() for v in view_set], dtype=np.float64)   # left, right, down, up
    return np.stack([(t[:, 0] + t[:, 1]) / 2, (t[:, 2] + t[:, 3]) / 2], axis=1)


def eccentricity_map(view_set, gaze=None) -> np.ndarray:
    """Degrees between each pixel's centre ray and the gaze, (views, h, w), row 0 the bottom row
    (GL, as readbacks are unless flipped). `gaze`: (views, 2) tangents; default the view set's
    (`ViewSet.gaze_tangents`: the tracker's, else each image's centre)."""
    w, h = view_set.size
    t = np.array([v.fov.tangents() for v in view_set], dtype=np.float64)   # left, right, down, up
    g = np.asarray(view_set.gaze_tangents()[0] if gaze is None else gaze, dtype=np.float64)
    ux = (np.arange(w) + 0.5) / w
    uy = (np.arange(h) + 0.5) / h
    tx = t[:, 0, None] + (t[:, 1] - t[:, 0])[:, None] * ux[None]            # (views, w)
    ty = t[:, 2, None] + (t[:, 3] - t[:, 2])[:, None] * uy[None]            # (views, h)
    px, py = tx[:, None, :], ty[:, :, None]
    gx, gy = g[:, 0, None, None], g[:, 1, None, None]
    cos = (px * gx + py * gy + 1.0) / (np.sqrt(px * px + py * py + 1.0) * np.sqrt(gx * gx + gy * gy + 1.0))
    return np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))
