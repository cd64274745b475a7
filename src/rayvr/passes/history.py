"""A temporal pass's history of the scene's light (SVGF, ReSTIR DI): valid from the frame after it
starts, dropped by `reset()` and by scene edits that change the lighting (materials or lights:
`GpuScene.version` moved and one of them differs). Camera motion and moved instances never drop
it: reprojection follows the head, and the disocclusion test (glsl/reprojection.glsl) rejects
the pixels whose surface changed."""
from __future__ import annotations


def lights_key(scene) -> tuple:
    """What the scene's punctual lights look like (a change invalidates the lighting history)."""
    return tuple((l.type, tuple(l.position), tuple(l.direction), tuple(l.color), l.intensity, l.range,
                  l.inner_cone_angle, l.outer_cone_angle) for l in scene.lights)


class LightingHistory:
    """Whether a pass's history may be read this frame; `frames` counts the frames since compile
    (a pass's histories used in turn: frame parity), `resets` the histories lighting edits dropped."""

    def __init__(self):
        self.frames = 0
        self.valid = False
        self.resets = 0
        self._scene_version = None
        self._scene_key = None

    def restart(self) -> None:
        """A new compile: no history, nothing counted."""
        self.__init__()

    def reset(self) -> None:
        """Forget the history: the next frame starts it again."""
        self.valid = False

    def lighting_edited(self, ctx) -> bool:
        """Whether the materials or lights changed since the last frame (instances alone do not
        count: the disocclusion test handles what they uncover)."""
        gs = ctx.scene
        if gs is None or gs.version == self._scene_version:
            return False
        self._scene_version = gs.version
        key = (gs.scene.materials.version, lights_key(gs.scene))
        edited = key != self._scene_key
        self._scene_key = key
        return edited

    def begin_frame(self, ctx) -> tuple[int, int]:
        """Drop the history on a lighting edit; (previous, current): which of two histories used in
        turn this frame reads and which it writes."""
        if self.lighting_edited(ctx) and self.valid:
            self.resets += 1
            self.reset()
        return self.frames % 2, (self.frames + 1) % 2

    def end_frame(self) -> None:
        """The frame wrote its history: the next one may read it."""
        self.frames += 1
        self.valid = True


class HistoryOwner:
    """A pass's face of its LightingHistory (`self._history`): `reset()`, `history_valid`, `resets`."""

    _history: LightingHistory

    def reset(self) -> None:
        """Forget the history: the next frame starts it again."""
        self._history.reset()

    @property
    def history_valid(self) -> bool:
        """Whether the next frame reads a history (False after a reset or a lighting edit)."""
        return self._history.valid

    @property
    def resets(self) -> int:
        """Histories dropped by lighting edits since compile."""
        return self._history.resets
