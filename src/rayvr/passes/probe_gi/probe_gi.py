"""ProbeGI: a volume of ray-traced irradiance probes, updated once per frame for every view.

After DDGI (Majercik et al. 2019) and Tauray's DDISH-GI (Ikkala et al. 2021). Irradiance is kept
as an octahedral map per probe (6x6 texels inside a one-texel border) with depth moments (mean
and mean squared distance, 14x14) beside it: the moments let a shading point test, by
Chebyshev's inequality, whether a probe can see it, which is what stops light leaking through
thin walls, and give a mirror the share of its direction that leaves the scene (escaped rays
record twice the depth limit, hits at most the limit); spherical harmonics would be cheaper but
carry no visibility. Each update traces
`rays_per_probe` rays per probe (a spherical Fibonacci set under a new random rotation each
update), shades the hits with shadowed direct light and, through the previous update's probes,
the light those surfaces reflect (multi-bounce), and blends the result into the maps by
`hysteresis`. Probes that see mostly back faces are inside geometry and are disabled.

Probe state lives in two sets of internal pins used in turn (the update reads one set and writes
the other, as the samples of neighbouring probes need last update's values); the outputs, which
the shading passes read through glsl/probe_gi.glsl, are this frame's values. The ray work is per
frame: the views only read textures.

Response: after a change of lighting or geometry the light that bounced once reaches 90% of its
new value after ceil(ln 0.1 / ln hysteresis) updates (45 at the default 0.95); light that bounced
more often also waits for the probes it bounced through, at worst ln 0.1 / ln(h + (1 - h) a)
updates for surfaces of albedo a (the closed-box test, albedo 0.6, kept the once-bounced pace).
"""
from __future__ import annotations

import math

from ...errors import OptionError
from ...gpu.program_resources import program_resources
from ...gpu.records import PROBE_RAY
from ...rendergraph.formats import get_format
from ...rendergraph.registry import register_pass
from ...rendergraph.render_pass import Access, Reflection, RenderPass
from ...rendergraph.report import human_bytes
from ..effects import scene_defines
from . import layout as L

MAX_GROUPS_X = 65535
STAGES = ("probe_trace.comp", "probe_shade.comp", "probe_shadow.comp")   # before the blend (probe_update.comp)
RAY_RECORD_BYTES = PROBE_RAY.size   # one ProbeRay (probe_rays.glsl)
# pin -> (output format, history format, texels per probe side). The readers sample the irradiance
# as float16 (half the texture traffic of the lookups every pixel makes); the update blends in
# float32 history, where float16's rounding would stall the hysteresis 1% short of its target.
# Depth moments stay float32: a variance is a difference of two of them.
MAPS = {"irradiance": ("rgba16f", "rgba32f", L.IRRADIANCE_TILE), "depth": ("rg32f", "rg32f", L.DEPTH_TILE),
        "state": ("rg32f", "rg32f", L.STATE_TILE)}


