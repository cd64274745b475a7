"""The per-effect pixel lists EffectCompaction writes and the ray passes dispatch over
(glsl/pixel_list.glsl has the layout): sizes, the indirect-dispatch offset, and a readback."""
from __future__ import annotations

import numpy as np

HEADER_BYTES = 16   # count + indirect dispatch args
DISPATCH_OFFSET = 4
EMPTY_HEADER = np.array([0, 0, 1, 1], np.uint32).tobytes()   # no pixel; (0, 1, 1) groups


def empty_lists(ctx, *buffers) -> None:
    """Empty pixel lists before their writer appends (count 0, dispatch (0, 1, 1)), from the host
    after a buffer-update barrier: a list may be a transient whose memory another pass's shaders
    wrote just before."""
    from ...rendergraph.render_pass import Access

    ctx.barrier(Access.UPDATE)
    for buffer in buffers:
        buffer.write(EMPTY_HEADER)


def dispatch_list(res, block: str, buffer) -> None:
    """Bind list `buffer` to the storage block `block` of program `res` and dispatch the groups its
    header counts (indirect, at DISPATCH_OFFSET)."""
    res.buffer(block, buffer)
    res.prog.run_indirect(buffer, DISPATCH_OFFSET)


def pixel_list_bytes(size: tuple[int, int], views: int) -> int:
    """Bytes of a pixel list that can hold every pixel of every view."""
    return HEADER_BYTES + 4 * size[0] * size[1] * views


def read_pixel_list(buffer) -> tuple[int, np.ndarray]:
    """(count, (n, 3) x/y/view) of a pixel-list buffer; a readback for tests and tools."""
    head = np.frombuffer(buffer.read(HEADER_BYTES), dtype=np.uint32)
    n = int(head[0])
    items = np.frombuffer(buffer.read(4 * n, offset=HEADER_BYTES), dtype=np.uint32) if n else np.zeros(0, np.uint32)
    xyz = np.stack([items & 0x1FFF, (items >> 13) & 0x1FFF, items >> 26], axis=1)
    return n, xyz
