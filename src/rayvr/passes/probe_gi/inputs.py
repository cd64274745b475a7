"""The reading side of the probes: the inputs a shading pass declares to sample them through
glsl/probe_gi.glsl (`#define PROBE_GI 1`), how it binds them, and the graph wiring.

    probe_inputs.add_inputs(r)                       # in reflect(): optional inputs
    on = probe_inputs.bound(cd)                      # in compile(): all of them connected
    probe_inputs.bind(res, data, sampler)            # in execute(), before the dispatch
    probe_inputs.unbind(res)                         # after it (the sampler object leaves the units)
    probe_inputs.wire(graph, "Probes", "Direct")     # graph edges from a ProbeGI pass
"""
from __future__ import annotations

from ...rendergraph.render_pass import Reflection

# reader input pin -> (ProbeGI output, GLSL name in probe_gi.glsl)
# (a probe's active flag travels in its irradiance alpha: ProbeGI's `state` output has no reader)
PINS = {"probeIrradiance": ("irradiance", "probe_irradiance_tex"), "probeDepth": ("depth", "probe_depth_tex"),
        "probeVolumes": ("volumes", "ProbeVolumes")}
TEXTURES = ("probeIrradiance", "probeDepth")


def add_inputs(r: Reflection, unused: str | None = None) -> None:
    """Declare the probe inputs (optional; `unused`: why this configuration does not read them)."""
    for pin, (source, _) in PINS.items():
        p = r.add_input(pin, f"probe {source} (ProbeGI)").optional()
        if pin == "probeVolumes":
            p.buffer(0)
        if unused:
            p.unused(unused)


def bound(cd) -> bool:
    """Whether every probe input is connected and kept in this compile (then PROBE_GI is 1)."""
    return all(pin in cd.input_formats for pin in PINS)


def bind(res, data, sampler) -> None:
    """Bind the probe textures (sampled through `sampler`, linear and clamped) and the volumes block."""
    for pin, (_, glsl) in PINS.items():
        if pin in TEXTURES:
            res.texture(glsl, data[pin], sampler=sampler)
        else:
            res.buffer(glsl, data[pin])


def unbind(res) -> None:
    for pin in TEXTURES:
        res.clear_sampler(PINS[pin][1])


def wire(graph, probes: str, reader: str) -> None:
    """Edges from ProbeGI pass `probes` to the probe inputs of pass `reader`."""
    for pin, (source, _) in PINS.items():
        graph.add_edge(f"{probes}.{source}", f"{reader}.{pin}")
