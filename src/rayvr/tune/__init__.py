"""rayvr.tune: the per-material effect budget tuner, on top of the error study (rayvr.study,
whose public names it hands on, so `rv.tune.measure` and `rv.tune.standard_configs` work too).

    import rayvr as rv
    scene = rv.scenes.cornell_box()
    tuned = rv.tune.tune_effects(scene, budget_ms=11.1, size=(1440, 1600), views=2)
    print(tuned.table())
"""
from ..study import *  # noqa: F401,F403  (the study's names, as rv.tune.* too)
from ..study import __all__ as _study_names
from .budget import CostModel, TuneResult, Upgrade, choose_effects
from .cost_probe import probe_cost_model
from .tuner import tune_effects

__all__ = [*_study_names, "CostModel", "TuneResult", "Upgrade", "choose_effects", "probe_cost_model",
           "tune_effects"]
