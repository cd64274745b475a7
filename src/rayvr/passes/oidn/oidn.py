"""OIDNDenoise pass: Intel Open Image Denoise 2.x (through `pyoidn`, the `oidn` extra: `pip install
'rayvr[oidn]'`) on the frame's HDR radiance, with the first hit's albedo and normal from the
G-buffer as auxiliary images (noise-free: OIDN's cleanAux).

For offline and reference work, not the real-time path: each frame the pass reads the colour
and its auxiliaries back to host memory, runs OIDN's RT filter per view (OIDN's CPU device; its
wheel also has a CUDA device) and uploads the result. That time is CPU time, outside the GPU
timers (on llvmpipe the profile's wall time after a finish includes it). `enabled` false copies
`color` to `dst` on the GPU instead: `rayvr render --frames N --denoise oidn` denoises only the
last frame.
"""
from __future__ import annotations

import numpy as np

from ...errors import OptionError
from ...gpu.program_resources import program_resources
from ...rendergraph.formats import NUMPY_DTYPES
from ...rendergraph.registry import register_pass
from ...rendergraph.render_pass import Reflection, RenderPass
from ..dispatch import groups_2d
from ..effects import effect_defines, scene_defines
from ..gbuffer import channels

QUALITIES = ("high", "balanced", "fast")
INSTALL = "pip install 'rayvr[oidn]'"


def require_pyoidn(where: str = "denoise='oidn'"):
    """The pyoidn module, or OptionError saying how to install it."""
    try:
        import pyoidn
    except ImportError:
        raise OptionError(f"{where} needs Intel Open Image Denoise (pyoidn), which is not installed: "
                          f"{INSTALL}") from None
    return pyoidn


def read_array(tex) -> np.ndarray:
    """A texture array as float32 (layers, h, w, components), rows bottom-up."""
    data = np.frombuffer(tex.read(), NUMPY_DTYPES[tex.dtype])
    return data.reshape(tex.layers, tex.height, tex.width, tex.components).astype(np.float32)


@register_pass
class OIDNDenoise(RenderPass):
    """`color` (HDR radiance) denoised by OIDN with albedo and normal auxiliaries from the G-buffer
    -> `dst` (rgba32f); see the module docstring. Properties: `quality` ('high', 'balanced',
    'fast'), `enabled`."""

    COLOR, DST = "color", "dst"
    ALBEDO, NORMAL = "albedo", "normal"
    PROPERTIES = {"quality": "high", "enabled": True}
    CHOICES = {"quality": QUALITIES}
    USES_SCENE = True

    def reflect(self, cd):
        r = Reflection()
        channels.add_inputs(r)
        r.add_input(self.COLOR, "HDR radiance to denoise")
        r.add_output(self.DST, "denoised HDR radiance").format("rgba32f")
        r.add_internal(self.ALBEDO, "first-hit albedo (OIDN auxiliary)").format("rgba32f")
        r.add_internal(self.NORMAL, "first-hit shading normal (OIDN auxiliary)").format("rgba32f")
        return r

    def compile(self, ctx, cd):
        self._oidn = require_pyoidn(f"pass {self.name} (OIDNDenoise)")
        self._defines = {**scene_defines(ctx), **effect_defines()}
        self._res = program_resources(self.compute_program(ctx.gl, "oidn_aux.comp", self._defines))
        self._groups = groups_2d(cd.size, cd.views)

    def defines(self) -> dict:
        return dict(getattr(self, "_defines", {}))

    def execute(self, ctx, data):
        res = self._res
        channels.bind_inputs(res, data)
        res.texture("color", data[self.COLOR])
        res.image("aux_albedo", data[self.ALBEDO])
        res.image("aux_normal", data[self.NORMAL])
        res.image("dst", data[self.DST])
        res.set("copy_color", not self.enabled)
        res.prog.run(*self._groups)
        if not self.enabled:
            return
        ctx.barrier()   # the auxiliaries and the colour, visible to the readback
        color = np.clip(np.nan_to_num(read_array(data[self.COLOR])[..., :3], nan=0.0, posinf=0.0), 0.0, None)
        albedo = read_array(data[self.ALBEDO])[..., :3]
        normal = read_array(data[self.NORMAL])[..., :3]
        out = np.ones(color.shape[:3] + (4,), np.float32)
        for v in range(color.shape[0]):
            out[v, ..., :3] = self._oidn.denoise(np.ascontiguousarray(color[v]), np.ascontiguousarray(albedo[v]),
                                                 np.ascontiguousarray(normal[v]), hdr=True, clean_aux=True,
                                                 quality=self.quality)
        data[self.DST].write(out.tobytes())
