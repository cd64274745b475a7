"""A study's settings from named options over the machine's defaults (rayvr.study.defaults).

`plan_settings(defaults, options)` is what `rayvr converge` and `rayvr tune` run their parsed
options through: every option left out (None) takes the machine's default and is listed in
`chosen`, so the study can say what it picked; contradictory values are refused with the option's
name (`name(key)`: the command line's spelling there).
"""
from __future__ import annotations

from ..errors import OptionError
from .defaults import MachineDefaults

TRAJECTORY_NONE = "none"


def plan_settings(d: MachineDefaults, options: dict, name=lambda key: key):
    """(ReferenceSettings, StudySettings, chosen) from `options` (keys: reference_frames,
    reference_max_frames, reference_seconds, reference_spp, bounces, tolerance, bounce_tolerance,
    trajectory, motion_frames, motion_samples, frames, timing_frames, warmup, warmup_s, floors,
    floor_fraction, progressive_frames, preset, ppd, display, metrics). A reference frame count
    given alone is rendered exactly; otherwise the reference renders on until converged or capped.
    `chosen`: the option name -> the default taken for it."""
    from ..xr.presets import get_preset
    from .measure import StudySettings
    from .motion import Motion
    from .reference import ReferenceSettings

    o = options
    chosen = {}

    def pick(key, default):
        if o.get(key) is None:
            chosen[name(key)] = default
            return default
        return o[key]

    for key in ("reference_frames", "reference_max_frames"):
        if o.get(key) is not None and o[key] % 2:
            raise OptionError(f"{name(key)} {o[key]}: the reference is two equal halves; give an even number")
    frames = pick("reference_frames", d.reference_frames)
    fixed = o.get("reference_frames") is not None and o.get("reference_max_frames") is None \
        and o.get("reference_seconds") is None
    max_frames = None if fixed else pick("reference_max_frames", max(d.reference_max_frames, frames))
    if max_frames is not None and max_frames < frames:
        raise OptionError(f"{name('reference_max_frames')} {max_frames}: fewer than the first round's {frames} "
                          f"frames ({name('reference_frames')}); give at least {frames}")
    reference = ReferenceSettings(frames, pick("reference_spp", d.reference_spp), o["bounces"], o["tolerance"],
                                  o["bounce_tolerance"], max_frames=max_frames,
                                  max_seconds=None if fixed else pick("reference_seconds", d.reference_seconds))
    motion = None
    trajectory = o.get("trajectory") or TRAJECTORY_NONE
    if trajectory != TRAJECTORY_NONE:
        if not trajectory.lower().endswith(".json"):
            from ..xr.trajectory import TRAJECTORIES

            if trajectory not in TRAJECTORIES:
                raise OptionError(f"{name('trajectory')} {trajectory}: use one of {', '.join(TRAJECTORIES)}, "
                                  f"a pose-log .json or none")
        motion_frames = pick("motion_frames", d.motion_frames)
        samples = pick("motion_samples", d.motion_samples)
        motion = Motion(trajectory, motion_frames, min(samples, motion_frames),
                        get_preset(o["preset"]).default_refresh)
    settings = StudySettings(
        frames=pick("frames", d.frames), timing_frames=pick("timing_frames", d.timing_frames),
        warmup=pick("warmup", d.warmup), warmup_s=o.get("warmup_s"), motion=motion, floors=o.get("floors", True),
        floor_fraction=pick("floor_fraction", d.floor_fraction),
        progressive_frames=pick("progressive_frames", d.progressive_frames),
        preset=o["preset"], ppd=o.get("ppd"), display=o["display"], metrics=tuple(o["metrics"]))
    return reference, settings, chosen
