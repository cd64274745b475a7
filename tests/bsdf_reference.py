"""A float64 numpy implementation of rayvr's BSDF (glsl/bsdf.glsl's docstring is the
specification), written independently of the GLSL for tests: the reflection lobes of the glTF
metallic-roughness model with KHR_materials_specular, the albedo-scaled Lambert base, Turquin's
compensation, from the energy tables of rayvr.materials.bsdf_tables (float64)."""
from __future__ import annotations

import numpy as np

from rayvr.materials import bsdf_tables as T


def _lambda(c, alpha):
    c = np.clip(c, 1e-12, 1.0)
    return 0.5 * (np.sqrt(1.0 + alpha * alpha * (1.0 - c * c) / (c * c)) - 1.0)


def _schlick(f0, f90, c):
    return f0 + (f90 - f0) * (1.0 - np.clip(c, 0.0, 1.0)) ** 5


class Bsdf:
    """One material: base colour (3,), metallic, roughness, ior, specular, specular colour (3,)."""

    def __init__(self, base_color=(1.0, 1.0, 1.0), metallic=0.0, roughness=1.0, ior=1.5, specular=1.0,
                 specular_color=(1.0, 1.0, 1.0)):
        self.base = np.asarray(base_color, np.float64)
        self.metallic, self.roughness = float(metallic), float(roughness)
        r = (ior - 1.0) / (ior + 1.0)
        self.f0 = np.minimum(r * r * np.asarray(specular_color, np.float64), 1.0) * specular
        self.f90 = float(specular)
        self.alpha = max(self.roughness ** 2, 1e-6)

    def _ab(self, mu):
        return T.specular_terms(np.asarray(mu, np.float64), np.full(np.shape(mu), self.roughness))

    def layer_albedo(self, f0, f90, mu):
        ab = self._ab(mu)
        a, b = ab[..., 0:1], ab[..., 1:2]
        ess = np.maximum(a + b, 1e-4)
        return (f0 * a + f90 * b) * (1.0 + f0 * (1.0 / ess - 1.0))

    def layer_average(self, f0, f90) -> float:
        _, rough, _, averages = T.tables()
        avg = np.array([np.interp(self.roughness, rough, averages[:, j]) for j in range(4)])
        return float(f0 * avg[0] + f90 * avg[1] + f0 * f0 * avg[2] + f0 * f90 * avg[3])

    def eval(self, v, l, n=(0.0, 0.0, 1.0)):
        """f(v, l) cos(theta_l) (..., 3) for unit v, l (..., 3) above the surface."""
        n = np.asarray(n, np.float64)
        nv, nl = (v * n).sum(-1), (l * n).sum(-1)
        ok = (nv > 0) & (nl > 0)
        nv_c, nl_c = np.clip(nv, 1e-12, 1), np.clip(nl, 1e-12, 1)
        h = v + l
        h /= np.maximum(np.linalg.norm(h, axis=-1, keepdims=True), 1e-300)
        nh, vh = (h * n).sum(-1), (v * h).sum(-1)
        a2 = self.alpha ** 2
        sin2_h = np.maximum(1.0 - nh * nh, 0.0)
        d = a2 / (np.pi * (a2 * nh * nh + sin2_h) ** 2)
        g2 = 1.0 / (1.0 + _lambda(nv_c, self.alpha) + _lambda(nl_c, self.alpha))
        fss = (d * g2 / (4 * nv_c * nl_c))[..., None]
        ab_v = self._ab(nv_c)
        ess = np.maximum(ab_v[..., 0:1] + ab_v[..., 1:2], 1e-4)
        w_d, w_m = 1.0 - self.metallic, self.metallic
        fd = _schlick(self.f0, self.f90, vh[..., None]) * (1.0 + self.f0 * (1.0 / ess - 1.0))
        fm = _schlick(self.base, 1.0, vh[..., None]) * (1.0 + self.base * (1.0 / ess - 1.0))
        spec = (w_d * fd + w_m * fm) * fss
        ev = self.layer_albedo(self.f0, self.f90, nv_c).max(-1, keepdims=True)
        el = self.layer_albedo(self.f0, self.f90, nl_c).max(-1, keepdims=True)
        eavg = self.layer_average(self.f0.max(), self.f90)
        diffuse = w_d * self.base * (1 - ev) * (1 - el) / max(1 - eavg, 1e-4) / np.pi
        return np.where(ok[..., None], (spec + diffuse) * nl_c[..., None], 0.0)

    def albedo(self, mu, n_theta=256, n_phi=128) -> np.ndarray:
        """Directional albedo: the integral of eval over the hemisphere of l, for v at cos = mu."""
        t = (np.arange(n_theta) + 0.5) / n_theta * (np.pi / 2)
        ph = (np.arange(n_phi) + 0.5) / n_phi * 2 * np.pi
        tt, pp = np.meshgrid(t, ph, indexing="ij")
        l = np.stack([np.sin(tt) * np.cos(pp), np.sin(tt) * np.sin(pp), np.cos(tt)], -1)
        v = np.broadcast_to([np.sqrt(1 - mu * mu), 0.0, mu], l.shape)
        f = self.eval(v, l)
        return (f * np.sin(tt)[..., None]).sum(axis=(0, 1)) * (np.pi / 2 / n_theta) * (2 * np.pi / n_phi)
