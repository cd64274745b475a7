"""Running a panel's action so that a mistake shows in the status line instead of stopping the viewer."""
from __future__ import annotations

from ...errors import RayvrError


def guarded(viewer, action, *args, done: str | None = None):
    """Run `action(*args)`; a RayvrError goes to the status line. Returns the result or None;
    `done` ('wrote {result}') is shown on success."""
    try:
        result = action(*args)
    except RayvrError as exc:
        viewer.say(" ".join(str(exc).split()), error=True)
        return None
    if done:
        viewer.say(done.format(result=result))
    return result
