"""One SVGF a-trous iteration (passes/svgf/svgf_atrous.comp) against a float64 numpy reference
of the filter (Schied et al. 2017, section 4.3: 5x5 B3 kernel, or the 3x3 kernel of `kernel` 3,
depth / normal / luminance weights, the 3x3-blurred variance, the variance filtered with the
squared weights), on a synthetic 13x11 x 2-view key and illumination: steps 1, 2, 4
and 8 (taps fetched, most outside the view), with and without the specular lobe (rgba32ui float16
pairs, rgba16f), and the colour history it writes. The depth gradient the iteration reads is the
one the variance stage (svgf_variance.comp) writes once a frame from the key; the reference
derives it from the key in float64 as each iteration did before."""
import numpy as np
import pytest

from rayvr.gpu.program_resources import program_resources
from rayvr.passes import SVGF
from rayvr.passes.effects import effect_defines

W, H, L = 13, 11, 2          # partial workgroups in x and y, two views
PHI = {"svgf_phi_color": 4.0, "svgf_phi_normal": 16.0, "svgf_phi_depth": 1.0}
KERNELS = {5: (3 / 8, 1 / 4, 1 / 16), 3: (1 / 2, 1 / 4)}
LUMA = np.array([0.2126, 0.7152, 0.0722])


def pack_normals(n):
    """oct_pack_snorm16 (glsl/octahedral.glsl): octahedral, snorm16 x (low), y (high)."""
    n = n / np.abs(n).sum(-1, keepdims=True)
    sign = np.where(n[..., :2] >= 0, 1.0, -1.0)
    e = np.where(n[..., 2:] >= 0, n[..., :2], (1 - np.abs(n[..., 1::-1])) * sign)
    q = np.round(np.clip(e, -1, 1) * 32767).astype(np.int16).view(np.uint16).astype(np.uint32)
    return q[..., 0] | (q[..., 1] << 16)


def unpack_normals(bits):
    """oct_unpack_snorm16 in float64."""
    e = np.stack([(bits & 0xFFFF).astype(np.uint16).view(np.int16),
                  (bits >> 16).astype(np.uint16).view(np.int16)], -1) / 32767.0
    e = np.clip(e, -1, 1)
    n = np.concatenate([e, 1 - np.abs(e).sum(-1, keepdims=True)], -1)
    sign = np.where(n[..., :2] >= 0, 1.0, -1.0)
    n[..., :2] = np.where(n[..., 2:] < 0, (1 - np.abs(n[..., 1::-1])) * sign, n[..., :2])
    return n / np.linalg.norm(n, axis=-1, keepdims=True)


UNTOUCHED = 0.75   # what the output texture holds before a dispatch (a float16 value)


def half_pairs(a, b):
    return a.astype(np.float16).view(np.uint16).astype(np.uint32) | (b.astype(np.float16).view(np.uint16).astype(np.uint32) << 16)


def unhalf(u):
    return np.stack([(u & 0xFFFF).astype(np.uint16).view(np.float16),
                     (u >> 16).astype(np.uint16).view(np.float16)], -1).astype(np.float64)


def synthetic():
    """Two planes meeting at a depth step (x >= 7), their own normals with noise, holes where
    nothing was drawn; illumination brighter on one plane, noisy, with its variance."""
    rng = np.random.default_rng(7)
    y, x = np.mgrid[0:H, 0:W].astype(np.float64)
    right = x >= 7
    depth = 2.0 + 0.05 * x + 0.03 * y + 0.6 * right
    depth = np.broadcast_to(depth, (L, H, W)) * (1.0 + 0.1 * np.arange(L))[:, None, None]
    depth = np.where(rng.random((L, H, W)) < 0.12, 0.0, depth).astype(np.float32)
    n = np.where(right[..., None], [0.6, 0.0, 0.8], [0.0, 0.1, 1.0]) + 0.05 * rng.normal(size=(L, H, W, 3))
    key = np.stack([depth.view(np.uint32), pack_normals(n)], -1).astype(np.uint32)
    level = np.where(right, 3.0, 1.0)[None, ..., None]
    d = np.concatenate([level * rng.random((L, H, W, 3)), 0.5 * rng.random((L, H, W, 1))], -1).astype(np.float16)
    s = np.concatenate([rng.random((L, H, W, 3)), 0.2 * rng.random((L, H, W, 1))], -1).astype(np.float16)
    hole = (depth == 0)[..., None]   # 0 there, as the reprojection writes both scratch texels
    return key, np.where(hole, 0.0, d.astype(np.float64)), np.where(hole, 0.0, s.astype(np.float64))


