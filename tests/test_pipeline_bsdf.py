"""The shared BSDF (glsl/bsdf.glsl) and samplers (glsl/sampling.glsl), run on the GPU: sampled
weights equal eval / pdf pointwise, the VNDF estimate of the specular albedo matches uniform
sampling, the Lambert lobe matches albedo / pi, and nothing is NaN/Inf at grazing angles or
roughness 0."""
import numpy as np
import pytest

from rayvr.gpu.shaders import compute_program

SHADER = """
#include "bsdf.glsl"
layout(local_size_x = 64) in;
layout(std430, binding = RAYVR_PASS_SSBO_0) writeonly buffer Out { vec4 result[]; };
uniform float cos_v;
uniform float roughness;
uniform float metallic;
uniform uint mode;   // 0: VNDF sample (weight, eval/pdf), 1: uniform hemisphere (eval/pdf), 2: diffuse eval
void main() {
    uint i = gl_GlobalInvocationID.x;
    Rng rng = rng_init(uvec2(i, 7u), 0u, 0u, 11u);
    BsdfParams p = BsdfParams(vec3(1.0), metallic, roughness);
    vec3 n = vec3(0.0, 0.0, 1.0);
    vec3 v = vec3(sqrt(max(0.0, 1.0 - cos_v * cos_v)), 0.0, cos_v);
    vec4 r = vec4(0.0);
    if (mode == 0u) {
        vec3 l; bool valid;
        vec3 w = bsdf_sample_specular(p, n, v, rng_next2(rng), l, valid);
        float pdf = bsdf_pdf_specular(p, n, v, l);
        vec3 e = bsdf_eval_specular(p, n, v, l);
        r = vec4(w.r, valid && pdf > 0.0 ? e.r / pdf : 0.0, valid ? 1.0 : 0.0, pdf);
    } else if (mode == 1u) {
        vec2 u = rng_next2(rng);
        float z = u.x, s = sqrt(max(0.0, 1.0 - z * z)), phi = 6.283185307 * u.y;
        vec3 l = vec3(s * cos(phi), s * sin(phi), z);
        r = vec4(bsdf_eval_specular(p, n, v, l).r * 6.283185307, 0.0, 0.0, 0.0);
    } else {
        vec2 u = rng_next2(rng);
        vec3 l = basis_from_normal(n) * sample_cosine_hemisphere(u);
        r = vec4(bsdf_eval_diffuse(p, n, v, l).r, l.z, 0.0, 0.0);
    }
    result[i] = r;
}
"""
N = 64 * 512


def specular_albedo(cos_v, roughness, n=1200):
    """Independent quadrature of the white-metal GGX lobe (F = 1): integral of D G2 / (4 n.v) over
    the hemisphere of l, midpoint rule in (cos theta, phi)."""
    a2 = roughness ** 4
    mu = (np.arange(n) + 0.5) / n
    phi = (np.arange(n) + 0.5) / n * 2 * np.pi
    mu, phi = np.meshgrid(mu, phi, indexing="ij")
    s = np.sqrt(1 - mu * mu)
    l = np.stack([s * np.cos(phi), s * np.sin(phi), mu], -1)
    v = np.array([np.sqrt(1 - cos_v ** 2), 0.0, cos_v])
    h = l + v
    h /= np.linalg.norm(h, axis=-1, keepdims=True)
    d = a2 / (np.pi * (h[..., 2] ** 2 * (a2 - 1) + 1) ** 2)
    lam = lambda c: 0.5 * (np.sqrt(1 + a2 * (1 - c * c) / (c * c)) - 1)
    g2 = 1 / (1 + lam(cos_v) + lam(mu))
    return float((d * g2 / (4 * cos_v)).mean() * 2 * np.pi)


@pytest.fixture(scope="module")
def bsdf_program(gl, tmp_path_factory):
    path = tmp_path_factory.mktemp("bsdf") / "bsdf_test.comp"
    path.write_text(SHADER)
    return compute_program(gl, path)


def run(gl, prog, mode, cos_v, roughness, metallic=1.0):
    out = gl.buffer(reserve=16 * N)
    out.bind_to_storage_buffer(16)
    prog["cos_v"], prog["roughness"], prog["metallic"], prog["mode"] = cos_v, roughness, metallic, mode
    prog.run(N // 64)
    return np.frombuffer(out.read(), np.float32).reshape(N, 4)


@pytest.mark.parametrize("roughness", [0.3, 0.6, 1.0])
@pytest.mark.parametrize("cos_v", [0.2, 0.7, 1.0])
def test_vndf_weight_is_eval_over_pdf_and_matches_uniform_sampling(gl, bsdf_program, roughness, cos_v):
    s = run(gl, bsdf_program, 0, cos_v, roughness)
    valid = s[:, 2] > 0
    assert valid.mean() > 0.4        # rough lobes reflect some microfacets below the horizon
    np.testing.assert_allclose(s[valid, 0], s[valid, 1], rtol=2e-3, atol=1e-5)
    assert (s[:, 0] <= 1.0 + 1e-5).all()                 # F <= 1 and G2 <= G1
    assert s[:, 0].mean() == pytest.approx(specular_albedo(cos_v, roughness), rel=0.01)
    u = run(gl, bsdf_program, 1, cos_v, roughness)    # GPU eval, uniform directions: same integral
    assert u[:, 0].mean() == pytest.approx(specular_albedo(cos_v, roughness), rel=0.02 + 0.1 * (roughness < 0.5))


def test_lambert_lobe_is_albedo_over_pi(gl, bsdf_program):
    d = run(gl, bsdf_program, 2, 0.8, 1.0, metallic=0.0)
    np.testing.assert_allclose(d[:, 0], d[:, 1] / np.pi, rtol=1e-5, atol=1e-7)


@pytest.mark.parametrize("roughness", [0.0, 1e-4, 0.02, 1.0])
@pytest.mark.parametrize("cos_v", [0.0, 1e-6, 1e-3, 1.0])
def test_no_nan_or_inf_at_grazing_angles_and_roughness_zero(gl, bsdf_program, roughness, cos_v):
    for mode in (0, 1, 2):
        r = run(gl, bsdf_program, mode, cos_v, roughness)
        assert np.isfinite(r).all(), (mode, roughness, cos_v)


def test_roughness_zero_is_an_exact_mirror(gl, bsdf_program):
    s = run(gl, bsdf_program, 0, 0.6, 0.0)
    assert (s[:, 2] == 1).all() and np.allclose(s[:, 0], 1.0)   # F = 1 for a white metal
