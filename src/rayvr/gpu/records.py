"""The records the host writes into buffers and the shaders read, each declared once as a
`layout.Record`: its GLSL struct is a generated include (`GLSL_INCLUDES`, resolved by
`shaders.preprocess`), its numpy dtype packs it on the host.

  scene_records.glsl   MaterialData (glsl/scene.glsl's material table), InstanceData, the TEX_*
                       ids of TEXTURE_SLOTS
  light_records.glsl   PunctualLight, LightEntry (glsl/lights.glsl)
  view_records.glsl    ViewData (glsl/views.glsl)
  probe_ray_record.glsl  ProbeRay (passes/probe_gi/probe_rays.glsl)
  probe_volume_record.glsl  ProbeVolume (glsl/probe_gi.glsl)
  pt_wave_fields.glsl  the PTW_* field numbers of the wavefront path state (PATH_WAVE_FIELDS)
  rng_salts.glsl       the random streams' salts (rng_salts.RNG_SALTS)
  reservoir_records.glsl  Reservoir, ReservoirSurface: ReSTIR DI's texels (glsl/reservoir.glsl)

The probe records a reflection pass defers (glsl/probe_records.glsl) are PROBE_RECORD_TEXELS.
"""
from __future__ import annotations

import dataclasses

from . import rng_salts
from .layout import Field, Record

# ---- scene ---------------------------------------------------------------------------------------
# A material's textures, in the order of MaterialData.tex (TEX_<SLOT> ids in GLSL); the Material
# field of slot s is f"{s}_texture".
TEXTURE_SLOTS = ("base_color", "metallic_roughness", "normal", "occlusion", "emissive", "transmission",
                 "specular", "specular_color", "thickness")
TEXTURE_ROWS = 2   # vec4 rows per slot: (m00, m01, m02, layer or -1), (m10, m11, m12, scale/strength)

MATERIAL_DATA = Record("MaterialData", (
    Field("base_color", "vec4"),
    Field("emission_cutoff", "vec4", meaning="rgb: emissive * emissive_strength, a: alpha cutoff"),
    Field("pbr", "vec4", meaning="metallic, roughness, transmission, ior (1e30: Fresnel 1 everywhere)"),
    Field("flags", "uvec4", meaning="x: Effect id, y: alpha mode, z: double sided, w: a volume (thickness > 0)"),
    Field("specular", "vec4", meaning="rgb: specular colour (F0 tint), a: specular factor (KHR_materials_specular)"),
    Field("volume", "vec4", meaning="rgb: attenuation colour, a: attenuation distance (KHR_materials_volume)"),
    Field("extra", "vec4", meaning="x: thickness"),
    Field("tex", "vec4", TEXTURE_ROWS * len(TEXTURE_SLOTS),
          meaning="per slot: (m00, m01, m02, layer or -1), (m10, m11, m12, scale/strength)"),
), meaning="One material of the scene's table (rayvr.scene.gpu_scene.pack_materials).")

INSTANCE_DATA = Record("InstanceData", (
    Field("to_render", "vec4", 3, meaning="rows of the 3x4 object -> render space matrix"),
    Field("to_object", "vec4", 3, meaning="rows of its inverse"),
    Field("info", "uvec4", meaning="x: mesh, y: its BLAS root node, z: its first scene triangle"),
), meaning="One instance (rayvr.scene.gpu_frame).")

# ---- lights ---------------------------------------------------------------------------------------
PUNCTUAL_LIGHT = Record("PunctualLight", (
    Field("position_type", "vec4", meaning="anchor-space position (scene.glsl render_shift), type (uint bits)"),
    Field("direction_range", "vec4", meaning="direction the light points, range (0: infinite)"),
    Field("intensity", "vec4", meaning="colour * intensity"),
    Field("cone", "vec4", meaning="cos(outer), 1 / (cos(inner) - cos(outer))"),
), meaning="One punctual light (rayvr.scene.gpu_frame).")
PUNCTUAL_LIGHTS_HEADER_BYTES = 16   # uvec4 punctual_info before the PunctualLight array

LIGHT_ENTRY = Record("LightEntry", (
    Field("ids", "uvec4", meaning="kind, index within the kind, alias entry"),
    Field("select", "vec4", meaning="alias threshold, selection probability, the punctual lights' summed "
                                    "probability (on a punctual entry)"),
), meaning="One entry of the light table (rayvr.scene.light_table.LightTable.packed).")
LIGHT_TABLE_HEADER_BYTES = 16   # vec4 light_table_info before the LightEntry array

