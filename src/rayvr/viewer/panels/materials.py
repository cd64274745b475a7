"""Materials section: each material's effect, editable, and a tuned assignment from `rayvr tune`
(its report's tune.json, or a {material: effect} JSON the viewer saved) applied in one go."""
from __future__ import annotations

from ...materials.effect import Effect
from .guard import guarded

_EFFECTS = [e.name.lower() for e in Effect]


def draw(v, state) -> None:
    from imgui_bundle import imgui

    used = v.scene.used_materials()
    if imgui.begin_table("materials", 2, imgui.TableFlags_.row_bg | imgui.TableFlags_.borders_inner_h):
        imgui.table_setup_column("material")
        imgui.table_setup_column("effect")
        imgui.table_headers_row()
        for i, m in enumerate(v.scene.materials):
            imgui.table_next_row()
            imgui.table_next_column()
            if i in used:
                imgui.text(m.name)
            else:
                imgui.text_disabled(f"{m.name} (unused)")
            imgui.table_next_column()
            imgui.set_next_item_width(-1)
            changed, index = imgui.combo(f"##effect_{i}", int(m.effect), _EFFECTS)
            if changed:
                guarded(v, v.set_effect, m.name, Effect(index))
        imgui.end_table()
    imgui.text("tuned assignment (rayvr tune --report DIR: DIR/tune.json)")
    imgui.set_next_item_width(-70)
    _, state.assignment_path = imgui.input_text("##assignment", state.assignment_path)
    imgui.same_line()
    if imgui.button("apply"):
        applied = guarded(v, v.apply_assignment_file, state.assignment_path)
        if applied is not None:
            v.say(f"applied {state.assignment_path}: "
                  + ", ".join(f"{name}={effect.name.lower()}" for name, effect in applied.items()))
