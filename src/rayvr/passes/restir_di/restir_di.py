"""ReSTIRDI: emission + ray-traced direct light by spatiotemporal reservoir resampling (Bitterli et
al. 2020, "Spatiotemporal reservoir resampling for real-time ray tracing with dynamic direct
lighting"), a drop-in for RTShadows (the same pins and pixels: `rv.graphs.hybrid(direct="restir")`).

Four stages, one compute shader each, over the pixels whose effect is SHADOWS or above (the shadow
list, or the whole image in one-warp tiles, as RTShadows: `dispatch_mode`):
    candidates  `candidates` light samples from the light table, one kept by resampled importance
                sampling with the target p_hat (the luminance of its unshadowed contribution, or with
                `target="cosine"` of Le G cos: no BSDF evaluation);
                with `visibility_reuse` a shadow ray to it, and an occluded one is dropped
    temporal    (`temporal_reuse`) combined with last frame's temporal reservoir where the motion
                vector points (the disocclusion test of glsl/reprojection.glsl), its confidence
                capped at `max_history_m` x `candidates`: next frame's history. Without
                visibility reuse it runs in the candidates' kernel (no traversal there to share
                registers with), saving a pass over the G-buffer and the reservoirs
    spatial     (`spatial_samples` > 0, or `share_views` in a frame of several views) combined with
                the reservoirs of up to `spatial_samples` pixels within `spatial_radius` pixels that
                show the same surface and hold a sample, and in views after the first with view 0's
                reservoir where the pixel's surface point lies in view 0: the views share samples
    shade       emission + the final sample's contribution with its own shadow ray (expected
                transmittance through BLEND surfaces) + the probes' indirect diffuse light when
                the probe inputs are bound: RTShadows' output. With `occluded_weight` < 1 its
                verdict updates the pixel's visibility hints: a bit per light (hashed) that scales
                next frame's target of a light found occluded by that weight, so candidates and
                reuse favour what the pixel sees, unbiased (glsl/restir_di.glsl)
Reservoirs are 16 bytes (gpu/records.py RESERVOIR: the sample's light identity, its weight W and
confidence M); each pixel's temporal reservoir is next frame's history (`history0/1`, used in
turn, with the surfaces they were made at, `surface0/1`). The stages combine reservoirs by
generalized RIS with pairwise MIS of the unshadowed targets (glsl/restir_di.glsl), each target
evaluated at its own pixel's surface: without visibility reuse that is unbiased.

Visibility reuse makes each pixel's reservoirs hold samples it sees, which is unbiased for the
pixel itself (its own chain over frames, for a static occluder) but not for the pixels that reuse
them, whose MIS weights count a neighbour as able to draw every light its unshadowed target has.
Two choices bound that bias: the history is the temporal stage's output, not the spatial one's
(fed back, the spatial bias compounds frame over frame: 10% darker on a hard shadow's surround
in 64 frames, against none), and a neighbour whose reservoir holds no sample (it found no visible
light) is not reused (a fully shadowed neighbour can give none of the light: exact at a single
light's shadow edge). What remains: a pixel is darker where an accepted neighbour within
`spatial_radius` sees other lights but not this pixel's (at worst by the neighbours' share of the
confidence, for that light alone, and not compounded: 4% of the mean on a plane under 60 point
lights with a box's shadows, 32x32, the radius spanning the image), and slightly brighter in the
first frames of a history where a partly lit neighbour happened to find nothing. Light never
passes an occluder: every pixel's light passes its own shadow ray. docs/materials.md has the
details.

History resets on the first frame, on `reset()` and on lighting edits (passes/history.py), as SVGF's.
"""
from __future__ import annotations

from ...errors import OptionError
from ...gpu.program_resources import program_resources
from ...gpu.textures import zero_texture
from ...materials.effect import Effect
from ...rendergraph.registry import register_pass
from ...rendergraph.render_pass import Access, Choice
from ..effects import unused_effect_reason
from ..gbuffer import channels
from ..gbuffer.lighting_pass import GBufferLightingPass, ray_properties
from ..history import HistoryOwner, LightingHistory

MAX_CANDIDATES = 64
MAX_SPATIAL_SAMPLES = 16
MAX_SPATIAL_RADIUS = 256.0
RESERVOIR_FORMAT = "rgba32ui"   # gpu/records.py RESERVOIR, RESERVOIR_SURFACE: one texel each


