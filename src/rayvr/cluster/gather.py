"""After the gather: passes that need every view of a frame run on the driver's context.

Auto exposure maps the mean log luminance of all views to mid grey, so a share of the views
cannot tone map itself: the workers return linear radiance and `tone_map` runs the same
ToneMapper over the gathered frame, in one dispatch over all views as one process would (so the
rgba8 images equal one process's when the radiance does).
"""
from __future__ import annotations

import numpy as np

from ..rendergraph.render_pass import Reflection, RenderPass

NUMPY_FORMATS = {np.dtype(np.float16): "rgba16f", np.dtype(np.float32): "rgba32f", np.dtype(np.uint8): "rgba8"}


class GatheredViews(RenderPass):
    """A graph's source of views rendered elsewhere: `pixels` (views, h, w, 4), rows bottom-up
    as GL stores them, written into `dst` (format `format`) when the graph executes."""

    DST = "dst"
    PROPERTIES = {"format": "rgba16f"}

    def __init__(self, props: dict | None = None, **kwargs):
        super().__init__(props, **kwargs)
        self.pixels = None

    def reflect(self, cd):
        r = Reflection()
        r.add_output(self.DST, "views gathered from the workers").format(self.format)
        return r

    def execute(self, ctx, data):
        if self.pixels is not None:
            data[self.DST].write(np.ascontiguousarray(self.pixels))


def tone_map(hdr: np.ndarray, operator: str = "aces", exposure: float = 0.0, auto_exposure: bool = False,
             gpu=None, flip_y: bool = True):
    """rgba8 (views, h, w, 4) of linear `hdr` (views, h, w, 4; rows top-down if `flip_y`)
    through rayvr's ToneMapper on `gpu` (default the process context); also returns the
    tone-mapped texture array (for quilts) and the compiled graph that owns it (release it)."""
    from ..gpu import get_context
    from ..passes.tonemap import ToneMapper
    from ..rendergraph.graph import RenderGraph

    gpu = gpu or get_context()
    views, h, w, _ = hdr.shape
    g = RenderGraph("Gathered")
    source = g.add_pass(GatheredViews(format=NUMPY_FORMATS[hdr.dtype]), "Gathered")
    g.add_pass(ToneMapper(operator=operator, exposure=exposure, auto_exposure=auto_exposure), "ToneMap")
    g.add_edge("Gathered.dst", "ToneMap.src")
    g.mark_output("ToneMap.dst")
    compiled = g.compile(size=(w, h), views=views, gpu=gpu, profiling=False)
    source.pixels = hdr[:, ::-1] if flip_y else hdr
    compiled.execute(compiled.make_context())
    return compiled.read_output("ToneMap.dst", flip_y=flip_y), compiled.get_output("ToneMap.dst"), compiled
