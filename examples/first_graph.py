"""A first render graph: build it in Python, compile it, print the report, write an image.

    python examples/first_graph.py [--out first_graph.png] [--size 256x256] [--views 2]

A checkerboard per view (shifted per eye), halved and scaled back up with linear Blits (the
upscaled copy reuses the checkerboard's texture: lifetime aliasing), converted to rgba8 and
written with the views side by side. A pass that feeds no output is pruned; the report says so.
"""
from __future__ import annotations

import argparse

import numpy as np

import rayvr as rv
from rayvr.fileio import write_png
from rayvr.passes.basic import Blit, Checkerboard, Clear


def build() -> rv.RenderGraph:
    g = rv.RenderGraph("FirstGraph")
    g.add_pass(Checkerboard(cell=16, color_a=[0.9, 0.6, 0.2, 1], color_b=[0.1, 0.2, 0.4, 1],
                            format="rgba16f"), "Pattern")
    g.add_pass(Blit(scale=0.5, filter="linear"), "Half")
    g.add_pass(Blit(scale=1.0, filter="linear"), "Full")          # reuses Pattern's texture
    g.add_pass(Blit(format="rgba8"), "ToLdr")
    g.add_pass(Clear(color=[1, 0, 1, 1]), "Unused")           # feeds nothing: pruned
    g.add_edge("Pattern.dst", "Half.src")
    g.add_edge("Half.dst", "Full.src")
    g.add_edge("Full.dst", "ToLdr.src")
    g.mark_output("ToLdr.dst")
    return g


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="first_graph.png")
    ap.add_argument("--size", default="256x256", help="per-view WxH")
    ap.add_argument("--views", type=int, default=2)
    args = ap.parse_args()
    w, h = (int(v) for v in args.size.split("x"))

    graph = build()
    compiled = graph.compile(size=(w, h), views=args.views)
    print(compiled.report())
    ctx = compiled.make_context()
    for _ in range(10):
        compiled.execute(ctx)
    print(compiled.profile())

    views = compiled.read_output("ToLdr.dst", flip_y=True)      # (views, h, w, 4) uint8
    write_png(args.out, np.concatenate(list(views), axis=1))      # atomic: never half written
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
