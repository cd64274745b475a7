"""`rayvr view` / `rv.view()`: a live window on a scene and render graph, with Dear ImGui panels.

    import rayvr as rv
    scene = rv.scenes.cornell_box()
    rv.view(scene, rv.graphs.hybrid())     # fly around; edit effects and pass properties; screenshot

Modules: `window` (glfw, the GL 4.5 context the renderer shares), `offscreen` (the same loop
without a display), `camera` (fly and orbit), `view_rig` (views, fov, IPD, headset presets),
`input` and `script` (events, scripted input), `ui` and `panels` (ImGui), `display` (the output
texture array on screen), `screenshot`, `assignment` (effects as JSON), `app` (the frame loop).
glfw and imgui-bundle (the `viewer` extra) are imported only when a viewer starts.
"""
from __future__ import annotations


def view(scene=None, graph=None, **kwargs):
    """Open a window on `scene` (a Scene, built-in name or glTF path) rendered by `graph` (a
    RenderGraph, 'hybrid', 'path_traced' or a saved .json/.py) until it is closed. Keywords:
    views (1, 2), size (per view), frames, screenshot, script, on_frame(viewer), preset, show_ui,
    window_size; see `rayvr.viewer.app.view`. Returns the frames drawn."""
    from .app import view as _view

    return _view(scene, graph, **kwargs)


def __getattr__(name: str):
    if name == "Viewer":
        from .app import Viewer

        return Viewer
    raise AttributeError(f"module 'rayvr.viewer' has no attribute '{name}'")


__all__ = ["view", "Viewer"]
