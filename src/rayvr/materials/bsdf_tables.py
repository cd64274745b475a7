"""The precomputed tables of the BSDF's energy compensation, built once in float64.

For the GGX lobe with height-correlated Smith masking, over perceptual roughness r (alpha = r^2)
and mu = n.v, with Schlick's Fresnel F = f0 + (f90 - f0) w, w = (1 - v.h)^5:

    A(mu, r) = integral of (1 - w) f_ss cos dl,   B(mu, r) = integral of w f_ss cos dl

(f_ss = D G2 / (4 n.v n.l), no Fresnel), so the specular lobe's directional albedo is
f0 A + f90 B and its albedo without Fresnel E_ss = A + B (the "DFG" terms of split-sum image
lighting). The compensated lobe (Turquin 2019) scales f_ss by 1 + f0 (1 / E_ss - 1), so a white
metal reflects everything; the diffuse base under a dielectric's specular layer is weighted by
(1 - E(mu_v)) (1 - E(mu_l)) / (1 - E_avg) (the albedo scaling of Kulla & Conty 2017), so a white
dielectric does too. E_avg is the cosine-weighted hemispherical mean of E; for the compensated
E(mu) = (f0 A + f90 B)(1 + f0 (1/E_ss - 1)) it is f0 Ā + f90 B̄ + f0² C̄ + f0 f90 D̄ with the
per-roughness means of A, B, A (1/E_ss - 1), B (1/E_ss - 1) tabulated as AVERAGES.

Glass (a rough dielectric interface, Walter et al. 2007) reflects with the exact Fresnel term F
and refracts with 1 - F at each microfacet, and loses what masking takes: its single-scatter
albedo G(mu, r, ior) (reflected plus transmitted energy, entering the glass or leaving it) is
tabulated over IOR too, and both its lobes are divided by it, so white glass conserves energy.

`table_floats()` is the SSBO the shaders read (glsl/bsdf.glsl, binding RAYVR_BSDF_TABLE_SSBO).
The integrals use VNDF importance sampling with a Hammersley set: the estimator of f_ss cos over
VNDF samples is G2 / G1(v), smooth enough that 4096 samples give ~1e-4.
"""
from __future__ import annotations

import functools
from pathlib import Path

import numpy as np

MU_SIZE = 32          # cos(theta_v) from MU_MIN to 1, uniformly
ROUGHNESS_SIZE = 32   # perceptual roughness from 0 to 1, uniformly
MU_MIN = 1.0 / 64
SAMPLES = 4096
HEADER_FLOATS = 4     # mu size, roughness size, mu min, IOR size (as floats)
IOR_SIZE = 16         # glass: IOR from 1 to IOR_MAX, uniformly
IOR_MAX = 3.0
GLASS_SAMPLES = 2048


def _hammersley(n: int) -> np.ndarray:
    """(n, 2) points of the 2D Hammersley set: i / n and the base-2 radical inverse of i."""
    i = np.arange(n, dtype=np.uint64)
    bits = i.copy()
    bits = ((bits & 0x55555555) << 1) | ((bits & 0xAAAAAAAA) >> 1)
    bits = ((bits & 0x33333333) << 2) | ((bits & 0xCCCCCCCC) >> 2)
    bits = ((bits & 0x0F0F0F0F) << 4) | ((bits & 0xF0F0F0F0) >> 4)
    bits = ((bits & 0x00FF00FF) << 8) | ((bits & 0xFF00FF00) >> 8)
    bits = ((bits & 0x0000FFFF) << 16) | ((bits & 0xFFFF0000) >> 16)
    return np.stack([(i.astype(np.float64) + 0.5) / n, bits.astype(np.float64) / 2.0 ** 32], axis=1)


def smith_lambda(cos_theta, alpha):
    c2 = np.maximum(cos_theta * cos_theta, 1e-12)
    return 0.5 * (np.sqrt(1.0 + alpha * alpha * np.maximum(1.0 - c2, 0.0) / c2) - 1.0)


