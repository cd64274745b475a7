"""trace_transmittance through stacked alphaMode BLEND layers: exact (RQ_BLEND_ROULETTE 0) it is the
product of (1 - alpha) in every draw; with Russian roulette below a threshold its mean over many
paths' draws is that product (float64) within the draws' noise, and the rays end sooner; an opaque
surface anywhere on the ray, before, between or behind the layers, gives 0 in every draw."""
import numpy as np
import pytest

from rayvr.gpu import compute_program, get_context
from rayvr.gpu.bindings import BINDINGS
from rayvr.scene import GpuScene, Scene
from rayvr.scene.builtin import lambert, quad_mesh
from rayvr.scene.model import Environment

ALPHAS = (0.3, 0.55, 0.8, 0.2, 0.65, 0.4)
DRAWS = 8192
KERNEL = """
#include "ray_query.glsl"
layout(local_size_x = 64) in;
layout(std430, binding = RAYVR_PASS_SSBO_0) writeonly buffer Out { vec2 result[]; };
void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= uint(DRAWS)) return;
    rq_blend_begin(rng_init(uvec2(i % 97u, i / 97u), 0u, 0u, 11u));   // a path of its own per invocation
    float t = trace_transmittance(vec3(0.1, 0.2, 0.0), vec3(0.0, 0.0, 1.0), 20.0);
    result[i] = vec2(t, float(rq_stat_triangles));
}
"""


def layers_scene(opaque_z=None, layout="bvh4"):
    """BLEND quads of ALPHAS at z = 1, 2, ... over the ray's path, and an opaque one at opaque_z."""
    s = Scene("layers")
    s.environment = Environment((0.0, 0.0, 0.0), name="black")
    s.bvh_layout = layout
    for k, a in enumerate(ALPHAS):
        m = lambert(f"Layer{k}", (0.5, 0.5, 0.5))
        m.base_color, m.alpha_mode = (0.5, 0.5, 0.5, a), "BLEND"
        s.add_material(m)
        s.add_object(f"L{k}", *quad_mesh([[-1, -1, k + 1], [1, -1, k + 1], [1, 1, k + 1], [-1, 1, k + 1]]), k)
    if opaque_z is not None:
        s.add_material(lambert("Wall", (0.5, 0.5, 0.5)))
        z = opaque_z
        s.add_object("Wall", *quad_mesh([[-1, -1, z], [1, -1, z], [1, 1, z], [-1, 1, z]]), len(ALPHAS))
    return s


def draws(gl, tmp_path, scene, roulette):
    gs = GpuScene(get_context(), scene)
    src = tmp_path / "transmittance.comp"
    src.write_text(KERNEL)
    prog = compute_program(gl, src, {**gs.defines(), "RQ_BLEND_ROULETTE": repr(float(roulette)), "RQ_STATS": 1,
                                     "DRAWS": DRAWS})
    out = gl.buffer(reserve=DRAWS * 8)
    gs.bind()
    out.bind_to_storage_buffer(BINDINGS["RAYVR_PASS_SSBO_0"])
    prog.run(DRAWS // 64)
    r = np.frombuffer(out.read(), np.float32).reshape(-1, 2).astype(np.float64)
    out.release(), gs.release()
    return r[:, 0], r[:, 1]


@pytest.mark.parametrize("layout", ["bvh4", "bvh8"])
def test_roulette_keeps_the_mean_transmittance_and_ends_rays_sooner(gl, tmp_path, layout):
    exact = float(np.prod(1.0 - np.array(ALPHAS, np.float64)))
    t0, tests0 = draws(gl, tmp_path, layers_scene(layout=layout), 0.0)
    np.testing.assert_allclose(t0, exact, rtol=1e-5)                      # no random decision
    for roulette in (0.05, 0.3, 1.0):
        t, tests = draws(gl, tmp_path, layers_scene(layout=layout), roulette)
        assert set(np.unique(t)) <= {0.0} | set(np.unique(t[t > 0])) and (t[t > 0] >= min(roulette, exact) * 0.999).all()
        noise = t.std() / np.sqrt(DRAWS)
        assert abs(t.mean() - exact) <= 5 * noise + 1e-6, (roulette, t.mean(), exact, noise)
        assert (t == 0).any() and tests.mean() < tests0.mean(), "roulette ends some rays before the last layer"


@pytest.mark.parametrize("roulette", [0.0, 0.3, 1.0])
@pytest.mark.parametrize("opaque_z", [0.5, 3.5, len(ALPHAS) + 0.5])
def test_an_opaque_surface_anywhere_blocks_every_draw(gl, tmp_path, roulette, opaque_z):
    t, _ = draws(gl, tmp_path, layers_scene(opaque_z), roulette)
    np.testing.assert_array_equal(t, 0.0)
