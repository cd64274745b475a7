"""How busy the lanes of the decision-reading passes' warps are, counted from the trace decision
(any GL: llvmpipe will do): for RTShadows' two dispatches, the composite and SVGF's reprojection,
the pixels with work, the 8x4 tiles (one warp each) holding any, and the batches of 32 the tile
gather (glsl/tile_gather.glsl, 8 tiles side by side) would run instead.

    python3 tools/gather_lanes.py SCENE WIDTH HEIGHT VIEWS reuse|foveation
"""
from __future__ import annotations

import sys

import numpy as np


def lanes(name: str, work: np.ndarray, gather: int = 8) -> str:
    """One line: the warps with work over 8x4 tiles, and over gathered batches of `gather` tiles."""
    views, h, w = work.shape
    hp, wp = -(-h // 4) * 4, -(-w // (8 * gather)) * 8 * gather
    pad = np.zeros((views, hp, wp), bool)
    pad[:, :h, :w] = work
    tiles = pad.reshape(views, hp // 4, 4, wp // 8, 8).sum(axis=(2, 4))
    warps = int((tiles > 0).sum())
    batches = int((-(-tiles.reshape(views, hp // 4, wp // (8 * gather), gather).sum(axis=3) // 32)).sum())
    n = int(work.sum())
    return (f"{name}: {n / work.size:.3f} of the pixels; warps with work {warps} (lanes busy "
            f"{n / max(1, 32 * warps):.2f}), gathered {batches} ({n / max(1, 32 * batches):.2f}), "
            f"{1 - batches / max(1, warps):.0%} fewer")


def main(argv: list[str]) -> None:
    import rayvr as rv
    from rayvr.renderer import Renderer
    from rayvr.scene import load_scene

    path, width, height, views, mode = argv[0], int(argv[1]), int(argv[2]), int(argv[3]), argv[4]
    g = rv.graphs.hybrid(preset="clean", **({"reuse": "views"} if mode == "reuse" else {"foveation": "fixed"}))
    g.mark_output("Decision.decision")
    g.mark_output("GBuffer.effect")
    with Renderer(load_scene(path), g, views=views, size=(width, height)) as r:
        for _ in range(2):
            r.render()
        d = r.read_output("Decision.decision")[..., 0].astype(np.uint32)
        effect = r.read_output("GBuffer.effect")[..., 0].astype(np.uint32) & 0xFF
    drawn = effect != 0xFF
    spread = (d & 4) != 0   # glsl/trace_decision.glsl DECISION_SPREAD
    traced = drawn & (effect >= 1) & ((d & 3) == 1)   # effect SHADOWS and above, DECISION_TRACE
    shared = (d & 8) != 0   # DECISION_SHARED_LIGHT
    for name, work in (("RTShadows, own light sample", traced & ~shared), ("RTShadows, shared sample", traced & shared),
                       ("composite", ~spread), ("SVGF reprojection", drawn & ~spread)):
        print(lanes(name, work))


if __name__ == "__main__":
    main(sys.argv[1:])
