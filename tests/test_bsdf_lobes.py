"""The BSDF's lobe sets (glsl/bsdf_lobes.glsl): evaluating the whole BSDF equals evaluating its
diffuse set and its specular set apart, and a set sampled alone is sampled by its own
probabilities, pdf and weight (the diffuse set: the cosine, f / pdf its eval over cos / pi)."""
import numpy as np
import pytest

from rayvr.gpu import compute_program
from rayvr.gpu.bindings import BINDINGS
from rayvr.gpu.program_resources import program_resources
from rayvr.materials import bsdf_tables

SHADER = """
#define SCENE_HAS_TRANSMISSION 1
#include "bsdf.glsl"
layout(local_size_x = 64) in;
layout(std430) writeonly buffer Out { vec4 result[]; };
float h(uint i, uint k) { return float(pcg_hash(i * 16u + k) >> 8) / 16777216.0; }
void main() {
    uint i = gl_GlobalInvocationID.x;
    MaterialParams m;
    m.base_color = vec3(h(i, 1u), h(i, 2u), h(i, 3u)); m.alpha = 1.0;
    m.metallic = h(i, 4u) < 0.3 ? 0.0 : h(i, 4u);
    m.roughness = 0.02 + h(i, 5u);
    m.emissive = vec3(0.0); m.occlusion = 1.0;
    m.transmission = h(i, 6u) < 0.5 ? 0.0 : h(i, 7u);
    m.ior = 1.1 + h(i, 8u); m.specular = h(i, 9u); m.specular_color = vec3(1.0);
    m.volume = h(i, 10u) < 0.5; m.attenuation = vec3(0.0);
    m.effect = 0u; m.alpha_mode = 0u; m.double_sided = false;
    BsdfParams b = bsdf_params(m);
    vec3 n = vec3(0.0, 0.0, 1.0);
    float cv = 0.05 + 0.95 * h(i, 11u);
    vec3 v = vec3(sqrt(1.0 - cv * cv), 0.0, cv);
    bsdf_set_view(b, n, v);
    float z = 1.0 - 2.0 * h(i, 12u), s = sqrt(max(0.0, 1.0 - z * z)), phi = 6.283185307 * h(i, 13u);
    vec3 l = vec3(s * cos(phi), s * sin(phi), z);
    BsdfSample d;
    bool ok = bsdf_sample_lobes(b, n, v, vec3(h(i, 14u), h(i, 15u), 0.5), BSDF_LOBES_DIFFUSE, d);
    result[5u * i] = vec4(bsdf_eval(b, n, v, l), z);
    result[5u * i + 1u] = vec4(bsdf_eval_lobes(b, n, v, l, BSDF_LOBES_DIFFUSE), bsdf_pdf_lobes(b, n, v, l, BSDF_LOBES_DIFFUSE));
    result[5u * i + 2u] = vec4(bsdf_eval_lobes(b, n, v, l, BSDF_LOBES_SPECULAR), float(ok));
    result[5u * i + 3u] = vec4(d.weight, d.pdf);
    result[5u * i + 4u] = vec4(bsdf_eval_lobes(b, n, v, d.l, BSDF_LOBES_DIFFUSE), d.l.z);
}
"""
N = 64 * 256


@pytest.fixture(scope="module")
def lobes(gl, tmp_path_factory):
    path = tmp_path_factory.mktemp("lobes") / "bsdf_lobes.comp"
    path.write_text(SHADER)
    prog = compute_program(gl, path)
    tables = gl.buffer(bsdf_tables.table_floats().tobytes())
    out = gl.buffer(reserve=5 * 16 * N)
    tables.bind_to_storage_buffer(BINDINGS["RAYVR_BSDF_TABLE_SSBO"])
    program_resources(prog).buffer("Out", out)
    prog.run(N // 64)
    gl.memory_barrier()
    res = np.frombuffer(out.read(), np.float32).reshape(N, 5, 4).astype(np.float64)
    tables.release(), out.release()
    return res


def test_the_whole_bsdf_is_its_diffuse_and_specular_sets(lobes):
    total, diffuse, specular = lobes[:, 0, :3], lobes[:, 1, :3], lobes[:, 2, :3]
    above = lobes[:, 0, 3] > 0
    assert np.allclose(total[above], diffuse[above] + specular[above], rtol=1e-5, atol=1e-7)
    assert np.array_equal(total[~above], specular[~above]) and not diffuse[~above].any()
    assert (specular[~above] > 0).any() and (diffuse[above] > 0).any()


def test_the_diffuse_set_samples_and_weighs_the_cosine(lobes):
    z, pdf = lobes[:, 0, 3], lobes[:, 1, 3]
    scatters = lobes[:, 2, 3] == 1
    assert scatters.mean() > 0.2
    above = (z > 0) & scatters
    assert np.allclose(pdf[above], z[above] / np.pi, rtol=1e-5) and not pdf[z < 0].any()
    weight, spdf, f, lz = lobes[scatters, 3, :3], lobes[scatters, 3, 3], lobes[scatters, 4, :3], lobes[scatters, 4, 3]
    assert (lz >= 0).all() and np.allclose(spdf, lz / np.pi, rtol=1e-5)
    good = spdf > 1e-6
    assert np.allclose(weight[good], f[good] / spdf[good, None], rtol=1e-4, atol=1e-7)
