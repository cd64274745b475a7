"""The displayed image: what a headset shows of a linear HDR render, computed on the CPU.

The error study judges test and reference on the picture a user sees, so both go through the one
transform below, in numpy: exposure (a fixed number of stops, the same for every image), the
ToneMapper's operator (the curves of `rayvr/passes/shaders/tonemap.comp`: ACES fit, Reinhard,
linear clamp) and sRGB encoding. The result is float sRGB in [0, 1], not quantised to 8 bits.

A per-image auto exposure would map test and reference differently (a darker test image would be
brightened), so the study fixes the exposure once: given in stops, or derived from the reference
with the GPU auto exposure's rule (key 0.18 over the mean log2 luminance of the pixels brighter
than 1e-3, `luminance.comp` and `exposure.comp`).
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..errors import OptionError
from ..images import srgb_encode

OPERATORS = ("aces", "reinhard", "linear")
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])
BLACK_LUMINANCE = 1e-3   # luminance.comp's: black pixels do not drag the exposure
AUTO_KEY = 0.18


@dataclasses.dataclass(frozen=True)
class Display:
    """How linear radiance becomes the displayed image: `operator` (aces, reinhard, linear) at
    `exposure` stops (None: derived from the reference once, `auto_exposure`)."""

    operator: str = "aces"
    exposure: float | None = None

    def __post_init__(self):
        if self.operator not in OPERATORS:
            raise OptionError(f"display operator {self.operator!r}: use one of {', '.join(OPERATORS)}")
        if self.exposure is not None and not math.isfinite(self.exposure):
            raise OptionError(f"display exposure {self.exposure!r}: give a finite number of stops or None (auto)")

    def fixed(self, reference) -> "Display":
        """This display with its exposure fixed (from `reference` when it is None)."""
        if self.exposure is not None:
            return self
        return Display(self.operator, auto_exposure(reference))

    def __call__(self, linear) -> np.ndarray:
        """Displayed sRGB (float64 in [0, 1], RGB) of linear radiance (..., c)."""
        if self.exposure is None:
            raise OptionError("Display: the exposure is not fixed; call display.fixed(reference) first")
        return tonemap(linear, self.operator, self.exposure)

    def describe(self) -> str:
        return f"{self.operator} tone mapping at {self.exposure:+.2f} stops, sRGB" if self.exposure is not None \
            else f"{self.operator} tone mapping, exposure from the reference, sRGB"

    def as_dict(self) -> dict:
        return {"operator": self.operator, "exposure_stops": self.exposure, "encoding": "sRGB",
                "quantised": False}


def aces_fit(x: np.ndarray) -> np.ndarray:
    """Narkowicz 2015's fit of the ACES RRT+ODT, as tonemap.comp has it."""
    x = x * 0.6
    return np.clip((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0)


def tonemap(linear, operator: str = "aces", exposure: float = 0.0) -> np.ndarray:
    """tonemap.comp on the CPU: exposure, operator, sRGB; the first three channels, float64."""
    c = np.asarray(linear, dtype=np.float64)[..., :3] * 2.0 ** float(exposure)
    c = np.where(np.isfinite(c).all(axis=-1, keepdims=True), np.maximum(c, 0.0), 0.0)
    if operator == "aces":
        ldr = aces_fit(c)
    elif operator == "reinhard":
        ldr = c / (1.0 + c)
    elif operator == "linear":
        ldr = np.clip(c, 0.0, 1.0)
    else:
        raise OptionError(f"tone mapping operator {operator!r}: use one of {', '.join(OPERATORS)}")
    return srgb_encode(ldr)


def clamp_negative(linear) -> tuple[np.ndarray, int]:
    """(radiance with negative values set to 0, how many there were): what the tone mapper
    shows of a render that wrote negative radiance (TAA's YCoCg box clamp can leave an RGB
    channel below 0). The study judges this, and reports the count."""
    a = np.asarray(linear)
    negative = a[..., :3] < 0
    count = int(negative.sum())
    if count:
        a = a.copy()
        a[..., :3][negative] = 0
    return a, count


def auto_exposure(reference) -> float:
    """Stops that map the reference's mean log2 luminance (pixels above 1e-3) to 0.18, as the
    GPU auto exposure would for it in one frame; 0 for an all-black reference."""
    c = np.asarray(reference, dtype=np.float64)[..., :3]
    lum = c @ LUMINANCE
    lit = lum[np.isfinite(lum) & (lum > BLACK_LUMINANCE)]
    if lit.size == 0:
        return 0.0
    return float(math.log2(AUTO_KEY) - np.log2(lit).mean())


def to_uint8(displayed: np.ndarray) -> np.ndarray:
    """Displayed float sRGB in [0, 1] as 8-bit pixels (for PNGs)."""
    return (np.clip(displayed, 0.0, 1.0) * 255.0 + 0.5).astype(np.uint8)
