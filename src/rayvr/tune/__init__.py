"""rayvr.tune: image error against GPU time that can be trusted, and the per-material effect
budget tuner built on it.

    import rayvr as rv
    scene = rv.scenes.cornell_box()
    results = rv.tune.measure(scene, rv.tune.standard_configs(scene), views=2, size=(64, 64))
    print(results.table())
    rv.tune.write_report(results, "out/study")     # report.md, report.html, results.json, images
    tuned = rv.tune.tune_effects(scene, budget_ms=11.1, size=(1440, 1600), views=2)
    print(tuned.table())
"""
from .budget import CostModel, TuneResult, Upgrade, choose_effects
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
from .probe import probe_cost_model
from .reference import Reference, ReferenceSettings, cached_reference, render_reference
from .report import write_report
from .results import Curve, Results, Row
from .timing import Timing, make_views, timed_frames, warm_up
from .tuner import tune_effects

__all__ = [
    "Config", "CostModel", "Curve", "Display", "Floor", "Motion", "Reference", "ReferenceSettings", "Results",
    "Row", "StudySettings", "Timing", "TuneResult", "Upgrade", "all_metrics", "bias_floor", "cached_reference", "choose_effects",
    "evaluate", "flip", "flip_map", "hybrid_graph", "hybrid_taa_graph", "load_configs", "make_views", "measure",
    "path_traced_graph", "probe_cost_model", "psnr", "reflective_material", "rel_mse", "rel_mse_map",
    "render_reference", "srgb_encode", "ssim", "standard_configs", "timed_frames", "tune_effects", "warm_up",
    "write_report",
]
