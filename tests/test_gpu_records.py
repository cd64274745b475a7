"""Buffer records declared once (rayvr.gpu.layout, rayvr.gpu.records): the std430/std140 offsets
against the GL rules, a table edit followed by both the GLSL struct and the numpy dtype, every
real record compiled and read back on the GPU field by field, and the material and view records
packed by the host read by the shaders that use them."""
import numpy as np
import pytest

from rayvr.gpu import records, rng_salts
from rayvr.gpu.bindings import BINDINGS
from rayvr.gpu.layout import Field, Record
from rayvr.gpu.shaders import preprocess

TRICKY = Record("Tricky", (
    Field("a", "vec3"), Field("b", "float"),      # b fills a's fourth slot
    Field("c", "vec2"), Field("d", "vec3"),        # d aligns to 16
    Field("e", "uint"), Field("f", "float", 3),    # std430: stride 4; std140: 16
    Field("g", "vec3", 2),                         # stride 16 in both
    Field("m", "mat3"),                            # three vec3 columns at 16
    Field("h", "ivec2"), Field("k", "uvec4"),
))


def test_std430_offsets_follow_the_gl_rules():
    r = TRICKY
    assert [r.offset(n) for n in "abcdefgmhk"] == [0, 12, 16, 32, 44, 48, 64, 96, 144, 160]
    assert r.size == 176 and r.alignment == 16 and r.dtype.itemsize == 176
    assert r.dtype["g"].shape == (2, 4) and r.dtype["m"].shape == (3, 4) and r.dtype["f"].shape == (3,)


def test_std140_rounds_array_strides_and_struct_alignment_to_16():
    r = Record("Tricky140", TRICKY.fields, layout="std140")
    assert [r.offset(n) for n in "abcdefgmhk"] == [0, 12, 16, 32, 44, 48, 96, 128, 176, 192]
    assert r.dtype["f"].shape == (3, 4) and r.size == 208
    small = Record("Small", (Field("x", "float"),), layout="std140")
    assert small.size == 16 and Record("Small430", small.fields).size == 4


def test_a_table_edit_moves_both_the_glsl_struct_and_the_dtype():
    base = records.MATERIAL_DATA
    fields = list(base.fields)
    sheen = Field("sheen", "vec3", meaning="rgb: sheen colour")
    edited = Record(base.name, [*fields[:1], sheen, Field("sheen_roughness", "float"), *fields[1:]])
    text = edited.glsl()
    lines = [ln.strip() for ln in text.splitlines()]

    def line(decl):
        return next(i for i, ln in enumerate(lines) if ln.startswith(decl))

    assert line("vec4 base_color;") < line("vec3 sheen;") < line("float sheen_roughness;") < line("vec4 emission_cutoff;")
    assert lines[line("vec3 sheen;")].endswith("// rgb: sheen colour")
    assert edited.offset("sheen") == 16 and edited.offset("sheen_roughness") == 28
    assert edited.offset("emission_cutoff") == base.offset("emission_cutoff") + 16
    assert edited.size == base.size + 16 and edited.dtype.itemsize == edited.size
    swapped = Record(base.name, [fields[1], fields[0], *fields[2:]])
    assert swapped.glsl().index("emission_cutoff") < swapped.glsl().index("base_color")
    assert swapped.offset("emission_cutoff") == 0 and swapped.offset("base_color") == 16
    assert swapped.dtype.names[:2] == ("emission_cutoff", "base_color")
    with pytest.raises(ValueError):
        Record("Bad", [Field("x", "float"), Field("x", "vec2")])
    with pytest.raises(ValueError):
        Record("Bad", [Field("x", "double")])


def test_texture_slots_and_salts_have_one_definition():
    from rayvr.materials.material import TEXTURE_SLOTS

    text = records.GLSL_INCLUDES["scene_records.glsl"]()
    for i, slot in enumerate(records.TEXTURE_SLOTS):
        assert f"#define TEX_{slot.upper()} {i}\n" in text
        assert TEXTURE_SLOTS[i] == f"{slot}_texture"
    assert f"vec4 tex[{records.TEXTURE_ROWS * len(records.TEXTURE_SLOTS)}];" in text
    salts = rng_salts.glsl_source()
    assert all(f"const uint RNG_SALT_{n.upper()} = {v}u;" in salts for n, v in rng_salts.RNG_SALTS.items())
    assert len(set(rng_salts.RNG_SALTS.values())) == len(rng_salts.RNG_SALTS)


