"""Graph section: a ready-made graph's options (their real-time values), the passes in execution
order with their GPU ms, what was pruned and why, and memory (allocated with lifetime aliasing,
and without), from the compile report."""
from __future__ import annotations

from ...graph_options import NONE
from ...graphs import BUILDERS
from ...rendergraph.report import human_bytes
from .guard import guarded


def draw(v, state) -> None:
    from imgui_bundle import imgui

    if v.graph_builder is not None:
        for option in BUILDERS[v.graph_builder].options:
            values = [NONE, *option.realtime_values()]   # a live view: no offline denoiser
            current = v.graph_options.get(option.name, BUILDERS[v.graph_builder].defaults().get(option.name)) or NONE
            imgui.set_next_item_width(140)
            changed, index = imgui.combo(option.name, values.index(current) if current in values else 0, values)
            if changed:
                guarded(v, v.set_graph_option, option.name, values[index])
    report = v.renderer.report()
    profile = v.profile
    w, h = report.size
    imgui.text(f"'{report.graph}': {w}x{h} x {report.views} view(s)")
    imgui.text("runs, in order:")
    for i, name in enumerate(report.order):
        stats = profile.passes.get(name)
        imgui.bullet_text(f"{i + 1}. {name} ({type(v.renderer.compiled.passes[name]).__name__})"
                          + (f"  {stats.last_ms:.2f} ms" if stats else ""))
    if report.pruned:
        imgui.text("pruned:")
        imgui.push_text_wrap_pos(0.0)
        for name, why in report.pruned.items():
            imgui.bullet_text(f"{name}: {why}")
        imgui.pop_text_wrap_pos()
    for ref, why in report.unavailable.items():
        imgui.text_disabled(f"{ref} not produced: {why}")
    imgui.text(f"memory: {human_bytes(report.total_bytes)} allocated, "
               f"{human_bytes(report.unaliased_bytes)} without aliasing")
    if imgui.tree_node("resources"):
        if imgui.begin_table("resources", 3, imgui.TableFlags_.row_bg | imgui.TableFlags_.borders_inner_h):
            imgui.table_setup_column("resource")
            imgui.table_setup_column("shape")
            imgui.table_setup_column("bytes")
            imgui.table_headers_row()
            for r in report.resources:
                imgui.table_next_row()
                imgui.table_next_column()
                imgui.text(r.name)
                imgui.table_next_column()
                imgui.text(f"{r.format} {r.size[0]}x{r.size[1]}x{r.layers}" if r.kind == "texture" else "buffer")
                imgui.table_next_column()
                imgui.text(human_bytes(r.bytes) + (" (shared)" if r.aliased_with else ""))
            imgui.end_table()
        imgui.tree_pop()
    if imgui.tree_node("compile report"):
        imgui.push_text_wrap_pos(0.0)
        imgui.text_unformatted(str(report))
        imgui.pop_text_wrap_pos()
        imgui.tree_pop()
