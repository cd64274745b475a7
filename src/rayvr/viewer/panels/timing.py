"""Timing section: per-pass GPU ms of the last frames as live plots, with the 90 Hz budget line."""
from __future__ import annotations

import numpy as np

from ...tune.budget import FRAME_BUDGET_MS as BUDGET_MS


def draw(v, state) -> None:
    from imgui_bundle import imgui, implot

    profile = v.profile
    imgui.text_disabled(f"GPU ms per pass ({profile.method}); budget {BUDGET_MS} ms (90 Hz)")
    if implot.begin_plot("##gpu_ms", imgui.ImVec2(-1, 170), implot.Flags_.no_menus | implot.Flags_.no_box_select):
        implot.setup_axes("frame", "ms", implot.AxisFlags_.no_tick_labels | implot.AxisFlags_.auto_fit)
        peak = max((max(t) for t in v.history.values() if t), default=0.0)
        implot.setup_axis_limits(implot.ImAxis_.y1, 0.0, 1.1 * max(peak, 1.2 * BUDGET_MS), implot.Cond_.always)
        implot.setup_legend(implot.Location_.north, implot.LegendFlags_.outside | implot.LegendFlags_.horizontal)
        for name, times in v.history.items():
            if len(times) > 1:
                implot.plot_line(name, np.fromiter(times, np.float64, len(times)))
        spec = implot.Spec()
        spec.flags = implot.InfLinesFlags_.horizontal
        implot.plot_inf_lines(f"budget {BUDGET_MS} ms", np.array([BUDGET_MS]), spec)
        implot.end_plot()
    if imgui.begin_table("passes_ms", 3, imgui.TableFlags_.row_bg | imgui.TableFlags_.borders_inner_h):
        imgui.table_setup_column("pass")
        imgui.table_setup_column("last ms")
        imgui.table_setup_column("mean ms")
        imgui.table_headers_row()
        for name, stats in profile.passes.items():
            imgui.table_next_row()
            imgui.table_next_column()
            imgui.text(name)
            imgui.table_next_column()
            imgui.text(f"{stats.last_ms:.3f}")
            imgui.table_next_column()
            imgui.text(f"{stats.mean_ms:.3f}")
        imgui.table_next_row()
        imgui.table_next_column()
        imgui.text("total")
        imgui.table_next_column()
        total = v.history.get("total")
        imgui.text(f"{total[-1]:.3f}" if total else "-")
        imgui.table_next_column()
        over = profile.total_ms > BUDGET_MS
        color = imgui.ImVec4(1.0, 0.45, 0.4, 1.0) if over else imgui.ImVec4(0.6, 0.9, 0.6, 1.0)
        imgui.text_colored(color, f"{profile.total_ms:.3f}")
        imgui.end_table()