# ---- views ---------------------------------------------------------------------------------------
VIEW_DATA = Record("ViewData", (
    Field("view", "mat4", meaning="render space -> eye space"),
    Field("proj", "mat4", meaning="eye -> clip (OpenGL clip, z in [-1,1]; reversed-Z when flagged)"),
    Field("view_proj", "mat4", meaning="render space -> clip"),
    Field("inv_view", "mat4", meaning="eye -> render space"),
    Field("prev_view_proj", "mat4", meaning="last frame's view_proj, in this frame's render space (motion vectors)"),
    Field("eye", "vec4", meaning="xyz eye position in render space"),
    Field("fov_tan", "vec4", meaning="tan(angleLeft), tan(angleRight), tan(angleDown), tan(angleUp): left/down < 0"),
    Field("clip", "vec4", meaning="near, far, width px, height px"),
    Field("jitter", "vec4", meaning="xy sub-pixel jitter in pixels (TAA), z the view's index in its whole frame "
                                    "(uint bits: random streams follow it, so a frame split by views draws the "
                                    "same numbers), w unused"),
    Field("gaze", "vec4", meaning="xy the tangents (x right, y up, as fov_tan) of the eye's gaze direction in eye "
                                  "space, z 1 when an eye tracker gave it (else 0 and xy the image centre's), w unused"),
), meaning="One view of a frame (rayvr.xr.views.ViewSet.pack); positions in render space.")
VIEWS_HEADER_BYTES = 16   # uvec4 frame_info before the ViewData array

# ---- probes --------------------------------------------------------------------------------------
PROBE_RAY = Record("ProbeRay", (
    Field("hit", "vec4", meaning="trace: t, barycentrics, kind (uint bits: PROBE_RAY_*); shade: the shadow "
                                 "ray's origin, tmax"),
    Field("ids", "uvec4", meaning="trace: instance, primitive; shade: the shadow ray's direction (float bits), kind"),
    Field("radiance", "vec4", meaning="shade: rgb what needs no ray (a miss's environment, the bounce); a: "
                                      "distance for the depth moments"),
    Field("direct", "vec4", meaning="shade: rgb the light sample's unshadowed contribution (0: no shadow ray), "
                                    "a the instance its shadow ray may skip + 1 (0: none; glsl/exit_instance.glsl); "
                                    "shadow: a, its visibility"),
), meaning="What one probe ray's update stage hands on to the next (probe_rays.glsl).")

PROBE_VOLUME = Record("ProbeVolume", (
    Field("origin", "vec4", meaning="xyz: render-space position of probe (0, 0, 0); w: normal bias (scene units)"),
    Field("spacing", "vec4", meaning="xyz: between neighbouring probes; w: view bias"),
    Field("counts", "uvec4", meaning="xyz: probes per axis; w: atlas index of its first probe"),
    Field("lo", "vec4", meaning="xyz: the box it serves (render space); w: depth moments' maximum distance"),
    Field("hi", "vec4"),
), meaning="One probe volume (rayvr.passes.probe_gi.layout.pack_volumes).")
PROBE_VOLUMES_HEADER_BYTES = 16   # uvec4 probe_info before the ProbeVolume array

# A deferred probe lookup (glsl/probe_records.glsl): two rgba32ui texels, a layer per view and bounce.
PROBE_RECORD_TEXELS = Record("ProbeRecordTexels", (
    Field("hit", "uvec4", meaning="position float bits, octahedral shading normal"),
    Field("factors", "uvec4", meaning="octahedral v, float16 diffuse and glossy factors"),
))


# ---- ReSTIR DI (passes/restir_di): one rgba32ui texel each, a layer per view -------------------------
RESERVOIR = Record("Reservoir", (
    Field("light", "uint", meaning="the sample's light: kind << 30 | index (lights.glsl light_id; ~0u: none)"),
    Field("point", "uint", meaning="the point on it: rounded random numbers or an octahedral direction"),
    Field("weight", "float", meaning="W, the sample's unbiased contribution weight in its light's measure"),
    Field("confidence", "float", meaning="M, the candidates it stands for"),
), meaning="A reservoir of one light sample (ReSTIR DI).")
RESERVOIR_SURFACE = Record("ReservoirSurface", (
    Field("depth", "float", meaning="linear eye depth (0: not a pixel the pass lit)"),
    Field("normal", "uint", meaning="shading normal, octahedral snorm16 x2"),
    Field("word", "uint", meaning="the G-buffer's effect word"),
    Field("view_dir", "uint", meaning="towards the eye, octahedral snorm16 x2"),
), meaning="The surface a history reservoir was made at (ReSTIR DI's reprojection).")


# ---- the wavefront path state --------------------------------------------------------------------
@dataclasses.dataclass(frozen=True)
class WaveField:
    """One uvec4 field of the wavefront path state; `when`: the #define that must be 1 for it to exist."""

    name: str
    meaning: str
    when: str = ""


