"""Named ReSTIRDI property sets that the benchmarks time (frame_configs' rows, restir's --restir)."""
from __future__ import annotations

_LEAN = {"target": "cosine", "candidates": 4, "visibility_reuse": False}
_NO_REUSE = {"spatial_samples": 0, "temporal_reuse": False, "share_views": False}
# name -> ReSTIRDI properties (beyond the pass's defaults)
RESTIR_SETS = {
    "defaults": {},
    # the stages apart: fewer candidates, no visibility reuse, no spatial or temporal reuse
    "2 candidates": {"candidates": 2},
    "no visibility reuse": {"visibility_reuse": False},
    "no spatial": {"spatial_samples": 0},
    "candidates only": dict(_NO_REUSE),
    # the resampling target without the BSDF (p_hat = Le G cos), alone and with cheaper settings
    "cosine target": {"target": "cosine"},
    "lean": dict(_LEAN),
    # lean's stages apart: candidates alone, + temporal reuse (fused), + spatial reuse
    "lean candidates": {**_LEAN, **_NO_REUSE},
    "lean temporal": {**_LEAN, "spatial_samples": 0, "share_views": False},
    "lean spatial": {**_LEAN, "temporal_reuse": False},
    # visibility hints instead of the candidates' visibility ray: the cheapest set, and lean with them
    "hints": {"target": "cosine", "candidates": 2, "visibility_reuse": False, "spatial_samples": 0,
              "share_views": False, "occluded_weight": 0.05},
    "lean hints": {**_LEAN, "occluded_weight": 0.05},
    # hints beside the candidates' visibility ray, with the BSDF's target or the automatic one
    "defaults hints": {"occluded_weight": 0.05},
    "auto hints": {"target": "auto", "occluded_weight": 0.05},
}
