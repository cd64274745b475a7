"""The G-buffer's channels, declared once (after Falcor's kGBufferChannels).

Everything else comes from this table: the G-buffer passes' output pins and clear values, the
inputs of the passes that read it (`add_inputs`), the graph wiring (`wire`), and the GLSL
(`glsl_source()`, included as "gbuffer_channels.glsl"): a `GBufferTexel` struct with one field per
channel, the readers' samplers `gbuf_<name>` with `gbuf_fetch_<name>(p)`, the compute writers'
images `gbuf_out_<name>` with `gbuf_store(p, t)`, and the raster writer's outputs with
`gbuf_output(t)`.
"""
from __future__ import annotations

import dataclasses

from ...gpu.shaders import register_include
from ...rendergraph.formats import get_format


@dataclasses.dataclass(frozen=True)
class Channel:
    """One G-buffer target: pin name, texture format, clear value (where nothing is drawn), meaning."""

    name: str
    format: str
    clear: tuple
    meaning: str
    lighting: bool = True    # read by the lighting passes (add_inputs' default set)

    @property
    def is_uint(self) -> bool:
        return get_format(self.format).dtype == "u4"

    @property
    def components(self) -> int:
        return get_format(self.format).components

    @property
    def glsl_type(self) -> str:
        n = self.components
        if self.is_uint:
            return "uint" if n == 1 else f"uvec{n}"
        return "float" if n == 1 else f"vec{n}"


NO_GEOMETRY = 0xFF   # the effect word where nothing was drawn (gbuffer.glsl GBUF_NO_GEOMETRY)

CHANNELS = (
    Channel("posW", "rgba32f", (0.0, 0.0, 0.0, 0.0),
            "render-space position; w = linear eye depth (0: no geometry)"),
    Channel("normW", "rgba32f", (0.0, 0.0, 0.0, 0.0), "shading normal (render space, facing the viewer); "
            "w = 1 + the instance rays leaving on the geometric normal's side may skip (0: none)"),
    Channel("faceNormalW", "rgba16f", (0.0, 0.0, 0.0, 0.0), "geometric normal (render space, facing the viewer); w = 1 where the back face is seen"),
    # float16, not rgba8: 8 bits quantise dark colours coarsely (linear: albedo 0.01 stored as
    # 3/255, 18% off; sRGB-encoded still 3% off), and the path tracer reads the material in float
    Channel("baseColor", "rgba16f", (0.0, 0.0, 0.0, 0.0), "base colour and alpha"),
    Channel("metalRough", "rg16f", (0.0, 0.0), "metallic, roughness"),
    Channel("emissive", "rgba16f", (0.0, 0.0, 0.0, 0.0), "emitted radiance"),
    Channel("effect", "r32ui", (NO_GEOMETRY,), "effect id (low byte) | material index << 8; 0xFF: no geometry"),
    Channel("motion", "rg16f", (0.0, 0.0), "motion vector in pixels (this frame - last frame)", lighting=False),
)
BY_NAME = {c.name: c for c in CHANNELS}
LIGHTING = tuple(c.name for c in CHANNELS if c.lighting)   # what a G-buffer lighting pass reads


def channel(name: str) -> Channel:
    """The channel called `name` (KeyError names the known ones)."""
    try:
        return BY_NAME[name]
    except KeyError:
        raise KeyError(f"no G-buffer channel {name!r}; channels: {', '.join(BY_NAME)}") from None


def add_outputs(reflection) -> None:
    """Declare every channel as an output of a G-buffer pass."""
    for c in CHANNELS:
        reflection.add_output(c.name, c.meaning).format(c.format)


def add_inputs(reflection, names=LIGHTING) -> None:
    """Declare the channels `names` as (sampled) inputs of a pass that reads the G-buffer."""
    for name in names:
        c = channel(name)
        reflection.add_input(c.name, f"G-buffer {c.name}: {c.meaning}").format(c.format)


def wire(graph, gbuffer: str, reader: str, names=LIGHTING) -> None:
    """add_edge('<gbuffer>.<channel>', '<reader>.<channel>') for each channel of `names`."""
    for name in names:
        graph.add_edge(f"{gbuffer}.{name}", f"{reader}.{channel(name).name}")


def read_by(render_pass) -> tuple[str, ...]:
    """The channels a G-buffer reader declares: its `gbuffer_channels()`, else LIGHTING."""
    names = getattr(render_pass, "gbuffer_channels", None)
    return tuple(names()) if names is not None else LIGHTING


def bind_inputs(res, data, names=LIGHTING) -> None:
    """Bind the G-buffer inputs `names` of RenderData `data` to their samplers `gbuf_<name>`."""
    for name in names:
        tex = data.get(name)
        if tex is not None:
            res.texture(f"gbuf_{name}", tex)


def bind_outputs(res, data) -> None:
    """Bind every channel of RenderData `data` to its image `gbuf_out_<name>` (compute writers)."""
    for c in CHANNELS:
        res.image(f"gbuf_out_{c.name}", data[c.name], read=False, write=True)


def _store_value(c: Channel, expr: str) -> str:
    """`expr` (of the channel's GLSL type) widened to the vec4/uvec4 that imageStore takes."""
    n = c.components
    if n == 4:
        return expr
    pad = ", ".join(["0"] * (4 - n)) if c.is_uint else ", ".join(["0.0"] * (4 - n))
    return f"{'uvec4' if c.is_uint else 'vec4'}({expr}, {pad})"


def glsl_source() -> str:
    """The generated "gbuffer_channels.glsl" (see the module docstring)."""
    lines = ["// Generated from rayvr/passes/gbuffer/channels.py CHANNELS: edit the table, not this text.",
             "struct GBufferTexel {"]
    lines += [f"    {c.glsl_type} {c.name};   // {c.meaning}" for c in CHANNELS]
    lines += ["};", "", "#ifdef GBUF_READER"]
    for c in CHANNELS:
        sampler = "usampler2DArray" if c.is_uint else "sampler2DArray"
        swizzle = "xyzw"[:c.components]
        lines += [f"uniform {sampler} gbuf_{c.name};",
                  f"{c.glsl_type} gbuf_fetch_{c.name}(ivec3 p) {{ return texelFetch(gbuf_{c.name}, p, 0).{swizzle}; }}"]
    lines += ["#endif", "", "#if defined(GBUF_WRITER) && !defined(GBUF_RASTER_WRITER)"]
    for c in CHANNELS:
        image = "uimage2DArray" if c.is_uint else "image2DArray"
        lines.append(f"layout({get_format(c.format).glsl}) writeonly uniform {image} gbuf_out_{c.name};")
    lines.append("void gbuf_store(ivec3 p, GBufferTexel t) {")
    lines += [f"    imageStore(gbuf_out_{c.name}, p, {_store_value(c, 't.' + c.name)});" for c in CHANNELS]
    lines += ["}", "#endif", "", "#ifdef GBUF_RASTER_WRITER"]
    lines += [f"layout(location = {i}) out {c.glsl_type} gbuf_frag_{c.name};" for i, c in enumerate(CHANNELS)]
    lines.append("void gbuf_output(GBufferTexel t) {")
    lines += [f"    gbuf_frag_{c.name} = t.{c.name};" for c in CHANNELS]
    lines += ["}", "#endif", ""]
    return "\n".join(lines)


register_include("gbuffer_channels.glsl", glsl_source)
