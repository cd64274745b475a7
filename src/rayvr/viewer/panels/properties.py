"""Passes section: every pass's properties from `get_properties()`, edited by their type, so a
pass added later (a denoiser, say) gets its controls without code here: booleans as checkboxes,
numbers as drag fields, lists of 2-4 numbers as vectors, strings as a combo when the pass class
names the choices (`CHOICES = {"operator": ("aces", "reinhard", "linear")}`) and as text otherwise.
An edit commits when the widget is let go (or Enter is pressed): `graph.update_pass`, then the
graph recompiles at the next frame; the pass checks the value and a refusal shows in the status line.
"""
from __future__ import annotations

from .guard import guarded


def _commit(v, state, pass_name, key, value) -> None:
    state.edits.pop((pass_name, key), None)
    guarded(v, v.set_pass_property, pass_name, key, value, done=f"{pass_name}.{key} = {value!r}")


def _number(v, state, pass_name, key, value, imgui) -> None:
    shown = state.edits.get((pass_name, key), value)
    label = f"{key}##{pass_name}"
    if isinstance(value, int):
        changed, shown = imgui.drag_int(label, int(shown), 0.2)
    else:
        changed, shown = imgui.drag_float(label, float(shown), max(abs(float(shown)) * 0.01, 0.01), 0.0, 0.0, "%.4g")
    if changed:
        state.edits[(pass_name, key)] = shown
    if imgui.is_item_deactivated_after_edit():
        _commit(v, state, pass_name, key, state.edits.get((pass_name, key), shown))


def _vector(v, state, pass_name, key, value, imgui) -> None:
    shown = list(state.edits.get((pass_name, key), value))
    draw = {2: imgui.drag_float2, 3: imgui.drag_float3, 4: imgui.drag_float4}[len(value)]
    changed, shown = draw(f"{key}##{pass_name}", [float(x) for x in shown], 0.01)
    if changed:
        state.edits[(pass_name, key)] = list(shown)
    if imgui.is_item_deactivated_after_edit():
        _commit(v, state, pass_name, key, [float(x) for x in state.edits.get((pass_name, key), shown)])


def _string(v, state, render_pass, pass_name, key, value, imgui) -> None:
    choices = tuple(getattr(type(render_pass), "CHOICES", {}).get(key, ()))
    label = f"{key}##{pass_name}"
    if choices:
        current = choices.index(value) if value in choices else 0
        changed, index = imgui.combo(label, current, list(choices))
        if changed:
            _commit(v, state, pass_name, key, choices[index])
        return
    shown = state.edits.get((pass_name, key), value)
    entered, shown = imgui.input_text(label, str(shown), imgui.InputTextFlags_.enter_returns_true)
    if shown != value:
        state.edits[(pass_name, key)] = shown
    else:
        state.edits.pop((pass_name, key), None)
    if entered or imgui.is_item_deactivated_after_edit():
        if shown != value:
            _commit(v, state, pass_name, key, shown)
        else:
            state.edits.pop((pass_name, key), None)


def draw_pass(v, state, pass_name, render_pass) -> None:
    """The editors of one pass's properties."""
    from imgui_bundle import imgui

    props = render_pass.get_properties()
    if not props:
        imgui.text_disabled("no properties")
    for key, value in props.items():
        if isinstance(value, bool):
            changed, on = imgui.checkbox(f"{key}##{pass_name}", value)
            if changed:
                _commit(v, state, pass_name, key, on)
        elif isinstance(value, (int, float)):
            _number(v, state, pass_name, key, value, imgui)
        elif (isinstance(value, (list, tuple)) and 2 <= len(value) <= 4
              and all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in value)):
            _vector(v, state, pass_name, key, value, imgui)
        elif isinstance(value, str):
            _string(v, state, render_pass, pass_name, key, value, imgui)
        else:
            imgui.text_disabled(f"{key}: {value!r}")


def draw(v, state) -> None:
    from imgui_bundle import imgui

    report = v.renderer.report()
    for pass_name, render_pass in v.graph.passes.items():
        why = report.pruned.get(pass_name)
        title = f"{pass_name} ({type(render_pass).__name__})" + ("  [pruned]" if why else "")
        if imgui.tree_node(f"{title}###{pass_name}"):
            if why:
                imgui.push_text_wrap_pos(0.0)
                imgui.text_disabled(f"pruned: {why}")
                imgui.pop_text_wrap_pos()
            draw_pass(v, state, pass_name, render_pass)
            imgui.tree_pop()
