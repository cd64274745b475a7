"""Disjoint frame-index ranges, so that no two renders of the error study share random numbers.

Every random stream of the renderer is seeded by (pixel, view, frame index, salt), and TAA's
jitter follows the frame index; `rv.Renderer(first_frame=...)` starts a render at a given index.
The study gives each kind of render its own range of 2^20 frames:

    [0, 2^20)                          the configurations: timing, error frames, motion, progressive
    REFERENCE + k 2^20, k = 0          the static reference (half A then half B, one after the other)
    REFERENCE + k 2^20, k = 1 .. 255   the reference of trajectory sample k
    FLOOR + j 2^20, j = 0 .. 255       the converged render of configuration j (its bias floor)

The bounce check of a reference deliberately reuses half A's frames: with the same random
numbers, B and B + 1 bounces differ only by the extra bounce's light.
"""
from __future__ import annotations

import hashlib

RANGE = 1 << 20                  # frames per range: more than any render of the study takes
TEST = 0
REFERENCE = 1 << 28
FLOOR = 2 << 28
SLOTS = 256


def reference_first_frame(sample: int = 0) -> int:
    """First frame of the reference of trajectory sample `sample` (0: the static view)."""
    if not 0 <= sample < SLOTS:
        raise ValueError(f"reference slot {sample} outside 0..{SLOTS - 1}")
    return REFERENCE + sample * RANGE


def floor_first_frame(key: str) -> int:
    """First frame of a configuration's converged render, from its settings' key (stable
    whatever the order of the configurations)."""
    slot = int(hashlib.sha256(key.encode()).hexdigest()[:8], 16) % SLOTS
    return FLOOR + slot * RANGE


def check_length(frames: int, what: str) -> None:
    """A render of `frames` frames must fit in its range."""
    if frames > RANGE:
        from ..errors import OptionError

        raise OptionError(f"{what}: {frames} frames exceed the {RANGE} frames of its seed range; render fewer")