# In order: fields the shade kernel keeps for itself, then what the trace kernel reads and answers.
PATH_WAVE_FIELDS = (
    WaveField("RADIANCE", "path radiance, rays' pdf"),
    WaveField("BETA", "path beta, rays' cone width"),
    WaveField("NEE", "rays' light sample contribution, rng_word"),
    WaveField("POS", "rays' vertex, flags (both kernels)"),
    WaveField("DIR", "BSDF ray direction (both kernels), rays' cone spread"),
    WaveField("NG", "trace kernel: rays' geometric normal, shadow distance (< 0: none)"),
    WaveField("NEE_DIR", "trace kernel: shadow ray direction"),
    WaveField("EMITTED", "what the first vertex emits towards the eye (or the background)"),
    WaveField("HIT", "trace kernel's answer: t, barycentrics, instance"),
    WaveField("ANSWER", "trace kernel's answer: primitive, PTW_FOUND | PTW_OCCLUDED | PTW_SHADOW, BLEND rays "
                        "traced so far"),
    WaveField("MEDIUM", "path medium", when="PTW_HAS_MEDIUM"),
    WaveField("FIRST_DIFFUSE", "lobe split: the diffuse part of the first vertex's light sample", when="PT_LOBES"),
    WaveField("FIRST_TOTAL", "lobe split: all that sample added", when="PT_LOBES"),
    WaveField("SHARE", "lobe split: the diffuse share of the first BSDF sample's weight", when="PT_LOBES"),
    WaveField("NEE_DIFFUSE", "lobe split: rays' light sample contribution, its diffuse part", when="PT_LOBES"),
)
PATH_WAVE_FIELD_BYTES = 16


def path_wave_fields(**defines) -> int:
    """Fields of the wavefront path state under `defines` (e.g. PTW_HAS_MEDIUM=1, PT_LOBES=0)."""
    return sum(1 for f in PATH_WAVE_FIELDS if not f.when or defines.get(f.when))


def _pt_wave_glsl() -> str:
    lines = [_header("PATH_WAVE_FIELDS")]
    # a field's number: the fields before it that are always there or share its condition, plus
    # uint(<define>) for each earlier one under another condition
    for i, f in enumerate(PATH_WAVE_FIELDS):
        before = PATH_WAVE_FIELDS[:i]
        fixed = sum(1 for b in before if not b.when or b.when == f.when)
        others = [f"uint({b.when})" for b in before if b.when and b.when != f.when]
        number = f"({' + '.join([f'{fixed}u', *others])})" if others else f"{fixed}u"
        lines.append(f"#define PTW_{f.name} {number}   // {f.meaning}")
    return "\n".join(lines) + "\n"


# ---- the generated includes ----------------------------------------------------------------------
def _header(*tables: str) -> str:
    return f"// Generated from rayvr/gpu/records.py {', '.join(tables)}: edit the table, not this text."


def _scene_glsl() -> str:
    slots = [f"#define TEX_{s.upper()} {i}" for i, s in enumerate(TEXTURE_SLOTS)]
    return "\n".join([_header("TEXTURE_SLOTS", "MATERIAL_DATA", "INSTANCE_DATA"),
                      f"// material texture slots ({TEXTURE_ROWS} vec4 rows each in MaterialData.tex)",
                      *slots, "", INSTANCE_DATA.glsl(), "", MATERIAL_DATA.glsl(), ""])


def _lights_glsl() -> str:
    return "\n".join([_header("PUNCTUAL_LIGHT", "LIGHT_ENTRY"), PUNCTUAL_LIGHT.glsl(), "", LIGHT_ENTRY.glsl(), ""])


def _views_glsl() -> str:
    return "\n".join([_header("VIEW_DATA"), VIEW_DATA.glsl(), ""])


def _probe_ray_glsl() -> str:
    return "\n".join([_header("PROBE_RAY"), PROBE_RAY.glsl(), ""])


def _probe_volume_glsl() -> str:
    return "\n".join([_header("PROBE_VOLUME"), PROBE_VOLUME.glsl(), ""])


def _reservoir_glsl() -> str:
    return "\n".join([_header("RESERVOIR", "RESERVOIR_SURFACE"), RESERVOIR.glsl(), "", RESERVOIR_SURFACE.glsl(), ""])


GLSL_INCLUDES = {"scene_records.glsl": _scene_glsl, "light_records.glsl": _lights_glsl, "view_records.glsl": _views_glsl,
                 "probe_ray_record.glsl": _probe_ray_glsl, "probe_volume_record.glsl": _probe_volume_glsl,
                 "pt_wave_fields.glsl": _pt_wave_glsl, "rng_salts.glsl": rng_salts.glsl_source,
                 "reservoir_records.glsl": _reservoir_glsl}