def depth_gradient(z):
    """The depth gradient per pixel (svgf_depth_gradient) of depths z (L, H, W) in float64."""
    def at(a, dx, dy):
        big = np.zeros((L, H + 2, W + 2))
        big[:, 1:1 + H, 1:1 + W] = a
        return big[:, 1 + dy:1 + dy + H, 1 + dx:1 + dx + W]

    def slope(before, after):
        a = np.where(before > 0, z - before, 1e30)
        b = np.where(after > 0, after - z, 1e30)
        r = np.where(np.abs(a) < np.abs(b), a, b)
        return np.where(r > 1e29, 0.0, r)

    return np.stack([slope(at(z, -1, 0), at(z, 1, 0)), slope(at(z, 0, -1), at(z, 0, 1))], -1)


def reference(key, d, s, step, specular, kernel=5):
    """The a-trous iteration in float64: (diffuse rgb + variance, specular rgb + variance)."""
    KERNEL = KERNELS[kernel]
    radius = len(KERNEL) - 1
    z = key[..., 0].view(np.float32).astype(np.float64)
    n = unpack_normals(key[..., 1])
    pad = 2 * step

    def at(a, dx, dy):   # a at (x + dx, y + dy), 0 outside the view
        out = np.zeros_like(a)
        big = np.zeros((L, H + 2 * pad, W + 2 * pad) + a.shape[3:])
        big[:, pad:pad + H, pad:pad + W] = a
        out[:] = big[:, pad + dy:pad + dy + H, pad + dx:pad + dx + W]
        return out

    gradient = depth_gradient(z)
    inside = np.ones((L, H, W))
    var = np.stack([d[..., 3], s[..., 3]], -1)
    blur, total = 0.0, 0.0
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            k = (0.5 if dx == 0 else 0.25) * (0.5 if dy == 0 else 0.25)
            blur = blur + k * at(var, dx, dy)
            total = total + k * at(inside, dx, dy)[..., None]
    phi = PHI["svgf_phi_color"] * np.sqrt(np.maximum(blur / total, 0.0) + 1e-10)
    lum = [d[..., :3] @ LUMA, s[..., :3] @ LUMA]
    k0 = KERNEL[0] ** 2
    sums = []
    for lobe, (c, l) in enumerate(((d, lum[0]), (s, lum[1]))):
        sw, sc, sv = np.full((L, H, W), k0), k0 * c[..., :3], k0 * k0 * c[..., 3]
        for dy in range(-radius, radius + 1):
            for dx in range(-radius, radius + 1):
                if dx == 0 and dy == 0:
                    continue
                ox, oy = dx * step, dy * step
                zq, nq, cq = at(z, ox, oy), at(n, ox, oy), at(c, ox, oy)
                wz = np.exp(-np.abs(z - zq) / (PHI["svgf_phi_depth"] * np.abs(gradient @ [ox, oy]) + 1e-3 * z + 1e-8))
                wn = np.maximum((n * nq).sum(-1), 0.0) ** PHI["svgf_phi_normal"]
                wl = np.exp(-np.abs(l - cq[..., :3] @ LUMA) / phi[..., lobe])
                w = np.where(zq > 0, KERNEL[abs(dx)] * KERNEL[abs(dy)] * wz * wn * wl, 0.0)
                sw, sc, sv = sw + w, sc + w[..., None] * cq[..., :3], sv + w * w * cq[..., 3]
        filtered = np.concatenate([sc / sw[..., None], (sv / sw ** 2)[..., None]], -1)
        sums.append(np.where((z > 0)[..., None], filtered, c))
    if not specular:
        sums[1] = np.zeros_like(s)
    return sums


