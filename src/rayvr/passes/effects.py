"""What a pass compiles with from the scene: its feature and effect #defines, and whether any
material needs the pass's effect at all (otherwise the compiler prunes it and says why)."""
from __future__ import annotations

from ..materials.effect import Effect


def scene_defines(ctx) -> dict:
    """The GpuScene's feature #defines (none without a scene)."""
    return {} if ctx.scene is None else dict(ctx.scene.defines())


def scene_transmits(scene) -> bool:
    """Whether a pass must provide for transmission: unless `scene` (a GpuScene) is known not to
    transmit. Its features are those of its upload, not of later material edits."""
    return scene is None or "SCENE_HAS_TRANSMISSION" in scene.features


def effect_defines() -> dict:
    """EFFECT_RASTER .. EFFECT_PATH_TRACED as #defines, so GLSL and rayvr.Effect agree."""
    return {f"EFFECT_{e.name}": int(e) for e in Effect}


def effects_used(cd) -> set | None:
    """The effects the scene's materials use, or None without a scene (then nothing is skipped)."""
    return None if cd.scene is None else set(cd.scene.effects_used())


def unused_effect_reason(cd, lowest: Effect) -> str | None:
    """The skip reason of a pass that serves effect `lowest` and above, when no material uses one
    of them (None without a scene, or when one is used)."""
    used = effects_used(cd)
    if used is None or any(e >= lowest for e in used):
        return None
    return f"no material uses {lowest.name}" + ("" if lowest == max(Effect) else " or above")