def test_path_wave_fields_number_the_optional_ones_after_the_fixed():
    text = records.GLSL_INCLUDES["pt_wave_fields.glsl"]()
    assert "#define PTW_ANSWER 9u" in text and "#define PTW_MEDIUM 10u" in text
    assert "#define PTW_FIRST_DIFFUSE (10u + uint(PTW_HAS_MEDIUM))" in text
    assert "#define PTW_NEE_DIFFUSE (13u + uint(PTW_HAS_MEDIUM))" in text
    assert records.path_wave_fields() == 10 and records.path_wave_fields(PTW_HAS_MEDIUM=1, PT_LOBES=1) == 15


# ---- on the GPU -----------------------------------------------------------------------------------
def _scalar(t: str) -> str:
    return {"i": "int", "u": "uint"}.get(t[0], "float") if t not in ("float", "int", "uint") else t


def _components(f: Field) -> tuple[int, int]:
    """(columns, rows) the shader reads of one element of field f."""
    t = f.type
    if t.startswith("mat"):
        return int(t[-1]), int(t[-1])
    return 1, int(t[-1]) if "vec" in t else 1


def _dump_shader(record: Record, include: str = "") -> str:
    """A compute shader writing every field of recs[i] as 32-bit words, in field order, padding left out."""
    body = []
    for f in record.fields:
        cols, rows = _components(f)
        bits = {"float": "floatBitsToUint", "int": "uint", "uint": ""}[_scalar(f.type)]
        for e in range(max(f.count, 1)):
            ref = f"r.{f.name}" + (f"[{e}]" if f.count else "")
            for c in range(cols):
                for k in range(rows):
                    x = ref + (f"[{c}]" if cols > 1 else "") + (f"[{k}]" if rows > 1 else "")
                    body.append(f"    words[o++] = {bits}({x});")
    decl = f'#include "{include}"' if include else record.glsl()
    return f"""{decl}
layout(local_size_x = 1) in;
layout({record.layout}, binding = RAYVR_PASS_SSBO_0) readonly buffer In {{ {record.name} recs[]; }};
layout(std430, binding = RAYVR_PASS_SSBO_1) writeonly buffer Out {{ uint words[]; }};
void main() {{
    uint i = gl_GlobalInvocationID.x;
    {record.name} r = recs[i];
    uint o = i * {sum(_words(f) for f in record.fields)}u;
{chr(10).join(body)}
}}
"""


def _words(f: Field) -> int:
    cols, rows = _components(f)
    return max(f.count, 1) * cols * rows


def _expected_words(record: Record, data: np.ndarray) -> np.ndarray:
    out = []
    for i in range(len(data)):
        for f in record.fields:
            cols, rows = _components(f)
            v = np.asarray(data[f.name][i]).view(np.uint32).reshape(max(f.count, 1), cols, -1)[..., :rows]
            out.append(v.reshape(-1))
    return np.concatenate(out)