def gl_texture(gl, data, components, dtype):
    tex = gl.texture_array((W, H, L), components, data.tobytes() if data is not None else None, dtype=dtype)
    if dtype in ("u4", "f2"):
        import moderngl
        tex.filter = (moderngl.NEAREST, moderngl.NEAREST)
    return tex


def variance_gradient(gl, keys, specular):
    """The variance stage on `keys` (every history 8 frames long: it keeps the illumination and
    writes only the depth gradient): its `gradient_out` texture (rg16f)."""
    res = program_resources(SVGF().compute_program(gl, "svgf_variance.comp", {**effect_defines(), "SVGF_SPECULAR": int(specular)}))
    history = np.zeros((L, H, W, 2), np.uint32)
    history[..., 1] = np.float32(8.0).view(np.uint32)
    illum = np.zeros((L, H, W, 4), np.uint32 if specular else np.float16)
    made = [gl_texture(gl, history, 2, "u4"), gl_texture(gl, np.zeros((L, H, W, 4), np.float32), 4, "f4"),
            gl_texture(gl, illum, 4, "u4" if specular else "f2")]
    made += [gl_texture(gl, np.zeros((L, H, W, 4), np.float16), 4, "f2") for _ in range(2)]
    gradient = gl_texture(gl, np.full((L, H, W, 2), np.nan, np.float16), 2, "f2")
    res.texture("key_cur", keys)
    res.texture("surface_cur", made[0])
    res.texture("moments_cur", made[1])
    res.image("illum", made[2], read=True, write=True)
    res.image("history_diffuse", made[3])
    res.image("history_specular", made[4])
    res.image("gradient_out", gradient)
    for name, value in PHI.items():
        res.set(name, value)
    res.set("svgf_write_history", False)
    res.prog.run((W + 7) // 8, (H + 7) // 8, L)
    gl.memory_barrier()
    for t in made:
        t.release()
    return gradient


def dispatch(gl, key, d, s, step, specular, kernel=5, gradient=None):
    """One iteration on the GPU, with the history written: (diffuse, specular, history diffuse,
    history specular) as float64, rows as in the inputs. The depth gradient: the variance
    stage's from the key, or `gradient` (L, H, W, 2) as given."""
    prog = SVGF().compute_program(gl, "svgf_atrous.comp", {**effect_defines(), "SVGF_SPECULAR": int(specular), "SVGF_KERNEL": kernel})
    res = program_resources(prog)
    def texture(data, components, dtype):
        return gl_texture(gl, data, components, dtype)

    if specular:
        illum = np.stack([half_pairs(d[..., 0], d[..., 1]), half_pairs(d[..., 2], d[..., 3]),
                          half_pairs(s[..., 0], s[..., 1]), half_pairs(s[..., 2], s[..., 3])], -1)
        src, dst = texture(illum, 4, "u4"), texture(np.full_like(illum, half_pairs(np.array(UNTOUCHED), np.array(UNTOUCHED))), 4, "u4")
    else:
        src = texture(d.astype(np.float16), 4, "f2")
        dst = texture(np.full((L, H, W, 4), UNTOUCHED, np.float16), 4, "f2")
    keys = texture(key, 2, "u4")
    grad = variance_gradient(gl, keys, specular) if gradient is None else texture(gradient.astype(np.float16), 2, "f2")
    history = [texture(np.zeros((L, H, W, 4), np.float16), 4, "f2") for _ in range(2)]
    res.texture("key_cur", keys)
    res.texture("gradient_cur", grad)
    res.texture("src_illum", src)
    res.image("dst_illum", dst)
    res.image("history_diffuse", history[0])
    res.image("history_specular", history[1])
    for name, value in PHI.items():
        res.set(name, value)
    res.set("svgf_step", step)
    res.set("svgf_write_history", True)
    prog.run((W + 7) // 8, (H + 7) // 8, L)
    gl.memory_barrier()
    if specular:
        u = np.frombuffer(dst.read(), np.uint32).reshape(L, H, W, 4)
        out_d = np.concatenate([unhalf(u[..., 0]), unhalf(u[..., 1])], -1)
        out_s = np.concatenate([unhalf(u[..., 2]), unhalf(u[..., 3])], -1)
    else:
        out_d = np.frombuffer(dst.read(), np.float16).reshape(L, H, W, 4).astype(np.float64)
        out_s = np.zeros_like(out_d)
    hist = [np.frombuffer(h.read(), np.float16).reshape(L, H, W, 4).astype(np.float64) for h in history]
    for t in (src, dst, keys, grad, *history):
        t.release()
    return out_d, out_s, hist[0], hist[1]


@pytest.mark.parametrize("kernel", [5, 3])
@pytest.mark.parametrize("specular", [True, False])
@pytest.mark.parametrize("step", [1, 2, 4, 8])
def test_atrous_iteration_matches_the_float64_reference(gl, step, specular, kernel):
    key, d, s = synthetic()
    want_d, want_s = reference(key, d, s, step, specular, kernel)
    out_d, out_s, hist_d, hist_s = dispatch(gl, key, d, s, step, specular, kernel)
    # float32 arithmetic, then float16 storage (one ulp: 2^-10 relative, whichever rounding)
    drawn = key[..., 0] != 0
    np.testing.assert_allclose(out_d[drawn], want_d[drawn], rtol=2e-3, atol=1e-6)
    np.testing.assert_allclose(out_s[drawn], want_s[drawn], rtol=2e-3, atol=1e-6)
    # the history: the same colour, stored as rgba16f (llvmpipe's image stores truncate where
    # packHalf2x16 rounds to nearest: one ulp apart at most)
    np.testing.assert_allclose(hist_d[drawn][..., :3], out_d[drawn][..., :3], rtol=1e-3, atol=0)
    np.testing.assert_allclose(hist_s[drawn][..., :3], out_s[drawn][..., :3], rtol=1e-3, atol=0)
    changed = np.abs(out_d - d).max(-1) > 0.05
    assert changed[drawn].mean() > 0.3                                # the filter did filter (measured 0.45-0.9)
    assert (~drawn).any() and (out_d[~drawn] == UNTOUCHED).all()      # and wrote nothing in the holes
    assert (hist_d[~drawn] == 0).all()


@pytest.mark.parametrize("specular", [True, False])
def test_the_variance_stage_writes_the_depth_gradient_each_iteration_derived(gl, specular):
    """The gradient the a-trous iterations read (rg16f, written once a frame) is the one each
    iteration derived from four neighbours' keys before, within float16 rounding; where nothing was
    drawn, which no iteration reads, it writes nothing."""
    key, _, _ = synthetic()
    z = key[..., 0].view(np.float32).astype(np.float64)
    keys = gl_texture(gl, key, 2, "u4")
    tex = variance_gradient(gl, keys, specular)
    got = np.frombuffer(tex.read(), np.float16).reshape(L, H, W, 2).astype(np.float64)
    keys.release()
    tex.release()
    want = depth_gradient(z)
    drawn = z > 0
    np.testing.assert_allclose(got[drawn], want[drawn], rtol=1e-3, atol=1e-6)
    assert np.abs(want[drawn]).max() > 0.5 and (np.abs(want[drawn]) > 0.02).mean() > 0.9   # steps and slopes
    assert (~drawn).any() and np.isnan(got[~drawn]).all()   # as the texture came


def test_a_wrong_gradient_changes_the_output(gl):
    """The iteration does read the gradient texture: a zero gradient (every depth difference
    then weighs against depth alone) filters less across the slopes than the true one."""
    key, d, s = synthetic()
    want_d, _ = reference(key, d, s, 1, False)
    right, _, _, _ = dispatch(gl, key, d, s, 1, False)
    wrong, _, _, _ = dispatch(gl, key, d, s, 1, False, gradient=np.zeros((L, H, W, 2)))
    drawn = key[..., 0] != 0
    np.testing.assert_allclose(right[drawn], want_d[drawn], rtol=2e-3, atol=1e-6)
    assert np.abs(wrong - want_d)[drawn].max() > 0.05
