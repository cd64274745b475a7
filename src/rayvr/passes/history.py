"""What the temporal passes (SVGF, TAA, ReSTIR DI) share: when a history must be dropped, and when
a frame is still.

A history survives camera motion (reprojection follows the head) and moved instances (the
disocclusion test of glsl/reprojection.glsl or a colour clamp rejects the pixels whose surface
changed), but not an edit of the lighting: a moved or recoloured light, a changed material or
effect makes every stored sample wrong at once.

A frame is *still* when its views and everything the GPU scene uploaded are those of the frame
before (the Renderer's `sample_index` > 0). Then a pixel whose motion vector is zero sees the same
surface under the same light as last frame, so its history may grow without bound: the temporal
mean converges to the configuration's own converged image instead of a moving average's noise.
"""
from __future__ import annotations

# The history length a still pixel may reach: float32 running means stay exact far beyond it.
STILL_MAX_HISTORY = float(1 << 20)


def lights_key(scene) -> tuple:
    """What the scene's punctual lights look like (a change invalidates the lighting history)."""
    return tuple((l.type, tuple(l.position), tuple(l.direction), tuple(l.color), l.intensity, l.range,
                  l.inner_cone_angle, l.outer_cone_angle) for l in scene.lights)


def still_frame(ctx) -> bool:
    """Whether this frame's views and uploaded scene are last frame's (module docstring)."""
    return bool(getattr(ctx, "sample_index", None))


class LightingWatch:
    """Tells a temporal pass when the materials, lights or environment changed since the last
    frame it saw (instances alone do not count)."""

    def __init__(self):
        self.forget()

    def forget(self) -> None:
        """Start over (at compile): the next frame counts as an edit."""
        self._version = None
        self._key = None

    def edited(self, ctx) -> bool:
        """Whether the lighting changed since the last call (True on the first frame a scene is seen)."""
        gs = ctx.scene
        if gs is None or gs.version == self._version:
            return False
        self._version = gs.version
        key = (gs.scene.materials.version, lights_key(gs.scene), id(gs.scene.environment))
        edited = key != self._key
        self._key = key
        return edited


class LightingHistory:
    """Whether a pass's history may be read this frame; `frames` counts the frames since compile
    (a pass's histories used in turn: frame parity), `resets` the histories lighting edits dropped."""

    def __init__(self):
        self.frames = 0
        self.valid = False
        self.resets = 0
        self._watch = LightingWatch()

    def restart(self) -> None:
        """A new compile: no history, nothing counted."""
        self.__init__()

    def reset(self) -> None:
        """Forget the history: the next frame starts it again."""
        self.valid = False

    def begin_frame(self, ctx) -> tuple[int, int]:
        """Drop the history on a lighting edit; (previous, current): which of two histories used in
        turn this frame reads and which it writes."""
        if self._watch.edited(ctx) and self.valid:
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
