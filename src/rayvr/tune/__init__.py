"""rayvr.tune: image error against GPU time, and the per-material effect budget tuner.

    import rayvr as rv
    scene = rv.scenes.cornell_box()
    results = rv.tune.measure(scene, rv.tune.standard_configs(scene), size=(64, 64), views=2)
    print(results.table()); results.write("out/tune")
    tuned = rv.tune.tune_effects(scene, budget_ms=11.1, size=(1440, 1600), views=2)
    print(tuned.table())
"""
from .budget import CostModel, TuneResult, Upgrade, choose_effects, tune_effects
from .configs import (
           Config,
           hybrid_graph,
           path_traced_graph,
           reflective_material,
           standard_configs,
)
from .measure import Timing, make_views, measure, timed_frames
from .metrics import (
           all_metrics,
           flip,
           flip_map,
           psnr,
           rel_mse,
           rel_mse_map,
           srgb_encode,
)
from .probe import probe_cost_model
from .reference import ReferenceSettings, reference_image, render_reference
from .results import ConfigResult, Results

__all__ = [
           "Config",
           "ConfigResult",
           "CostModel",
           "ReferenceSettings",
           "Results",
           "Timing",
           "TuneResult",
           "Upgrade",
           "all_metrics",
           "choose_effects",
           "flip",
           "flip_map",
           "hybrid_graph",
           "make_views",
           "measure",
           "path_traced_graph",
           "probe_cost_model",
           "psnr",
           "reference_image",
           "reflective_material",
           "rel_mse",
           "rel_mse_map",
           "render_reference",
           "srgb_encode",
           "standard_configs",
           "timed_frames",
           "tune_effects",
]
