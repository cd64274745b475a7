"""View section: camera mode and speed, the scene's cameras, reset; mono/stereo, which eye to show,
IPD, field of view; headset presets (per-eye resolution, scaled, and fov)."""
from __future__ import annotations

import dataclasses

from ...xr.presets import PRESETS
from ..camera import MODES
from ..display import MODES as DISPLAY_MODES
from .guard import guarded

_DISPLAY_LABELS = {"side_by_side": "side by side", "left": "left eye", "right": "right eye"}


def draw(v, state) -> None:
    from imgui_bundle import imgui

    imgui.text("camera")
    for mode in MODES:
        imgui.same_line()
        if imgui.radio_button(mode, v.camera.mode == mode):
            v.camera.set_mode(mode)
    changed, speed = imgui.drag_float("speed m/s", v.camera.speed, v.camera.speed * 0.02, 1e-4, 1e4, "%.3g",
                                      imgui.SliderFlags_.logarithmic)
    if changed:
        v.camera.speed = speed
    if imgui.button("reset (R)"):
        v.camera.reset()
    if v.scene.cameras:
        names = [c.name or f"camera {i}" for i, c in enumerate(v.scene.cameras)]
        imgui.same_line()
        imgui.set_next_item_width(140)
        changed, index = imgui.combo("scene camera", v.camera_index, names)
        if changed:
            guarded(v, v.use_scene_camera, index)
    imgui.text_disabled("fly: WASD, E/Q up/down, Shift fast, drag to look\norbit: drag to turn, scroll to zoom")

    imgui.separator()
    changed, stereo = imgui.checkbox("stereo", v.rig.views == 2)
    if changed:
        v.set_rig(dataclasses.replace(v.rig, views=2 if stereo else 1))
    if v.rig.views == 2:
        imgui.same_line()
        imgui.set_next_item_width(120)
        changed, index = imgui.combo("show", DISPLAY_MODES.index(v.display_mode),
                                     [_DISPLAY_LABELS[m] for m in DISPLAY_MODES])
        if changed:
            v.display_mode = DISPLAY_MODES[index]
        changed, ipd_mm = imgui.slider_float("IPD mm", v.rig.ipd * 1e3, 0.0, 200.0, "%.1f")
        if changed:   # poses only: no new renderer
            v.set_rig(dataclasses.replace(v.rig, ipd=ipd_mm * 1e-3))
    changed, fov = imgui.slider_float("vertical fov", v.rig.vertical_fov_deg, 10.0, 150.0, "%.1f deg")
    if changed:
        guarded(v, lambda: v.set_rig(v.rig.with_vertical_fov(fov)))
    imgui.text(f"per view {v.rig.size[0]}x{v.rig.size[1]}")

    imgui.separator()
    keys = [None, *PRESETS]
    names = ["scene camera"] + [p.title for p in PRESETS.values()]
    imgui.set_next_item_width(160)
    changed, index = imgui.combo("headset", keys.index(v.rig.preset) if v.rig.preset in keys else 0, names)
    if changed:
        guarded(v, v.set_preset, keys[index])
    imgui.set_next_item_width(160)
    _, v.preset_scale = imgui.slider_float("resolution scale", v.preset_scale, 0.05, 1.0, "%.2f")
    if imgui.is_item_deactivated_after_edit() and v.rig.preset:   # a new size: a new renderer, once
        guarded(v, v.set_preset, v.rig.preset)
    if v.rig.preset:
        p = PRESETS[v.rig.preset]
        left, right, up, down = p.left_fov.degrees()
        imgui.text_disabled(f"{p.eye_size[0]}x{p.eye_size[1]} per eye at scale 1, fov {right - left:.0f} x "
                            f"{up - down:.0f} deg" + (" (approximate)" if p.approximate else ""))