@register_pass
class ReSTIRDI(HistoryOwner, GBufferLightingPass):
    """Emission + ray-traced direct light by ReSTIR for SHADOWS pixels and above: RTShadows' pins,
    its image at lower noise (see the module docstring).

    Properties: `candidates` (light samples per pixel a frame, 1-64), `target` (the resampling target
    p_hat: "bsdf", the unshadowed contribution f cos Le G; "cosine", Le G cos without the BSDF, cheaper
    and unbiased, noisier on glossy surfaces; "auto", per pixel the first where its specular lobes
    carry over a quarter of the light, else the second), `visibility_reuse` (a shadow
    ray to each pixel's pick before it is shared), `occluded_weight` (in (0, 1]: the target's
    factor for a light the pixel's last shading ray found occluded; 1, no hints), `temporal_reuse`,
    `max_history_m` (the history's
    confidence cap, in frames of candidates), `spatial_samples` (neighbours, 0-16), `spatial_radius`
    (pixels, 1-256), `share_views` (views after the first reuse view 0's reservoirs), and the ray
    passes' `dispatch_mode`, `tile`, `view_group`."""

    COUNTS_RAYS = True   # the candidates' visibility rays and the shading's shadow rays

    SHADER = "restir_shade.comp"
    OUTPUT = "shadowed"
    OUTPUT_DESC = "emission + shadowed direct light (listed pixels only)"
    PIXEL_LIST = "pixels"
    LOWEST_EFFECT = Effect.SHADOWS
    STAGES = ("candidates", "temporal", "spatial")   # then the shading program (SHADER)
    CANDIDATES, REUSED = "reservoirs0", "reservoirs1"
    HISTORY = ("history0", "history1")
    SURFACE = ("surface0", "surface1")
    HINTS = "hints"
    TARGETS = {"bsdf": Choice("p_hat = f cos Le G", 1),   # glsl/restir_di.glsl RESTIR_TARGET
               "cosine": Choice("Le G cos, no BSDF: cheaper, noisier on glossy surfaces", 0),
               "auto": Choice("the BSDF's where the specular lobes carry over a quarter of the light, else the "
                              "cosine", 2)}
    CHOICES = {**GBufferLightingPass.CHOICES, "target": TARGETS}
    PROPERTIES = {"candidates": 8, "target": "bsdf", "visibility_reuse": True, "occluded_weight": 1.0,
                  "temporal_reuse": True, "max_history_m": 20,
                  "spatial_samples": 4, "spatial_radius": 30.0, "share_views": True,
                  **ray_properties(view_group=16)}
    WHOLE = {"candidates": (1, MAX_CANDIDATES, "light samples per pixel a frame"),
             "max_history_m": (1, 1 << 16, "the history's confidence cap, in frames of candidates"),
             "spatial_samples": (0, MAX_SPATIAL_SAMPLES, "neighbours reused per pixel")}

    def __init__(self, props: dict | None = None, **kwargs):
        super().__init__(props, **kwargs)
        self._history = LightingHistory()

    def validate_property(self, key, value):
        value = super().validate_property(key, value)
        if key == "occluded_weight" and not (isinstance(value, (int, float)) and 0.0 < value <= 1.0):
            raise OptionError(f"pass {self.name}: property 'occluded_weight' must be a number in (0, 1] (the target's "
                              f"factor for a light last found occluded; 1: no visibility hints), got {value!r}")
        if key == "spatial_radius" and not 1.0 <= value <= MAX_SPATIAL_RADIUS:
            raise OptionError(f"pass {self.name}: property 'spatial_radius' must be from 1 to {MAX_SPATIAL_RADIUS:g} "
                              f"pixels, got {value!r}")
        return value

    def skip_reason(self, cd):
        return unused_effect_reason(cd, Effect.SHADOWS)

    def gbuffer_channels(self) -> tuple[str, ...]:
        """The lighting channels, and with temporal reuse the motion vectors."""
        return channels.LIGHTING + ("motion",) * bool(self.temporal_reuse)

    def fuses_temporal(self) -> bool:
        """Whether the candidates' kernel does the temporal reuse: where it traces no visibility ray
        (a kernel with a traversal runs at the traversal's occupancy)."""
        return bool(self.temporal_reuse) and not self.visibility_reuse

    def keeps_hints(self) -> bool:
        """Whether the pixels keep visibility hints (`occluded_weight` < 1)."""
        return float(self.occluded_weight) < 1.0

    def stages(self, views: int) -> tuple[str, ...]:
        """The reservoir programs a frame of `views` views runs, in order (the shading follows)."""
        spatial = self.spatial_samples > 0 or (self.share_views and views > 1)
        temporal = self.temporal_reuse and not self.fuses_temporal()
        return tuple(s for s, on in zip(self.STAGES, (True, temporal, spatial)) if on)

    def reflect(self, cd):
        r = super().reflect(cd)
        stages = self.stages(cd.views)
        if not self.fuses_temporal():
            r.add_output(self.CANDIDATES, "each pixel's candidate reservoir (scratch)").format(RESERVOIR_FORMAT)
        if "spatial" in stages:
            r.add_output(self.REUSED, "the spatial stage's reservoirs: the final ones (scratch)").format(RESERVOIR_FORMAT)
        if self.temporal_reuse:
            for name in self.HISTORY:
                r.add_internal(name, "the temporal stage's reservoirs: last frame's are this one's history (used "
                                     "in turn)").format(RESERVOIR_FORMAT)
            for name in self.SURFACE:
                r.add_internal(name, "the surface each history reservoir was made at: depth, normal, effect word, "
                                     "view direction (used in turn)").format(RESERVOIR_FORMAT)
        if self.keeps_hints():
            r.add_internal(self.HINTS, "each pixel's visibility hints: a bit per light (hashed) its last shadow "
                                       "ray found occluded").format("r32ui")
        return r

    def shader_defines(self) -> dict:
        return {"RESTIR_CANDIDATES": int(self.candidates), "RESTIR_TARGET": self.choice_define("target"),
                "RESTIR_VISIBILITY_REUSE": bool(self.visibility_reuse),
                "RESTIR_TEMPORAL": bool(self.temporal_reuse), "RESTIR_FUSED_TEMPORAL": self.fuses_temporal(),
                "RESTIR_HINTS": self.keeps_hints(), "RESTIR_OCCLUDED_WEIGHT": float(self.occluded_weight),
                "RESTIR_MAX_HISTORY": float(self.max_history_m * self.candidates),
                "RESTIR_SPATIAL_SAMPLES": int(self.spatial_samples),
                "RESTIR_SPATIAL_RADIUS": float(self.spatial_radius), "RESTIR_SHARE_VIEWS": bool(self.share_views)}

    def compile(self, ctx, cd):
        super().compile(ctx, cd)   # the shading program, with the probes when they are bound
        self._stages = self.stages(cd.views)
        defines = {k: v for k, v in self._defines.items() if k != "PROBE_GI"}
        self._stage_res = {stage: program_resources(self.compute_program(ctx.gl, f"restir_{stage}.comp", defines))
                           for stage in self._stages}
        self._history.restart()

    def _targets(self, cur: int) -> dict:
        """Each stage's output pin, and the final reservoirs' (key "shade"): the temporal stage (or
        the candidates' with it fused) writes the history, which the spatial stage reads."""
        out = {"candidates": self.HISTORY[cur] if self.fuses_temporal() else self.CANDIDATES,
               "temporal": self.HISTORY[cur], "spatial": self.REUSED}
        out["shade"] = out[self._stages[-1]]
        return out

    def execute(self, ctx, data):
        prev, cur = self._history.begin_frame(ctx)
        if not self._history.valid:   # no surface of an old frame may match; no old verdict stands
            for name in self.SURFACE * bool(self.temporal_reuse) + (self.HINTS,) * self.keeps_hints():
                zero_texture(data[name])
        targets = self._targets(cur)
        source = None
        for stage in self._stages:
            res = self._stage_res[stage]
            self.bind_pixels(res, data)
            if source is not None:
                res.image("reservoirs_in", data[source], read=True, write=False)
            res.image("reservoirs_out", data[targets[stage]])
            if self.keeps_hints():
                res.image("restir_hints", data[self.HINTS], read=True, write=False)
            if stage == "candidates" and self.temporal_reuse:
                res.image("surface_out", data[self.SURFACE[cur]])
            if stage == "temporal" or (stage == "candidates" and self.fuses_temporal()):
                res.image("history_in", data[self.HISTORY[prev]], read=True, write=False)
                res.image("surface_in", data[self.SURFACE[prev]], read=True, write=False)
                res.set("restir_history_valid", self._history.valid)
            self.dispatch(res, data)
            ctx.barrier(Access.IMAGE)
            source = targets[stage]
        self._res.image("reservoirs_in", data[targets["shade"]], read=True, write=False)
        if self.keeps_hints():
            self._res.image("restir_hints", data[self.HINTS])
        super().execute(ctx, data)
        self._history.end_frame()
