"""The viewer's ImGui panels: one window of collapsing sections, one module per section.

Each section is `draw(viewer, state)`; `state` (PanelState) keeps what only the UI needs between
frames (text being typed, edits not yet committed). An action that fails (a bad path, a property
out of range) shows its RayvrError message in the status line instead of stopping the viewer.
"""
from __future__ import annotations

import dataclasses

from . import accumulation, graph, materials, output, properties, timing, view

WINDOW_POS = (8.0, 8.0)
WINDOW_WIDTH = 360.0
# (title, module, open at start)
SECTIONS = [("View", view, False), ("Timing", timing, True), ("Graph", graph, False),
            ("Materials", materials, False), ("Passes", properties, False),
            ("Accumulation", accumulation, False), ("Output", output, False)]


@dataclasses.dataclass
class PanelState:
    """UI-only state: text fields and property edits in progress."""

    assignment_path: str = "out/tune/tune.json"
    screenshot_path: str = "out/view.png"
    hdr_path: str = "out/view.exr"
    graph_path: str = "out/graph.py"
    effects_path: str = "out/effects.json"
    camera_path: str = "out/camera_path.json"
    edits: dict = dataclasses.field(default_factory=dict)


class Panels:
    """Builds the viewer's window each frame."""

    def __init__(self, viewer):
        self.viewer = viewer
        self.state = PanelState()

    def draw(self) -> None:
        from imgui_bundle import imgui

        v = self.viewer
        win_w, win_h = v.surface.window_size
        imgui.set_next_window_pos(imgui.ImVec2(*WINDOW_POS), imgui.Cond_.first_use_ever)
        imgui.set_next_window_size(imgui.ImVec2(max(160.0, min(WINDOW_WIDTH, win_w - 16.0)),
                                                max(120.0, min(win_h - 16.0, 640.0))), imgui.Cond_.first_use_ever)
        expanded, _ = imgui.begin("rayvr")
        if expanded:
            self._summary(imgui)
            for title, module, opened in SECTIONS:
                flags = imgui.TreeNodeFlags_.default_open if opened else 0
                if imgui.collapsing_header(title, flags):
                    imgui.push_id(title)
                    module.draw(v, self.state)
                    imgui.pop_id()
        imgui.end()

    def _summary(self, imgui) -> None:
        v = self.viewer
        r = v.renderer
        frames, seconds = v.accumulated()
        total = v.history.get("total")
        gpu_ms = f"{total[-1]:.2f} ms GPU" if total else "-"
        imgui.text(f"{v.scene.name}: {v.rig.views} x {v.rig.size[0]}x{v.rig.size[1]}  {gpu_ms}")
        imgui.text(f"frame {v.frame_index}  accumulated {frames}  {seconds:.1f} s"
                   + ("  (converged)" if v.settled() else ""))
        imgui.text_disabled(f"render {v.phase_ms['render']:.1f}  display {v.phase_ms['display']:.1f}  "
                            f"UI {v.phase_ms['ui']:.1f} ms (CPU); {r.compiles} compile(s)")
        if v.status:
            color = imgui.ImVec4(1.0, 0.45, 0.4, 1.0) if v.status_is_error else imgui.ImVec4(0.6, 0.9, 0.6, 1.0)
            imgui.push_text_wrap_pos(0.0)
            imgui.text_colored(color, v.status)
            imgui.pop_text_wrap_pos()
