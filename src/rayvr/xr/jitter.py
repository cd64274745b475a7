"""Sub-pixel camera jitter: the Halton (2, 3) sequence that temporal anti-aliasing resolves."""
from __future__ import annotations

# A still view averages its jittered frames without bound (rayvr.passes.TAA), so the cycle is long:
# its points are the quadrature of the pixel's box filter, and any run of consecutive frames of it
# still covers the pixel evenly for TAA in motion.
JITTER_SEQUENCE_LENGTH = 1024


def halton(index: int, base: int) -> float:
    """The radical inverse of `index` in `base`: the Halton sequence's value in [0, 1)."""
    result, f = 0.0, 1.0
    while index > 0:
        f /= base
        result += f * (index % base)
        index //= base
    return result


def halton_jitter(frame_index: int, length: int = JITTER_SEQUENCE_LENGTH) -> tuple[float, float]:
    """Sub-pixel jitter in pixels, in [-0.5, 0.5)^2, from the Halton (2, 3) sequence (cycle of
    `length` frames; the sequence starts at index 1 so frame 0 is not the pixel corner)."""
    i = frame_index % max(int(length), 1) + 1
    return halton(i, 2) - 0.5, halton(i, 3) - 0.5
