"""rayvr.study: image error against GPU time that can be trusted.

A converged, checked, pixel-filtered reference (`reference`), the configurations it judges
(`configs`), their GPU time, error on a still and a moving head, bias floors and progressive
curves (`measure`), the metrics (`metrics`, `display`), the report (`report`, `results`). The
budget tuner (rayvr.tune) stands on it.

    import rayvr as rv
    scene = rv.scenes.cornell_box()
    results = rv.study.measure(scene, rv.study.standard_configs(scene), views=2, size=(64, 64))
    print(results.table())
    rv.study.write_report(results, "out/study")     # report.md, report.html, results.json, images
"""
from .configs import (
    Config,
    hybrid_graph,
    hybrid_taa_graph,
    load_configs,
    path_traced_graph,
    reflective_material,
    standard_configs,
)
from .display import Display
from .floor import Floor, bias_floor
from .measure import StudySettings, measure
from .metrics import all_metrics, evaluate, flip, flip_map, psnr, rel_mse, rel_mse_map, srgb_encode, ssim
from .motion import Motion
from .reference import Reference, ReferenceSettings, cached_reference, render_reference
from .report import write_report
from .results import Curve, Results, Row
from .timing import Timing, make_views, timed_frames, warm_up

__all__ = [
    "Config", "Curve", "Display", "Floor", "Motion", "Reference", "ReferenceSettings", "Results", "Row",
    "StudySettings", "Timing", "all_metrics", "bias_floor", "cached_reference", "evaluate", "flip", "flip_map",
    "hybrid_graph", "hybrid_taa_graph", "load_configs", "make_views", "measure", "path_traced_graph", "psnr",
    "reflective_material", "rel_mse", "rel_mse_map", "render_reference", "srgb_encode", "ssim", "standard_configs",
    "timed_frames", "warm_up", "write_report",
]
