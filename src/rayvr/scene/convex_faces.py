"""The triangles of a mesh that have the whole mesh behind them.

A ray that leaves such a triangle through its front side (the side its winding makes the front)
cannot meet the mesh again: every point of the mesh lies in the half-space behind the triangle's
plane, and the ray only moves away from it. The traversal then skips the ray's own instance
(glsl/ray_query.glsl, `skip`), which for a closed convex mesh (a tessellated sphere, a box, a
wall) is most of the work of its bounce and shadow rays. Affine instance transforms keep the
relation, so it is a property of the mesh.

"Behind" allows `rel_tol` of the mesh's diagonal: exported convex meshes carry vertex noise
(the 1.04M-triangle spheres' vertices lie within 2e-4 of the radius). A skipped ray can miss only
mesh within that slab over the triangle's plane.
"""
from __future__ import annotations

import numpy as np
from scipy.spatial import ConvexHull, QhullError

REL_TOL = 1e-4            # of the mesh's diagonal
_SAMPLE_FACES = 32        # the quick rejection of plainly non-convex meshes
_SAMPLE_VERTICES = 4096
_FLAT_MAX_PRODUCTS = 5e7  # a flat mesh's exact test is faces x vertices products


def convex_faces(positions: np.ndarray, indices: np.ndarray, rel_tol: float = REL_TOL) -> np.ndarray:
    """One bool per triangle: the whole mesh lies behind its front plane (within rel_tol of the
    mesh's diagonal). Degenerate triangles are False, as is every triangle of a mesh where fewer
    than an eighth of a sample of triangles could pass (no exact test is spent on it)."""
    indices = np.asarray(indices).reshape(-1, 3)
    out = np.zeros(len(indices), bool)
    if not len(indices):
        return out
    p = np.asarray(positions, np.float64)
    lo, hi = p.min(axis=0), p.max(axis=0)
    diag = float(np.linalg.norm(hi - lo))
    if not diag > 0.0:
        return out
    p = (p - 0.5 * (lo + hi)) / diag   # unit diagonal: rel_tol is a plain distance
    a = p[indices[:, 0]]
    n = np.cross(p[indices[:, 1]] - a, p[indices[:, 2]] - a)
    length = np.linalg.norm(n, axis=1)
    good = length > 1e-14
    n[good] /= length[good, None]
    plane = np.einsum("ij,ij->i", n, a)
    rng = np.random.default_rng(0)
    faces = np.flatnonzero(good)
    if not len(faces):
        return out
    some = rng.choice(faces, min(_SAMPLE_FACES, len(faces)), replace=False)
    verts = p[rng.choice(len(p), min(_SAMPLE_VERTICES, len(p)), replace=False)]
    low = (n[some] @ verts.T).max(axis=1) - plane[some]   # a lower bound of each sampled depth
    if np.mean(low <= rel_tol) < 0.125:   # hardly any can pass: not worth the exact test
        return out
    out[faces] = support(p, n[faces], indices[faces, 0]) - plane[faces] <= rel_tol
    return out


def support(points: np.ndarray, dirs: np.ndarray, near: np.ndarray | None = None) -> np.ndarray:
    """max over points of dot(d, p) for each row d of dirs: greedy ascent over the convex hull's
    edges (a linear function's local maximum on a convex polytope is its maximum), so the cost
    is per direction, not per point. `near` (a point index per direction) starts each walk where
    it is a hull vertex: a convex triangle's own vertex is already the maximum. A flat point set
    (no hull) is done by brute force, or gives +inf (no triangle passes) when that is too large."""
    try:
        hull = ConvexHull(points)
    except (QhullError, ValueError):
        if len(points) * len(dirs) > _FLAT_MAX_PRODUCTS:
            return np.full(len(dirs), np.inf)
        return np.concatenate([(dirs[i:i + 4096] @ points.T).max(axis=1) for i in range(0, len(dirs), 4096)])
    hv = points[hull.vertices]
    local = np.full(len(points), -1, np.int64)
    local[hull.vertices] = np.arange(len(hv))
    s = local[hull.simplices]
    edges = np.concatenate([s[:, [0, 1]], s[:, [1, 2]], s[:, [2, 0]]])
    h = len(hv)
    keys = np.unique(np.concatenate([edges[:, 0] * h + edges[:, 1], edges[:, 1] * h + edges[:, 0]]))
    edges = np.stack([keys // h, keys % h], axis=1)   # both directions, sorted by first vertex
    count = np.bincount(edges[:, 0], minlength=len(hv))
    start = np.concatenate([[0], np.cumsum(count)[:-1]])
    rank = np.arange(len(edges)) - start[edges[:, 0]]
    nbr = np.repeat(np.arange(len(hv))[:, None], max(int(count.max()), 1), axis=1)   # padded with itself
    nbr[edges[:, 0], rank] = edges[:, 1]
    seeds = np.arange(len(hv)) if len(hv) <= 64 else np.random.default_rng(1).choice(len(hv), 64, replace=False)
    cur = seeds[np.argmax(dirs @ hv[seeds].T, axis=1)]
    if near is not None:
        cur = np.where(local[near] >= 0, local[near], cur)
    val = np.einsum("ij,ij->i", dirs, hv[cur])
    active = np.arange(len(dirs))
    while len(active):
        cand = nbr[cur[active]]
        vals = np.einsum("ad,akd->ak", dirs[active], hv[cand])
        k = np.argmax(vals, axis=1)
        best = vals[np.arange(len(active)), k]
        up = best > val[active]   # strictly: the walk ends
        moved = active[up]
        cur[moved] = cand[up, k[up]]
        val[moved] = best[up]
        active = moved
    return val