@register_pass
class ProbeGI(RenderPass):
    """Irradiance probes over the scene (see the module docstring).

    Properties: `counts` (probes per axis of the automatic volume over the scene's bounds),
    `volumes` (instead, a list of {"min", "max", "counts"} world boxes, finest first: a point
    takes the first that holds it), `rays_per_probe` (16-1024, one workgroup of that many
    invocations per probe), `hysteresis` (weight of the previous value, [0, 1)), `warmup`
    (updates on the first frame after a compile: half replace, half average), `normal_bias` and
    `view_bias` (lookups move off the surface by these fractions of the probe spacing),
    `visibility` (Chebyshev visibility on/off).

    Outputs: `irradiance`, `depth`, `state` (one-layer atlases) and `volumes` (the
    ProbeVolumes block), read by the lighting passes through `rayvr.passes.probe_gi.inputs`."""

    COUNTS_NONFINITE = True   # scrubs NaN/Inf samples (glsl/nonfinite.glsl)
    USES_SCENE = True
    VOLUMES = "volumes"
    RAYS = "rays"
    PROPERTIES = {"counts": [8, 8, 8], "volumes": [], "rays_per_probe": 128, "hysteresis": 0.95, "warmup": 8,
                  "normal_bias": 0.1, "view_bias": 0.3, "visibility": True}
    WHOLE = {"rays_per_probe": (16, 1024, "rays a probe traces a frame"), "warmup": (0, None, "frames")}

    def validate_property(self, key, value):
        if key == "counts":
            return list(L.parse_counts(value, f"pass {self.name}: property 'counts'"))
        if key == "volumes":
            if not isinstance(value, (list, tuple)):
                raise OptionError(f"pass {self.name}: property 'volumes' must be a list of "
                                  f"{{\"min\", \"max\", \"counts\"}} boxes ([] = one over the scene's bounds)")
            return [L.volume_from_dict(v, f"pass {self.name}: volumes[{i}]").as_dict() for i, v in enumerate(value)]
        value = super().validate_property(key, value)
        if key == "hysteresis" and not 0.0 <= value < 1.0:
            raise OptionError(f"pass {self.name}: property 'hysteresis' must be in [0, 1), got {value!r}")
        if key in ("normal_bias", "view_bias") and value < 0:
            raise OptionError(f"pass {self.name}: property '{key}' must be >= 0, got {value!r}")
        return value

    # -- layout ------------------------------------------------------------------------------
    def volumes_for(self, scene) -> list[L.ProbeVolume]:
        """The probe volumes: the user's list, or one over `scene`'s bounds."""
        if self.volumes:
            return [L.volume_from_dict(v, f"pass {self.name}: volumes") for v in self.volumes]
        bounds = scene.bounds() if scene is not None else [[-1.0] * 3, [1.0] * 3]
        return [L.volume_over_bounds(bounds, self.counts)]

    def probe_count(self) -> int:
        counts = [v["counts"] for v in self.volumes] if self.volumes else [self.counts]
        return sum(math.prod(c) for c in counts)

    def atlas(self) -> L.Atlas:
        return L.Atlas.for_probes(self.probe_count())

    def rays_per_frame(self) -> int:
        """Probe rays per update (each shades its hit with one shadow ray per light sample)."""
        return self.probe_count() * int(self.rays_per_probe)

    @staticmethod
    def history_pin(name: str, k: int) -> str:
        return f"{name}History{k}"

    def reflect(self, cd):
        r = Reflection()
        atlas = self.atlas()
        for name, (fmt, history_fmt, tile) in MAPS.items():
            w, h = atlas.size(tile)
            r.add_output(name, f"probe {name} atlas (one layer for every view)").format(fmt).texture_size(w, h).views(1)
            for k in (0, 1):
                r.add_internal(self.history_pin(name, k), f"probe {name}, kept between updates (used in turn)") \
                    .format(history_fmt).texture_size(w, h).views(1)
        r.add_internal(self.RAYS, "each probe ray's hit, shadow ray and light, handed from stage to stage "
                                  "of the update").buffer(self.rays_per_frame() * RAY_RECORD_BYTES)
        n = len(self.volumes) or 1
        r.add_output(self.VOLUMES, "the probe volumes (ProbeVolumes block, render space)").buffer(L.volume_bytes(n))
        return r

    def compile(self, ctx, cd):
        import moderngl

        self._volumes = self.volumes_for(cd.scene)
        self._atlas = self.atlas()
        self._defines = {**scene_defines(ctx), "PROBE_RAYS": int(self.rays_per_probe), "SHADE_SHADOWS": 1,
                         "LIGHT_SAMPLES": 1}
        # four dispatches per update (probe_rays.glsl): the closest hits; their shading and light samples;
        # the shadow rays; the blend. Each traversal runs in a kernel with no shading beside it, whose
        # registers would cost it occupancy (probe_trace.comp).
        self._stages = {name: program_resources(self.compute_program(ctx.gl, name, self._defines))
                        for name in STAGES}
        self._res = program_resources(self.compute_program(ctx.gl, "probe_update.comp", self._defines))
        n = self._atlas.probes
        self._groups = (min(n, MAX_GROUPS_X), -(-n // MAX_GROUPS_X), 1)
        self._sampler = self.own(ctx.gl.sampler(filter=(moderngl.LINEAR, moderngl.LINEAR), repeat_x=False,
                                                repeat_y=False))
        # each map three times (output and two histories), the ray records and the volumes block
        self._memory = sum(math.prod(self._atlas.size(tile)) * (get_format(fmt).bytes_per_texel
                                                                + 2 * get_format(history_fmt).bytes_per_texel)
                           for fmt, history_fmt, tile in MAPS.values()) + L.volume_bytes(len(self._volumes)) \
            + self.rays_per_frame() * RAY_RECORD_BYTES
        self.reset()

    def reset(self) -> None:
        """Forget the probes: the next frame starts them again (with `warmup` updates)."""
        self._updates = 0

    @property
    def updates(self) -> int:
        """Updates since the last compile or reset."""
        return self._updates

    def defines(self) -> dict:
        d = dict(getattr(self, "_defines", {}))
        if hasattr(self, "_atlas"):
            d.update({"probes": f"{self._atlas.probes} in {len(self._volumes)} volume(s)",
                      "rays_per_frame": self.rays_per_frame(), "probe_memory": human_bytes(self._memory)})
        return d

    def hysteresis_at(self, update: int) -> float:
        """The weight of the previous value in update `update` since the reset: 0 for the first half
        of the warm-up (bounces add up fast), then a running mean until it reaches `hysteresis`."""
        settle = int(self.warmup) // 2
        if update < max(settle, 1):
            return 0.0
        k = update - settle
        return min(float(self.hysteresis), k / (k + 1.0))

    def _programs(self) -> tuple:
        """The update's programs in dispatch order: the stages, then the blend."""
        return (*self._stages.values(), self._res)

    def execute(self, ctx, data):
        origin = ctx.scene.origin if ctx.scene is not None else None
        volumes = data[self.VOLUMES]
        volumes.write(L.pack_volumes(self._volumes, self._atlas, origin, float(self.normal_bias),
                                     float(self.view_bias), bool(self.visibility)))
        for prog in self._programs():   # each binds and sets only what its shader declares
            prog.buffer("ProbeVolumes", volumes)
            prog.buffer("ProbeRays", data[self.RAYS])
            prog.set("probe_frame", int(ctx.frame_index) & 0xFFFFFFFF)
        steps = 1 + (int(self.warmup) if self._updates == 0 else 0)
        for step in range(steps):
            if step:
                ctx.barrier(Access.SAMPLED, Access.IMAGE, Access.STORAGE)
            self._update(ctx, data, step)
        for prog in self._programs():
            for name in MAPS:
                prog.clear_sampler(f"probe_{name}_tex")

    def _update(self, ctx, data, step: int) -> None:
        rotation = tuple(L.random_rotation([ctx.frame_index, step]).T.ravel())
        read, write = self._updates % 2, (self._updates + 1) % 2
        res = self._res
        res.set("probe_hysteresis", self.hysteresis_at(self._updates))
        for name in MAPS:
            res.image(f"{name}_out", data[name])
            res.image(f"{name}_next", data[self.history_pin(name, write)])
        for k, prog in enumerate(self._programs()):
            if k:
                ctx.barrier(Access.STORAGE)
            prog.set("probe_rotation", rotation)
            prog.set("probe_step", step)
            prog.set("probe_history", int(self._updates > 0))
            for name in MAPS:   # the previous update's probes: the shading's bounce, the blend's history
                prog.texture(f"probe_{name}_tex", data[self.history_pin(name, read)], sampler=self._sampler)
            prog.prog.run(*self._groups)
        self._updates += 1
