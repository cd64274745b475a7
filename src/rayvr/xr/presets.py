"""Real headsets' per-eye resolution, field of view, IPD and refresh rates, for SimulatedHeadset.

Sources, per figure:
- Resolutions and refresh rates: the manufacturers' specification pages (Valve Index: "Dual
  1440x1600 LCDs", 80/90/120/144 Hz, valvesoftware.com/index/headset; Meta Quest 2: 1832x1920
  per eye, 72/90/120 Hz, and Meta Quest 3: 2064x2208 per eye, 72/90/120 Hz, meta.com tech specs;
  HTC Vive Pro 2: 2448x2448 per eye, 90/120 Hz, vive.com/us/product/vive-pro2/specs).
- Fields of view: OpenVR/Oculus raw projection tangents recorded with hmdq and published in the
  HMD Geometry Database (risa2000.github.io/hmdgdb). Quest 2: the exact values of its
  "Quest2_Native_R72" page. Valve Index: approximate tangents of the same kind (about 54/51 deg
  outer/inner, 55-56 deg up/down), not checked against the page when written: `approximate=True`.
  Where no recording was at hand the per-eye angles are *derived* from the manufacturer's total
  FOV (Quest 3: 110 deg H x 96 deg V; Vive Pro 2: "up to 120 deg" H) with the inner half-angle
  assumed 45 deg as on Quest 2; also `approximate=True`. On a real headset, OpenXRSink uses the fov the
  runtime reports per frame (xrLocateViews), never these tables.
- IPD: the headset's default (the hmdgdb eye-to-head offset where recorded) or 63 mm, the mean
  adult IPD (Dodgson 2004, "Variation and extrema of human interpupillary distance").
The right eye mirrors the left eye's horizontal angles (lenses are symmetric about the nose).
"""
from __future__ import annotations

import dataclasses
import math

from ..errors import OptionError, did_you_mean
from .views import Fov


@dataclasses.dataclass(frozen=True)
class HeadsetPreset:
    """One headset model's display geometry and timing."""

    name: str
    title: str
    eye_size: tuple[int, int]          # per-eye panel pixels (width, height)
    left_fov: Fov                      # left eye; the right eye is mirrored
    ipd: float                         # metres
    refresh_rates: tuple[float, ...]   # Hz the panel supports
    default_refresh: float
    approximate: bool = False          # fov derived from total-FOV marketing figures

    @property
    def pixels_per_degree(self) -> float:
        """Panel pixels per degree of view: the mean of width / horizontal fov and height /
        vertical fov (what FLIP's `ppd` asks for; the centre of a planar projection has fewer,
        its edges more)."""
        f = self.left_fov
        horizontal = self.eye_size[0] / math.degrees(f.angle_right - f.angle_left)
        vertical = self.eye_size[1] / math.degrees(f.angle_up - f.angle_down)
        return 0.5 * (horizontal + vertical)

    @property
    def right_fov(self) -> Fov:
        """The left eye's fov mirrored about the nose."""
        f = self.left_fov
        return Fov(-f.angle_right, -f.angle_left, f.angle_up, f.angle_down)


PRESETS: dict[str, HeadsetPreset] = {p.name: p for p in [
    HeadsetPreset("index", "Valve Index", (1440, 1600),
                  Fov.from_tangents(-1.3953, 1.2388, -1.4700, 1.4570),
                  ipd=0.0635, refresh_rates=(80.0, 90.0, 120.0, 144.0), default_refresh=90.0, approximate=True),
    HeadsetPreset("quest2", "Meta Quest 2", (1832, 1920),
                  Fov.from_tangents(-1.279942, 1.0, -1.191754, 1.110613),   # hmdgdb Quest2_Native_R72
                  ipd=0.0635, refresh_rates=(72.0, 90.0, 120.0), default_refresh=90.0),
    HeadsetPreset("quest3", "Meta Quest 3", (2064, 2208),
                  Fov.from_degrees(-55.0, 45.0, 48.0, -48.0),
                  ipd=0.063, refresh_rates=(72.0, 90.0, 120.0), default_refresh=90.0, approximate=True),
    HeadsetPreset("vive_pro2", "HTC Vive Pro 2", (2448, 2448),
                  Fov.from_degrees(-60.0, 45.0, 50.0, -50.0),
                  ipd=0.063, refresh_rates=(90.0, 120.0), default_refresh=90.0, approximate=True),
]}


def get_preset(name: str) -> HeadsetPreset:
    """The preset called `name`, or an OptionError listing the known ones."""
    try:
        return PRESETS[name]
    except KeyError:
        raise OptionError(f"unknown headset preset '{name}'{did_you_mean(name, PRESETS)}; "
                          f"choose one of {', '.join(PRESETS)}") from None