def _random_records(record: Record, n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    data = record.zeros(n)
    for name in record.dtype.names:
        field = data[name]
        if field.dtype.base == np.float32:
            field[...] = rng.uniform(-100, 100, field.shape)
        else:
            field[...] = rng.integers(0, 2**31, field.shape).astype(field.dtype.base)
    return data


def _round_trip(gl, tmp_path, record: Record, include: str, data: np.ndarray) -> np.ndarray:
    from rayvr.gpu import compute_program

    src = tmp_path / f"dump_{record.name}_{record.layout}.comp"
    src.write_text(_dump_shader(record, include))
    prog = compute_program(gl, src)
    words = sum(_words(f) for f in record.fields)
    inp, out = gl.buffer(data.tobytes()), gl.buffer(reserve=4 * words * len(data))
    inp.bind_to_storage_buffer(BINDINGS["RAYVR_PASS_SSBO_0"])
    out.bind_to_storage_buffer(BINDINGS["RAYVR_PASS_SSBO_1"])
    prog.run(len(data), 1, 1)
    res = np.frombuffer(out.read(), np.uint32)
    inp.release(), out.release()
    return res


REAL = [(records.MATERIAL_DATA, "scene_records.glsl"), (records.INSTANCE_DATA, "scene_records.glsl"),
        (records.PUNCTUAL_LIGHT, "light_records.glsl"), (records.LIGHT_ENTRY, "light_records.glsl"),
        (records.VIEW_DATA, "view_records.glsl"), (records.PROBE_RAY, "probe_ray_record.glsl"),
        (records.PROBE_VOLUME, "probe_volume_record.glsl"), (records.PROBE_RECORD_TEXELS, "")]


@pytest.mark.parametrize("record,include", REAL, ids=[r.name for r, _ in REAL])
def test_the_generated_struct_compiles_and_the_gpu_reads_the_dtype_field_by_field(gl, tmp_path, record, include):
    data = _random_records(record, 3, seed=len(record.name))
    assert np.array_equal(_round_trip(gl, tmp_path, record, include, data), _expected_words(record, data))


@pytest.mark.parametrize("layout", ["std430", "std140"])
def test_tricky_alignments_match_the_driver(gl, tmp_path, layout):
    record = Record("Tricky", TRICKY.fields, layout=layout)
    data = _random_records(record, 2, seed=7)
    assert np.array_equal(_round_trip(gl, tmp_path, record, "", data), _expected_words(record, data))


def test_an_edited_record_still_matches_the_driver(gl, tmp_path):
    base = records.VIEW_DATA
    edited = Record("EditedView", [Field("scale", "float"), *base.fields[:2], Field("tint", "vec3"),
                                   Field("id", "uint"), *base.fields[2:]])
    data = _random_records(edited, 2, seed=3)
    assert np.array_equal(_round_trip(gl, tmp_path, edited, "", data), _expected_words(edited, data))


def test_generated_includes_compile(gl, tmp_path):
    from rayvr.gpu import compute_program

    src = tmp_path / "includes.comp"
    src.write_text("".join(f'#include "{n}"\n' for n in records.GLSL_INCLUDES) + "#define PTW_HAS_MEDIUM 1\n"
                   "layout(local_size_x = 1) in;\nvoid main() { uint x = PTW_NEE_DIFFUSE + RNG_SALT_GBUFFER"
                   " + uint(TEX_THICKNESS); }\n")
    text = preprocess(src).text
    assert "struct MaterialData {" in text and "struct ViewData {" in text
    compute_program(gl, src)


MATERIAL_PROBE = """
#include "scene.glsl"
layout(local_size_x = 1) in;
layout(std430, binding = RAYVR_PASS_SSBO_0) writeonly buffer Out { vec4 outv[]; };
void main() {
    uint m = gl_GlobalInvocationID.x;
    MaterialParams p = material_factors(m);
    outv[4u * m] = vec4(p.base_color, p.alpha);
    outv[4u * m + 1u] = vec4(p.metallic, p.roughness, p.ior, p.specular);
    outv[4u * m + 2u] = vec4(p.emissive, float(p.effect) + 10.0 * float(p.double_sided));
    outv[4u * m + 3u] = vec4(scene_materials[m].tex[2 * TEX_NORMAL + 1].w, scene_materials[m].tex[2 * TEX_EMISSIVE].w,
                             scene_materials[m].emission_cutoff.a, float(scene_materials[m].flags.y));
}
"""


def test_packed_materials_read_back_through_scene_glsl(gl, tmp_path):
    from rayvr.gpu import compute_program
    from rayvr.materials.effect import Effect
    from rayvr.materials.material import AlphaMode, Material, TextureRef
    from rayvr.scene.gpu_scene import pack_materials

    mats = [Material(base_color=(0.1, 0.2, 0.3, 0.4), metallic=0.25, roughness=0.5, ior=1.7, specular=0.8,
                     emissive=(1.0, 2.0, 3.0), effect=Effect.REFLECTIONS, double_sided=True,
                     alpha_mode=AlphaMode.MASK, alpha_cutoff=0.3, normal_texture=TextureRef(0, strength=0.75),
                     emissive_texture=TextureRef(1)),
            Material(base_color=(0.9, 0.8, 0.7, 1.0), roughness=0.05, effect=Effect.PATH_TRACED)]
    packed = pack_materials(mats, {0: 0, 1: 4})
    assert packed.dtype == records.MATERIAL_DATA.dtype and packed.nbytes == 2 * records.MATERIAL_DATA.size
    src = tmp_path / "materials.comp"
    src.write_text(MATERIAL_PROBE)
    prog = compute_program(gl, src)
    buf, out = gl.buffer(packed.tobytes()), gl.buffer(reserve=2 * 4 * 16)
    buf.bind_to_storage_buffer(BINDINGS["RAYVR_MATERIAL_SSBO"])
    out.bind_to_storage_buffer(BINDINGS["RAYVR_PASS_SSBO_0"])
    prog.run(2, 1, 1)
    res = np.frombuffer(out.read(), np.float32).reshape(2, 4, 4)
    buf.release(), out.release()
    m0, m1 = mats
    assert np.allclose(res[0, 0], m0.base_color) and np.allclose(res[1, 0], m1.base_color)
    assert np.allclose(res[0, 1], (0.25, 0.5, 1.7, 0.8)) and np.allclose(res[1, 1, :2], (1.0, 0.05))
    assert np.allclose(res[0, 2], (*m0.emission, int(Effect.REFLECTIONS) + 10))
    assert np.allclose(res[1, 2, 3], int(Effect.PATH_TRACED))
    assert np.allclose(res[0, 3], (0.75, 4.0, 0.3, int(AlphaMode.MASK)))
    assert res[1, 3, 1] == -1.0   # no emissive texture: layer -1


VIEWS_PROBE = """
#include "views.glsl"
layout(local_size_x = 1) in;
layout(std430, binding = RAYVR_PASS_SSBO_0) writeonly buffer Out { vec4 outv[]; };
void main() {
    uint v = gl_GlobalInvocationID.x;
    outv[4u * v] = views[v].fov_tan;
    outv[4u * v + 1u] = views[v].clip;
    outv[4u * v + 2u] = vec4(views[v].eye.xyz, float(view_global_index(v)));
    outv[4u * v + 3u] = vec4(views[v].inv_view[3].xyz, views[v].proj[2][3]);
}
"""


def test_packed_views_read_back_through_views_glsl(gl, tmp_path):
    from rayvr.gpu import compute_program
    from rayvr.xr.views import Fov, Pose, View, ViewSet

    vs = ViewSet([View(Pose([0.1 * i, 1.5, -2.0]), Fov.symmetric(50 + 10 * i, 1.25), 64, 48, near=0.1 * (i + 1))
                  for i in range(3)])
    vs.first_view_index = 4
    origin = np.array([0.05, 1.0, -1.0])
    data = vs.pack(origin)
    assert len(data) == records.VIEWS_HEADER_BYTES + 3 * records.VIEW_DATA.size
    body = np.frombuffer(data[records.VIEWS_HEADER_BYTES:], records.VIEW_DATA.dtype)
    src = tmp_path / "views.comp"
    src.write_text(VIEWS_PROBE)
    prog = compute_program(gl, src)
    buf, out = gl.buffer(data), gl.buffer(reserve=3 * 4 * 16)
    buf.bind_to_storage_buffer(BINDINGS["RAYVR_VIEWS_SSBO"])
    out.bind_to_storage_buffer(BINDINGS["RAYVR_PASS_SSBO_0"])
    prog.run(3, 1, 1)
    res = np.frombuffer(out.read(), np.float32).reshape(3, 4, 4)
    buf.release(), out.release()
    for i, v in enumerate(vs):
        assert np.allclose(res[i, 0], v.fov.tangents())
        assert np.allclose(res[i, 1], (v.near, v.far, 64, 48))
        assert np.allclose(res[i, 2], (*(v.pose.position - origin), 4 + i))
        assert np.allclose(res[i, 3, :3], v.pose.position - origin)
        assert res[i, 3, 3] == np.float32(v.projection_matrix()[3, 2])   # GLSL [column][row]: row 3, column 2
        assert np.array_equal(body["view_proj"][i], np.float32(vs.matrices(origin)["view_proj"][i].T))
