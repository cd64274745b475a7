"""RTReflections: mirror and glossy reflections, only where a material asks for them."""
from __future__ import annotations

from ...gpu.program_resources import program_resources
from ...gpu.records import PROBE_RECORD_TEXELS
from ...gpu.rng_salts import RNG_SALTS
from ...materials.effect import Effect
from ...rendergraph.registry import register_pass
from ...rendergraph.render_pass import Access
from ..effects import scene_transmits, unused_effect_reason
from ..gbuffer.lighting_pass import GBufferLightingPass, ray_properties
from ..probe_gi import inputs as probe_inputs

RECORD_BYTES = PROBE_RECORD_TEXELS.size   # one deferred probe lookup (glsl/probe_records.glsl)
MAX_REFLECTION_BOUNCES = 64   # `max_bounces` (and `rayvr render --max-bounces`)


@register_pass
class RTReflections(GBufferLightingPass):
    """Mirror and glossy (GGX VNDF) reflections for the pixels whose effect is REFLECTIONS or above,
    `max_bounces` reflections deep; reflected hits are shaded with ray-traced shadows. Where the
    scene transmits, a path may also pass `transmission_bounces` more surfaces through their
    transmission (default 1: the far wall of a thin-walled glass object, so that what lies behind
    it shows); those bounces are compiled in only then. Emitters and the
    environment that a glossy ray finds are weighed against the direct-light passes' light samples
    by the power heuristic (those weigh the specular lobes of REFLECTIONS pixels the other way:
    shading.glsl shade_direct_mis), so near-mirrors reflect the sky. The output is the
    reflected radiance already weighted by the specular BSDF (the composite adds it).
    Runs over the whole image in 8x4 tiles unless a material is PATH_TRACED (benchmarks/RESULTS.md
    compares the tile shapes and the list).

    With the probe inputs bound, the hits' probe lookups (indirect diffuse light, and the glossy
    fallback where MAX_BOUNCES stops a path) are deferred: the traversal kernel stores a record per
    pixel, view and bounce in two scratch outputs `probeHits` and `probeFactors` (rgba32ui, views x
    bounces() layers, 32 bytes a record: glsl/probe_records.glsl), and a second program
    (rt_reflections_probes.comp), dispatched over the same pixels after a barrier, looks them up
    and adds them to the output. The lookup's registers in the traversal kernel cost it its
    occupancy (benchmarks/RESULTS.md). Graphs without probes allocate no records."""

    SHADER = "rt_reflections.comp"
    PROBE_SHADER = "rt_reflections_probes.comp"
    OUTPUT = "reflection"
    OUTPUT_DESC = "specular-weighted reflected radiance (listed pixels only)"
    PROBE_HITS, PROBE_FACTORS = "probeHits", "probeFactors"
    PIXEL_LIST = "pixels"
    COUNTS_RAYS = True
    LOWEST_EFFECT = Effect.REFLECTIONS
    FILL_LOBE = "specular"
    SALT = RNG_SALTS["rt_reflections"]
    # defer_probes False looks the probes up in the traversal kernel, one dispatch and no records:
    # the reference tests/test_reflection_probe_records.py compares the deferred lookups with.
    PROPERTIES = {"max_bounces": 1, "transmission_bounces": 1, "light_samples": 1, **ray_properties(),
                  "defer_probes": True}
    WHOLE = {**GBufferLightingPass.WHOLE, "max_bounces": (1, MAX_REFLECTION_BOUNCES, "reflection bounces"),
             "transmission_bounces": (0, MAX_REFLECTION_BOUNCES, "bounces through transmission")}

    def skip_reason(self, cd):
        return unused_effect_reason(cd, Effect.REFLECTIONS)

    def bounces(self, scene=None) -> int:
        """Vertices a path may reach: `max_bounces`, plus `transmission_bounces` where `scene`
        transmits (scene_transmits)."""
        return int(self.max_bounces) + (int(self.transmission_bounces) if scene_transmits(scene) else 0)

    def compile(self, ctx, cd):
        self._scene = cd.scene   # shader_defines' bounces
        super().compile(ctx, cd)
        self._lookup = None
        if self._defines.get("PROBE_RECORDS"):
            defines = {k: v for k, v in self._defines.items() if k != "PROBE_RECORDS"}
            self._lookup = program_resources(self.compute_program(ctx.gl, self.PROBE_SHADER,
                                                                  {**defines, "PROBE_GI": 1}))

    def shader_defines(self):
        return {"MAX_BOUNCES": self.bounces(getattr(self, "_scene", None)), "REFLECTION_BOUNCES": int(self.max_bounces),
                "LIGHT_SAMPLES": max(1, int(self.light_samples)), "SHADE_SHADOWS": 1}

    def defers_probes(self, cd) -> bool:
        """Whether the probe lookups run in the second dispatch (probe inputs bound and read)."""
        return bool(self.defer_probes) and probe_inputs.bound(cd) and self.probes_unused(cd) is None

    def record_bytes(self, size, views: int, scene=None) -> int:
        """The probe records' memory at a per-view `size` (both scratch outputs) for `scene`."""
        return int(size[0]) * int(size[1]) * int(views) * self.bounces(scene) * RECORD_BYTES

    def reflect(self, cd):
        r = super().reflect(cd)
        if self.defers_probes(cd):
            layers = cd.views * self.bounces(cd.scene)
            r.add_output(self.PROBE_HITS, "probe lookups deferred from the traversal (scratch): hit position "
                                          "(float bits), octahedral normal; a layer per bounce and view"
                         ).format("rgba32ui").views(layers)
            r.add_output(self.PROBE_FACTORS, "probe lookups deferred from the traversal (scratch): octahedral "
                                             "v, float16 throughput x diffuse and x specular albedo"
                         ).format("rgba32ui").views(layers)
        return r

    def probe_defines(self, cd):
        return {"PROBE_RECORDS": 1} if self.defers_probes(cd) else super().probe_defines(cd)

    def defines(self) -> dict:
        d = super().defines()
        if getattr(self, "_lookup", None) is not None:
            d["probe_lookups"] = f"deferred ({self.PROBE_SHADER}, PROBE_GI=1)"
        return d

    def execute(self, ctx, data):
        if self._lookup is None:
            super().execute(ctx, data)
            return
        res = self._res
        self.set_uniforms(res)
        self.bind_pixels(res, data)
        res.image("dst", data[self.OUTPUT])
        res.image("probe_hits", data[self.PROBE_HITS])
        res.image("probe_factors", data[self.PROBE_FACTORS])
        self.dispatch(res, data)
        ctx.barrier(Access.IMAGE)   # the records and the radiance, for the lookups' loads
        look = self._lookup
        self.bind_pixels(look, data)
        look.image("dst", data[self.OUTPUT], read=True, write=True)
        look.image("probe_hits", data[self.PROBE_HITS], read=True, write=False)
        look.image("probe_factors", data[self.PROBE_FACTORS], read=True, write=False)
        probe_inputs.bind(look, data, self._probe_sampler)
        self.dispatch(look, data)
        probe_inputs.unbind(look)
        self._fill.run(ctx, data)