def sample_vndf(v: np.ndarray, alpha: float, u: np.ndarray) -> np.ndarray:
    """Visible normals about +Z for view directions v (..., 3) (Heitz 2018), float64."""
    vh = np.stack([alpha * v[..., 0], alpha * v[..., 1], v[..., 2]], -1)
    vh /= np.linalg.norm(vh, axis=-1, keepdims=True)
    lensq = vh[..., 0] ** 2 + vh[..., 1] ** 2
    safe = np.maximum(lensq, 1e-300)
    t1 = np.where((lensq > 1e-12)[..., None],
                  np.stack([-vh[..., 1], vh[..., 0], np.zeros_like(lensq)], -1) / np.sqrt(safe)[..., None],
                  np.array([1.0, 0.0, 0.0]))
    t2 = np.cross(vh, t1)
    r = np.sqrt(u[..., 0])
    phi = 2 * np.pi * u[..., 1]
    p1, p2 = r * np.cos(phi), r * np.sin(phi)
    s = 0.5 * (1.0 + vh[..., 2])
    p2 = (1.0 - s) * np.sqrt(np.maximum(0.0, 1.0 - p1 * p1)) + s * p2
    nh = p1[..., None] * t1 + p2[..., None] * t2 + np.sqrt(np.maximum(0.0, 1 - p1 * p1 - p2 * p2))[..., None] * vh
    m = np.stack([alpha * nh[..., 0], alpha * nh[..., 1], np.maximum(nh[..., 2], 1e-12)], -1)
    return m / np.linalg.norm(m, axis=-1, keepdims=True)


def directional_terms(mu: float, roughness: float, samples: int = SAMPLES) -> tuple[float, float]:
    """(A, B) at one (mu, roughness), by VNDF sampling (see the module docstring)."""
    alpha = max(roughness * roughness, 1e-6)
    v = np.array([np.sqrt(max(0.0, 1.0 - mu * mu)), 0.0, mu])
    u = _hammersley(samples)
    h = sample_vndf(np.broadcast_to(v, (samples, 3)), alpha, u)
    vh = np.clip(h @ v, 0.0, 1.0)
    l = 2.0 * vh[:, None] * h - v
    ok = l[:, 2] > 0
    weight = np.where(ok, (1.0 + smith_lambda(mu, alpha)) / (1.0 + smith_lambda(mu, alpha)
                                                             + smith_lambda(np.maximum(l[:, 2], 1e-12), alpha)), 0.0)
    w = (1.0 - vh) ** 5
    return float(np.mean(weight * (1.0 - w))), float(np.mean(weight * w))


def fresnel_dielectric(cos_i, eta):
    """Exact unpolarised Fresnel reflectance, eta = n_t / n_i; 1 under total internal reflection."""
    cos_i = np.clip(cos_i, 0.0, 1.0)
    sin2_t = (1.0 - cos_i * cos_i) / (eta * eta)
    tir = sin2_t >= 1.0
    cos_t = np.sqrt(np.maximum(1.0 - sin2_t, 0.0))
    rs = (cos_i - eta * cos_t) / np.maximum(cos_i + eta * cos_t, 1e-300)
    rp = (eta * cos_i - cos_t) / np.maximum(eta * cos_i + cos_t, 1e-300)
    return np.where(tir, 1.0, 0.5 * (rs * rs + rp * rp))


def glass_albedo(mu: float, roughness: float, eta: float, samples: int = GLASS_SAMPLES) -> float:
    """Single-scatter albedo of a rough dielectric interface (reflected + transmitted energy, no
    radiance scaling) for v at cos = mu, relative IOR eta = n_l / n_v, by VNDF sampling: each
    microfacet reflects F and refracts 1 - F, each direction weighted by G2 / G1."""
    alpha = max(roughness * roughness, 1e-6)
    v = np.array([np.sqrt(max(0.0, 1.0 - mu * mu)), 0.0, mu])
    u = _hammersley(samples)
    h = sample_vndf(np.broadcast_to(v, (samples, 3)), alpha, u)
    vh = np.clip(h @ v, 0.0, 1.0)
    f = fresnel_dielectric(vh, eta)
    lam_v = smith_lambda(mu, alpha)
    r = 2.0 * vh[:, None] * h - v
    refl = np.where(r[:, 2] > 0, (1 + lam_v) / (1 + lam_v + smith_lambda(np.maximum(r[:, 2], 1e-12), alpha)), 0.0)
    # refraction of -v about h (GLSL's refract with index ratio 1 / eta)
    k = 1.0 - (1.0 / eta) ** 2 * (1.0 - vh * vh)
    t = -v / eta + (vh / eta - np.sqrt(np.maximum(k, 0.0)))[:, None] * h
    tz = t[:, 2]
    trans = np.where((k > 0) & (tz < 0), (1 + lam_v) / (1 + lam_v + smith_lambda(np.maximum(-tz, 1e-12), alpha)), 0.0)
    return float(np.mean(f * refl + (1.0 - f) * trans))


DATA_FILE = Path(__file__).with_name("bsdf_tables.npz")   # python -m rayvr.materials.bsdf_tables writes it


