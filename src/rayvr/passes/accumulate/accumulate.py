"""Accumulate pass: the progressive running mean of its
input over frames (after Falcor's AccumulatePass), for converging path-traced renders.

The sum lives in internal rgba32f pins (Kahan-compensated), so the mean of N frames equals the
float mean of the inputs. It restarts when `reset()` is called, and then:
- under a Renderer, when `ctx.sample_index` is 0: the Renderer's one signal that the views, the
  render-space origin or the scene (instances, lights, materials) changed;
- run without one (`ctx.sample_index` None), when its own check sees the frame's views (pose,
  field of view, size or count) or the scene change.
`max_frames` > 0 stops adding after that many frames; the output stays the mean of those.
"""
from __future__ import annotations

import numpy as np

from ...gpu.program_resources import program_resources
from ...rendergraph.registry import register_pass
from ...rendergraph.render_pass import Access, Reflection, RenderPass
from ..dispatch import groups_2d


@register_pass
class Accumulate(RenderPass):
    """Progressive mean of `src` -> `dst` (rgba32f); see the module docstring for resets."""

    SRC, DST = "src", "dst"
    SUM, COMPENSATION = "sum", "compensation"
    COUNTS_NONFINITE = True   # scrubs NaN/Inf samples (glsl/nonfinite.glsl)
    PROPERTIES = {"enabled": True, "max_frames": 0, "auto_reset": True}
    WHOLE = {"max_frames": (0, None, "frames averaged; 0: no limit")}

    def __init__(self, props: dict | None = None, **kwargs):
        super().__init__(props, **kwargs)
        self._count = 0
        self._pending_reset = True
        self._key = None

    def on_properties_changed(self):
        self.reset()

    @property
    def frame_count(self) -> int:
        """Frames in the current mean."""
        return self._count

    def reset(self) -> None:
        """Start the mean again at the next frame."""
        self._pending_reset = True

    def reflect(self, cd):
        r = Reflection()
        r.add_input(self.SRC, "this frame's estimate (any float format)")
        r.add_output(self.DST, "mean over the accumulated frames").format("rgba32f")
        r.add_internal(self.SUM, "running sum").format("rgba32f").accessed(Access.IMAGE)
        r.add_internal(self.COMPENSATION, "Kahan compensation of the sum").format("rgba32f").accessed(Access.IMAGE)
        return r

    def compile(self, ctx, cd):
        self._prog = self.compute_program(ctx.gl, "accumulate.comp")
        self._res = program_resources(self._prog)
        self._groups = groups_2d(cd.size, cd.views)
        self.reset()

    def _change_key(self, ctx, data) -> tuple:
        """What invalidates the mean without a Renderer: views and scene state (per view and per
        instance in Python: for hand-driven graphs, not the Renderer's frames)."""
        parts: list = [data.size, data.views]
        if ctx.view_set is not None:
            parts += [np.round(v.pose.matrix(), 9).tobytes() + np.asarray(v.fov.tangents()).tobytes()
                      for v in ctx.view_set]
        if ctx.scene is not None:
            scene = ctx.scene.scene
            parts.append(scene.materials.version)
            parts.append(b"".join(i.transform.tobytes() for i in scene.instances))
            parts.append(tuple((tuple(l.position), tuple(l.direction), tuple(l.color), l.intensity)
                               for l in scene.lights))
        return tuple(parts)

    def _needs_reset(self, ctx, data) -> bool:
        if self._pending_reset or not self.enabled:
            return True
        if not self.auto_reset:
            return False
        if ctx.sample_index is not None:
            return ctx.sample_index == 0
        return self._change_key(ctx, data) != self._key

    def execute(self, ctx, data):
        if self._needs_reset(ctx, data):
            self._count = 0
            self._pending_reset = False
            if self.auto_reset and ctx.sample_index is None:
                self._key = self._change_key(ctx, data)
        add = self.max_frames == 0 or self._count < self.max_frames
        if add:
            self._count += 1
        res = self._res
        res.set("acc_count", self._count)
        res.set("acc_add", add)
        res.texture("src", data[self.SRC])
        res.image("acc_sum", data[self.SUM], read=True, write=True)
        res.image("acc_compensation", data[self.COMPENSATION], read=True, write=True)
        res.image("dst", data[self.DST])
        self._prog.run(*self._groups)
