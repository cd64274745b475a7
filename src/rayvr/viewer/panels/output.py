"""Output section: screenshot (PNG of the window with its UI; EXR of the HDR output), the current
graph (.py or .json), the materials' effects (JSON), a camera path recorded for `rayvr render
--camera-path`; the error overlay's opacity when a hook provides one (Viewer.error_overlay)."""
from __future__ import annotations

from .guard import guarded


def _path_row(imgui, label: str, path: str) -> tuple[bool, str]:
    imgui.set_next_item_width(-110)
    _, path = imgui.input_text(f"##{label}", path)
    imgui.same_line()
    return imgui.button(label), path


def draw(v, state) -> None:
    from imgui_bundle import imgui

    clicked, state.screenshot_path = _path_row(imgui, "screenshot", state.screenshot_path)
    if clicked:
        v.request_screenshot(state.screenshot_path, strict=False)   # after this frame's UI is drawn
    clicked, state.hdr_path = _path_row(imgui, "HDR (EXR)", state.hdr_path)
    if clicked:
        path = state.hdr_path if state.hdr_path.lower().endswith(".exr") else state.hdr_path + ".exr"
        v.request_screenshot(path, strict=False)
    clicked, state.graph_path = _path_row(imgui, "save graph", state.graph_path)
    if clicked:
        guarded(v, v.save_graph, state.graph_path, done="wrote {result}")
    clicked, state.effects_path = _path_row(imgui, "save effects", state.effects_path)
    if clicked:
        guarded(v, v.save_effects, state.effects_path, done="wrote {result}")
    if v.recording is None:
        if imgui.button("record camera path"):
            v.start_recording()
    else:
        imgui.text(f"recording: {len(v.recording)} poses")
    clicked, state.camera_path = _path_row(imgui, "save path", state.camera_path)
    if clicked:
        if guarded(v, v.save_camera_path, state.camera_path, done="wrote {result}") is not None:
            v.recording = None
    if v.error_overlay is not None:
        _, v.overlay_alpha = imgui.slider_float("error overlay", v.overlay_alpha, 0.0, 1.0, "%.2f")