@functools.lru_cache(maxsize=1)
def tables() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(mu, roughness, terms (R, M, 2) = A and B, averages (R, 4) = Ā, B̄, C̄, D̄), float64: the
    package's precomputed file when it matches this module's grid, else computed (~1 s)."""
    data = _stored()
    if data is not None:
        return data["mu"], data["roughness"], data["terms"], data["averages"]
    return compute_tables()


@functools.lru_cache(maxsize=1)
def glass_tables() -> np.ndarray:
    """(2, I, R, M): glass's single-scatter albedo entering (side 0: eta = ior) and leaving (side 1:
    eta = 1 / ior), over IOR (1..IOR_MAX), roughness and mu; the stored file, else computed (~1 min)."""
    data = _stored()
    if data is not None and "glass" in data:
        return data["glass"]
    return compute_glass_tables()


def _stored():
    try:
        with np.load(DATA_FILE) as data:
            if data["terms"].shape == (ROUGHNESS_SIZE, MU_SIZE, 2) and float(data["mu"][0]) == MU_MIN \
                    and data["glass"].shape == (2, IOR_SIZE, ROUGHNESS_SIZE, MU_SIZE):
                return {k: data[k] for k in data.files}
    except (OSError, KeyError, ValueError):
        pass
    return None


def compute_glass_tables() -> np.ndarray:
    """glass_tables() computed afresh."""
    mu = np.linspace(MU_MIN, 1.0, MU_SIZE)
    rough = np.linspace(0.0, 1.0, ROUGHNESS_SIZE)
    iors = np.linspace(1.0, IOR_MAX, IOR_SIZE)
    out = np.ones((2, IOR_SIZE, ROUGHNESS_SIZE, MU_SIZE))
    for side in (0, 1):
        for i, ior in enumerate(iors):
            eta = ior if side == 0 else 1.0 / ior
            for k, r in enumerate(rough):
                out[side, i, k] = [glass_albedo(m, r, eta) for m in mu]
    return out


def compute_tables() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The tables computed afresh (see tables())."""
    mu = np.linspace(MU_MIN, 1.0, MU_SIZE)
    rough = np.linspace(0.0, 1.0, ROUGHNESS_SIZE)
    terms = np.array([[directional_terms(m, r) for m in mu] for r in rough])
    # cosine-weighted hemispherical means 2 * integral over mu of X(mu) mu dmu, on a fine mu grid
    fine = (np.arange(256) + 0.5) / 256
    averages = np.zeros((ROUGHNESS_SIZE, 4))
    for k in range(ROUGHNESS_SIZE):
        a = np.interp(fine, mu, terms[k, :, 0])
        b = np.interp(fine, mu, terms[k, :, 1])
        excess = 1.0 / np.maximum(a + b, 1e-6) - 1.0
        for j, x in enumerate((a, b, a * excess, b * excess)):
            averages[k, j] = 2.0 * np.mean(x * fine)
    return mu, rough, terms, averages


def table_floats() -> np.ndarray:
    """The tables as the shaders read them: header, A/B per (roughness, mu), averages per
    roughness, glass's albedo per (side, IOR, roughness, mu)."""
    _, _, terms, averages = tables()
    header = np.array([MU_SIZE, ROUGHNESS_SIZE, MU_MIN, IOR_SIZE], np.float32)
    return np.concatenate([header, terms.astype(np.float32).reshape(-1), averages.astype(np.float32).reshape(-1),
                           glass_tables().astype(np.float32).reshape(-1)])


def _lookup(grid_x, grid_y, values, x, y):
    """Bilinear lookup of values (len(grid_y), len(grid_x), ...) at (x, y), clamped to the grid."""
    fx = np.clip((x - grid_x[0]) / (grid_x[-1] - grid_x[0]) * (len(grid_x) - 1), 0, len(grid_x) - 1)
    fy = np.clip((y - grid_y[0]) / (grid_y[-1] - grid_y[0]) * (len(grid_y) - 1), 0, len(grid_y) - 1)
    x0, y0 = np.minimum(fx.astype(int), len(grid_x) - 2), np.minimum(fy.astype(int), len(grid_y) - 2)
    tx, ty = fx - x0, fy - y0
    v00, v01 = values[y0, x0], values[y0, x0 + 1]
    v10, v11 = values[y0 + 1, x0], values[y0 + 1, x0 + 1]
    tx, ty = np.asarray(tx)[..., None], np.asarray(ty)[..., None]
    return (v00 * (1 - tx) + v01 * tx) * (1 - ty) + (v10 * (1 - tx) + v11 * tx) * ty


def specular_terms(mu, roughness) -> np.ndarray:
    """(..., 2): A and B at (mu, roughness), interpolated as the shader does."""
    m, r, terms, _ = tables()
    return _lookup(m, r, terms, np.asarray(mu, np.float64), np.asarray(roughness, np.float64))


if __name__ == "__main__":   # regenerate the package's table file
    mu, rough, terms, averages = compute_tables()
    np.savez_compressed(DATA_FILE, mu=mu, roughness=rough, terms=terms, averages=averages,
                        glass=compute_glass_tables())
    print(f"wrote {DATA_FILE}")
